"""Are a new build's soil results those of an old build, within round-off? Measured against the
old build's own sensitivity to round-off.

    python benchmarks/studies/soil_roundoff.py OLD_CHECKOUT NEW_CHECKOUT --case bench --steps 200
    python benchmarks/studies/soil_roundoff.py OLD_CHECKOUT NEW_CHECKOUT --case collapse --resolution 20
    python benchmarks/studies/soil_roundoff.py OLD NEW --case saturated --formulation seed --steps 300

A speed-up that sums in another order, or rounds one product differently, changes every result by
round-off, and a particle flow amplifies round-off (a disordered or plastic flow is chaotic), so
"unchanged within round-off" needs a scale. This tool takes it from the old build itself: it runs
the old build once as is and twice with every initial position moved by one unit in the last
place (np.nextafter towards +inf and towards -inf; a perturbation no build can be more exact
than), then the new build as is, each in its own process, one Numba thread. The bound is the
larger of the two perturbed runs' differences from the plain old run, per quantity; the new
build is "within round-off" when its difference from the old run is at most that bound times
--factor (default 10: two realisations of round-off noise in a chaotic flow differ by a
factor of a few; the factor is printed with the verdict, and the raw figures with it).

Cases: "bench" is the 25k disordered column of benchmarks/bench_soil_step.py (random velocities,
--steps steps); "collapse" is verification/column_collapse.run at --resolution (the 5 mm
collapse to 1 s by default); "saturated" is a small saturated sand bed under a pond, disordered
as benchmarks/bench_seepage_step.py's (0.1 m x 0.04 m, --soil soil particles and as many pore-water
particles, 0.01 m of free water; --formulation mixture or seed; --steps steps): the water-soil
coupling (solver/physics/seepage.py) with both phases. Compared by particle id: positions (max
|dx|, in m and in dx), the Cauchy stress sigma = s - p I of the soil (max |d sigma| over max
|sigma|) and the density; the saturated case also the velocity (max |dv| over max |v|) and the
pore pressure field (p~ at soil, p^ at water; max |d p| over max |p|).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = """
import sys
root, case, steps, resolution, nudge, out, formulation, n_soil = sys.argv[1:9]
sys.path[:0] = [root, root + "/benchmarks"]
import numpy as np
import solver.simulation as simulation
from solver.materials import Phase

direction = np.inf if nudge == "+" else -np.inf
if nudge != "0" and case == "collapse":  # every initial position one ulp up or down
    created = simulation.create_particles

    def create_nudged(*args, **kwargs):
        ps = created(*args, **kwargs)
        ps["x"][:] = np.nextafter(ps["x"], direction)
        return ps

    simulation.create_particles = create_nudged

if case in ("bench", "saturated"):
    if case == "bench":
        from bench_soil_step import soil_collapse
        sim = soil_collapse(25_000)
    else:  # the scene is written here, so that an old checkout runs the same one
        from dam_break_setup import disordered
        from verification import seepage_common as sc
        width, depth, pond = 0.1, 0.04, 0.01
        dx = (width * depth / int(n_soil)) ** 0.5
        blocks = [
            {"name": "bed", "material": "sand", "shape": "rectangle", "min": [0.0, 0.0],
             "max": [width, depth], "geostatic": True, "saturated": True},
            {"name": "pond", "material": "water", "shape": "rectangle", "min": [0.0, depth],
             "max": [width, depth + pond], "hydrostatic": True},
        ]  # fmt: skip
        mats = {"sand": sc.sand(0.4, permeability=1e-3), "water": sc.WATER}
        scene = sc.scene("saturated_roundoff", dx, 1.0, [width, depth + 2 * pond], mats, blocks, formulation)
        sim = disordered(simulation.Simulation(scene))
    if nudge != "0":  # the benchmark disorders the lattice after creation: nudge its result
        n = sim.particles.n_owned
        sim.particles["x"][:n] = np.nextafter(sim.particles["x"][:n], direction)
        sim.rebuild()
    for _ in range(int(steps)):
        sim.step()
else:
    import verification.column_collapse as cc
    kept = {}
    original = cc.timed_run

    def keep(*args, **kwargs):
        result = original(*args, **kwargs)
        kept["sim"] = result[0]
        return result

    cc.timed_run = keep
    cc.run(int(resolution))
    sim = kept["sim"]
ps = sim.current_state()
n = ps.n_owned
order = np.argsort(ps["id"][:n])
soil = sim.plan.materials.phase[ps["material"][:n][order]] == Phase.SOIL
sigma = ps["stress_dev"][:n].copy()
sigma[:, :3] -= ps["mean_stress"][:n, None]
extra = {}
if case == "saturated":
    extra["v"] = ps["v"][:n][order]
    if formulation == "mixture":
        extra["pore"] = ps["pore_pressure"][:n][order]
np.savez(out, x=ps["x"][:n][order], sigma=sigma[order][soil], rho=ps["rho"][:n][order],
         steps=sim.step_count, dx=sim.scene.scene.spacing, **extra)
"""


def run(root, case, steps, resolution, nudge, folder, formulation="mixture", n_soil=2500):
    out = os.path.join(folder, f"{len(os.listdir(folder))}.npz")
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    args = [sys.executable, "-c", CHILD, os.path.abspath(root), case, str(steps), str(resolution), nudge, out]
    args += [formulation, str(n_soil)]
    done = subprocess.run(args, env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{root} ({case}, nudge {nudge}): {done.stderr.strip().splitlines()[-1]}")
    return dict(np.load(out))


def differences(a, b):
    """Largest differences of b from a: positions (m), stress (over max |sigma| of a), density (relative),
    and where saved velocity (over max |v|) and pore pressure (over max |p|)."""
    d = {
        "x (m)": float(np.abs(b["x"] - a["x"]).max()),
        "sigma / max|sigma|": float(np.abs(b["sigma"] - a["sigma"]).max() / np.abs(a["sigma"]).max()),
        "rho (relative)": float(np.abs(b["rho"] / a["rho"] - 1.0).max()),
    }
    for key, name in (("v", "v / max|v|"), ("pore", "pore p / max|p|")):
        if key in a:
            d[name] = float(np.abs(b[key] - a[key]).max() / np.abs(a[key]).max())
    return d


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--case", choices=("bench", "collapse", "saturated"), default="bench")
    ap.add_argument("--steps", type=int, default=200, help="bench: steps to take")
    ap.add_argument("--resolution", type=int, default=20, help="collapse: H0 / dx")
    ap.add_argument(
        "--formulation", choices=("mixture", "seed"), default="mixture", help="saturated: seepage"
    )
    ap.add_argument(
        "--soil",
        type=int,
        default=2500,
        help="saturated: soil particles (2000 blows up on main too: jitter within dx/2 of x_max)",
    )
    ap.add_argument("--factor", type=float, default=10.0, help="new-old may be this many times the bound")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        go = lambda root, nudge: run(  # noqa: E731
            root, args.case, args.steps, args.resolution, nudge, folder, args.formulation, args.soil
        )
        old, up, down, new = go(args.old, "0"), go(args.old, "+"), go(args.old, "-"), go(args.new, "0")
    if len(new["x"]) != len(old["x"]):
        raise SystemExit(f"different particle counts: old {len(old['x'])}, new {len(new['x'])}")
    steps = f"old {int(old['steps'])} steps, new {int(new['steps'])} steps"
    form = f" ({args.formulation})" if args.case == "saturated" else ""
    print(f"{args.case}{form}: {len(old['x'])} particles, {steps}")
    d_up, d_down, d_new = differences(old, up), differences(old, down), differences(old, new)
    within = True
    for key in d_new:
        bound = max(d_up[key], d_down[key])
        ok = d_new[key] <= args.factor * bound
        within &= ok
        print(
            f"  {key:20s} new-old {d_new[key]:.3e}   old+ulp {d_up[key]:.3e}   old-ulp {d_down[key]:.3e}"
            f"   ratio {d_new[key] / bound if bound > 0 else float('inf'):.2f}  {'ok' if ok else 'OUTSIDE'}"
        )
    print(f"  max |dx| / dx: new-old {d_new['x (m)'] / float(old['dx']):.3e}")
    verdict = "within" if within else "NOT within"
    print(f"verdict: {verdict} round-off (new-old <= {args.factor:g} x the 1-ulp bound)")
    return 0 if within else 1


if __name__ == "__main__":
    sys.exit(main())
