"""Cost of the issue-15 terms as a ratio to the water pass (fluid rates: pressure, viscous stress,
AV, XSPH), on the default dam break at a/80 (12,800 particles) after 100 steps (a disordered
state), 1 thread, CPU time (process_time, less sensitive to other users of a shared machine
than wall time; the 1-minute load is printed with the table).

    python benchmarks/bench_density_diffusion.py [--repeat 30]

Rows: the midpoint continuity with and without the fused density diffusion (numerics.leapfrog =
"midpoint_density"), the density diffusion as a rate term with the seed's leap-frog
(DensityDiffusionRate), the hydrostatic reference density and the wall repulsion (local terms).
"""

from __future__ import annotations

import argparse
import os
import time

import numba

from solver.simulation import Simulation
from verification.common import scene_from_file

SPACING = 0.05715 / 80
CASES = {
    "defaults": {},
    "midpoint, no diffusion": {"numerics.density_diffusion": "none"},
    "seed leap-frog + Fourtakas": {"numerics.leapfrog": "seed"},
}


def cpu_per_call(term, ctx, repeat):
    term.run(ctx)  # compiled already; one warm call
    t0 = time.process_time()
    for _ in range(repeat):
        term.run(ctx)
    return (time.process_time() - t0) / repeat


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    args = parser.parse_args(argv)
    numba.set_num_threads(1)
    rows = []
    for label, over in CASES.items():
        sim = Simulation(scene_from_file("dam_break_2d.toml", **{"scene.spacing": SPACING, **over}))
        for _ in range(100):
            sim.step()
        sim.refresh(tuple(n for n in sim.plan.fields if sim.plan.fields[n].mirror.name != "NONE"))
        terms = {t.name: t for t in sim.plan.terms}
        base = cpu_per_call(terms["fluid rates"], sim.ctx, args.repeat)
        for name in (
            "midpoint continuity",
            "density diffusion",
            "hydrostatic reference density",
            "wall repulsion",
        ):
            if name in terms:
                rows.append((label, name, cpu_per_call(terms[name], sim.ctx, args.repeat) / base, base))
    print(
        f"| scene options | term | CPU time / water pass | water pass (ms) |  (load {os.getloadavg()[0]:.1f})"
    )
    print("|---|---|---|---|")
    for label, name, ratio, base in rows:
        print(f"| {label} | {name} | {ratio:.3f} | {1e3 * base:.2f} |")


if __name__ == "__main__":
    main()
