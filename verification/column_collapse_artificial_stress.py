"""Column collapse (Bui et al. 2008) with the tensile-instability remedy on and off.

Issue 3 asks for "a remedy for tensile instability ... selectable, and measured by what it
changes". The remedy is Gray, Monaghan & Swift (2001) artificial stress
(numerics.artificial_stress = eps; Bui et al. 2008 use 0.5 with n = 2.55). This runs the
collapse scene twice at one spacing, eps = 0.5 and eps = 0, and reports what changes:
runout, height at the wall, free-surface and failure-line RMS vs the experiment, the
largest tensile principal stress seen (tension positive, over the run), and particle
clumping (smallest pair distance / dx and the fraction of particles with a neighbour
closer than dx/2, over the run and at the end). Also saves the initial and final positions
(npz) for the failure-line threshold analysis (verification/column_collapse.py).

  NUMBA_NUM_THREADS=1 python -m verification.column_collapse_artificial_stress [--resolution 25]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from . import column_collapse as cc


def principal_tension(ps, n):
    """Largest principal total stress per particle (tension positive): in-plane and zz."""
    p = ps["mean_stress"][:n]
    s = ps["stress_dev"][:n]
    sxx, syy, szz, sxy = s[:, 0] - p, s[:, 1] - p, s[:, 2] - p, s[:, 3]
    inplane = 0.5 * (sxx + syy) + np.sqrt((0.5 * (sxx - syy)) ** 2 + sxy**2)
    return np.maximum(inplane, szz)


def clumping(x, dx):
    """(min pair distance / dx, fraction of particles with a neighbour closer than dx/2)."""
    d2 = np.sum((x[:, None, :] - x[None, :, :]) ** 2, axis=-1)
    np.fill_diagonal(d2, np.inf)
    nearest = np.sqrt(d2.min(axis=1))
    return float(nearest.min() / dx), float(np.mean(nearest < 0.5 * dx))


def run_case(resolution, eps, cohesion=None):
    from solver.initial_state import create_particles
    from solver.plan import build_plan
    from solver.simulation import Simulation

    dx = cc.spacing(resolution)
    over = {"numerics": {"artificial_stress": float(eps)}}
    if cohesion is not None:  # a cohesive variant: tension is admissible there, so the remedy can act
        over["materials"] = {"bars": {"cohesion": float(cohesion)}}
    scene = cc.scene_at(dx, overrides=over)
    start = create_particles(scene, build_plan(scene))
    x0 = start["x"][: start.n_owned][np.argsort(start["id"][: start.n_owned])].copy()
    sim = Simulation(scene)
    sim.step()
    t0 = time.perf_counter()
    tension, min_sep, close = [], [], []
    for t in np.linspace(0.0, scene.scene.end_time, 41)[1:]:
        sim.advance_to(t)
        sim.current_state()
        ps = sim.particles
        n = ps.n_owned
        tension.append(float(principal_tension(ps, n).max()))
        a, b = clumping(ps["x"][:n], dx)
        min_sep.append(a)
        close.append(b)
    wall = time.perf_counter() - t0
    ps = sim.particles
    n = ps.n_owned
    x = ps["x"][:n][np.argsort(ps["id"][:n])]
    px, py = cc.surface_profile(x, dx)
    fx, fy = cc.failure_line(x0, x, dx, threshold=max(dx, cc.FAILURE_THRESHOLD))
    series = {
        "runout": cc.deposit_front(x, dx),
        "wall_height": float(py[0]),
        "profile_x": px,
        "profile_y": py,
        "failure_x": fx,
        "failure_y": fy,
    }
    series.update(cc.errors(series, cc.load_reference()))
    p = ps["mean_stress"][:n]
    return {
        "eps": eps,
        "dx": dx,
        "x0": x0,
        "x": x,
        "wall": wall,
        "steps": sim.step_count,
        **series,
        "max_tension_run": max(tension),
        "max_tension_final": tension[-1],
        "p_scale": float(np.max(p)),
        "min_sep_run": min(min_sep),
        "min_sep_final": min_sep[-1],
        "close_run": max(close),
        "close_final": close[-1],
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--resolution", type=int, default=25)
    ap.add_argument("--eps", type=float, nargs="+", default=[0.5, 0.0])
    ap.add_argument("--cohesion", type=float, default=None, help="Pa; default: the scene's (c = 0)")
    ap.add_argument("--out", default=str(cc.OUT))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from solver.errors import BlowUpError

    for eps in args.eps:
        try:
            r = run_case(args.resolution, eps, args.cohesion)
        except BlowUpError as err:  # a result of this study (the remedy off), not a crash of it
            print(
                f"resolution {args.resolution} cohesion {args.cohesion} eps {eps:g}: BLOW-UP: {err}",
                flush=True,
            )
            continue
        tag = "" if args.cohesion is None else f"_c{args.cohesion:g}"
        np.savez(out / f"positions_r{args.resolution}_eps{eps:g}{tag}.npz", x0=r["x0"], x=r["x"], dx=r["dx"])
        print(
            f"resolution {args.resolution} cohesion {args.cohesion} eps {eps:g}: runout {r['runout']:.4f} m, "
            f"wall height {r['wall_height']:.4f} m, "
            f"profile RMS {1000 * r['profile_rms']:.2f} mm, failure RMS {1000 * r['failure_rms']:.2f} mm, "
            f"max tension over run {r['max_tension_run']:.4g} Pa (final {r['max_tension_final']:.4g} Pa; max "
            f"p {r['p_scale']:.4g} Pa), "
            f"min separation/dx run {r['min_sep_run']:.3f} final {r['min_sep_final']:.3f}, "
            f"fraction with neighbour < dx/2 run {r['close_run']:.4f} final {r['close_final']:.4f}, "
            f"{r['steps']} steps, {r['wall']:.0f} s",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
