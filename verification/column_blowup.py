"""Reproduction of issue 14's blow-up: a column of the collapse material (scenes/column_collapse_2d.toml:
Drucker-Prager, artificial stress 0.5, no-slip floor) 0.1 m wide and 0.2 m tall in a 1.0 m long tank
(the stability matrix's cell column_dp_a2, verification/stability_matrix.py).

    python -m verification.column_blowup 0.004 [--eps 0.5] [--end 1.0]

Prints the outcome (completed, or the BlowUpError with time, step and place), the lowest density
reached (rho / rho0, sampled every 50 steps) and the wall time. Before the crack-density fix
(solver/physics/soil_stress.py, soil_stress_state) it blew up at 4 mm (t = 0.817 s) and 2.5 mm
(t = 0.374 s), with artificial_stress 0.5 and 0 alike, after a detached grain's density had
fallen below zero.
"""

from __future__ import annotations

import argparse
import time

from solver.errors import BlowUpError
from solver.scene import parse_scene
from solver.simulation import Simulation
from verification.stability_matrix import COLLAPSE, column_raw


def column_scene(dx, end_time=1.0, artificial_stress=0.5):
    raw = column_raw(2, dx, end_time=end_time)
    raw["numerics"]["artificial_stress"] = float(artificial_stress)
    return parse_scene(raw, COLLAPSE)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("spacing", type=float)
    ap.add_argument("--eps", type=float, default=0.5, help="numerics.artificial_stress")
    ap.add_argument("--end", type=float, default=1.0)
    a = ap.parse_args(argv)
    sim = Simulation(column_scene(a.spacing, a.end, a.eps))
    ps = sim.particles
    rho0 = float(sim.plan.materials.rho0[0])
    lowest = [1.0]

    def watch(s):
        if s.step_count % 50 == 0:
            lowest[0] = min(lowest[0], float(ps["rho"][: ps.n_owned].min()) / rho0)

    start = time.perf_counter()
    try:
        sim.advance_to(a.end, on_step=watch)
        outcome = "completed"
    except BlowUpError as e:
        outcome = f"BLOW-UP: {e}"
    print(
        f"dx = {a.spacing} eps = {a.eps}: {outcome}; steps {sim.step_count}, t = {sim.t:.4f} s, "
        f"{ps.n_owned} particles, lowest rho/rho0 {lowest[0]:.3g}, wall {time.perf_counter() - start:.1f} s"
    )


if __name__ == "__main__":
    main()
