"""Column collapse (Bui et al. 2008): what makes the runout short (issue 24 item 3, last point).

Runs the collapse case (verification/column_collapse.py, the seed's scheme) at 5, 4 and 2.5 mm in
the variants that could change the runout for a physical reason, and the numerical one that does:
  base          the verification scene (Drucker-Prager, no-slip floor, soil AV alpha = beta = 1)
  mu_I_1mm      mu(I) once yielded with d = 1 mm (numerics.rheology = "material" over the seed preset;
                docs/rheology.md)
  mu_I_1.5mm    the same with d = 1.5 mm (Bui et al. 2008 used bars of 1 and 1.5 mm: the brief's value;
                the paper was not reachable here to check it first-hand)
  floor_19.8    a Coulomb floor (walls.y_min = "frictional") at the bars' own friction angle, the
                interface friction of a rough base (delta = phi)
  av_off        the soil's artificial viscosity off (alpha = beta = 0)
  mu_I_1mm_av_off, mu_I_1.5mm_av_off   mu(I) without it
and tabulates the case's metrics (runout of the contiguous deposit, height at the wall, free-surface
and failure-line RMS) with two that read the deposit's mass instead of its front: the area of the
deposit beyond x = 0.30 m (experiment: 1425 mm^2, the digitised profile integrated) and the "front by
area", the x beyond which the SPH deposit holds the experiment's area beyond 0.40 m (106 mm^2); plus
the farthest particle and the final / peak kinetic energy (a deposit still moving at 1 s is not final).

Writes verification/results/column_collapse/rheology_and_floor.md and .csv.

  NUMBA_NUM_THREADS=1 python -m verification.column_collapse_rheology [--variants base mu_I_1mm ...]
  NUMBA_NUM_THREADS=1 python -m verification.column_collapse_rheology --inertial-numbers
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from . import column_collapse as cc
from .common import machine_load, write_csv

AV_OFF = {"artificial_viscosity": {"bars": {"alpha": 0.0, "beta": 0.0}}}


def mu_i(d, numerics=None):
    return {"numerics": {"rheology": "material", **(numerics or {})},
            "materials": {"bars": {"rheology": "mu_I", "grain_size": d}}}  # fmt: skip


VARIANTS = {
    "base": None,
    "mu_I_1mm": mu_i(1.0e-3),
    "mu_I_1.5mm": mu_i(1.5e-3),
    "floor_19.8": {"walls": {"y_min": "frictional", "friction_angle": 19.8}},
    "av_off": {"numerics": AV_OFF},
    "mu_I_1mm_av_off": mu_i(1.0e-3, AV_OFF),
    "mu_I_1.5mm_av_off": mu_i(1.5e-3, AV_OFF),
}
RESOLUTIONS = (20, 25, 40)
BODY_FROM, FRONT_FROM = 0.30, 0.40  # m: where the deposit's mass is read (module doc)
OUT = cc.OUT


def experiment_area_beyond(x):
    """Area (m^2 per m) under the digitised final profile beyond x."""
    surf = cc.load_reference()["final_free_surface"]
    xs = np.linspace(x, surf[-1, 0], 4000)
    return float(np.trapezoid(np.interp(xs, surf[:, 0], surf[:, 1]), xs))


def mass_metrics(x, dx):
    """(SPH area beyond BODY_FROM, the front by area) of final positions x (one particle = dx^2)."""
    area = float(np.sum(x[:, 0] + 0.5 * dx > BODY_FROM)) * dx * dx
    xs = np.sort(x[:, 0])[::-1]
    held = np.arange(1, len(xs) + 1) * dx * dx
    front = float(xs[min(np.searchsorted(held, experiment_area_beyond(FRONT_FROM)), len(xs) - 1)] + 0.5 * dx)
    return area, front


def run_variant(name, resolution):
    res = cc.run(resolution, overrides=VARIANTS[name])
    s = res.series
    dx = cc.spacing(resolution)
    area, front = mass_metrics(s["x"], dx)
    return {"variant": name, "spacing_mm": 1e3 * dx, "runout_m": s["runout"],
            "runout_error_pct": 100.0 * s["runout_error"] / (s["runout"] - s["runout_error"]),
            "wall_height_m": s["wall_height"], "profile_rms_mm": 1e3 * s["profile_rms"],
            "failure_rms_mm": 1e3 * s["failure_rms"], "area_beyond_030_mm2": 1e6 * area,
            "front_by_area_m": front, "farthest_m": float(s["x"][:, 0].max() + 0.5 * dx),
            "ke_final_over_peak": s["ke_final_over_peak"], "cpu_time_s": res.cpu_time}  # fmt: skip


def write(rows, out=OUT):
    out = Path(out)
    write_csv(out / "rheology_and_floor.csv", rows)
    head = list(rows[0])
    lines = [
        "# Column collapse: what makes the runout short (issue 24)",
        "",
        f"Reproduce: `NUMBA_NUM_THREADS=1 python -m verification.column_collapse_rheology`; "
        f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}, {machine_load()}. "
        f"Experiment: runout 0.442 m, height at the wall 0.099 m, area beyond {BODY_FROM} m "
        f"{1e6 * experiment_area_beyond(BODY_FROM):.0f} mm^2, front by area {FRONT_FROM} m (by definition). "
        "Variants and metrics: the module's docstring; findings: README.md here.",
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    for r in rows:
        lines.append(
            "| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r.values()) + " |"
        )
    (out / "rheology_and_floor.md").write_text("\n".join(lines) + "\n")


def inertial_numbers(resolution=25, d=1.0e-3, times=(0.05, 0.1, 0.15, 0.2, 0.3, 0.4)):
    """Rows of I = gamma_dot d / sqrt(p / rho_grain) over the yielding particles (p > 1 Pa, sqrt(J2) on
    the static Drucker-Prager surface or above) of the mu(I) collapse at those times: how large the
    rate-dependent friction is in this flow (the bars' grain density taken as the scene's density)."""
    from solver.simulation import Simulation

    scene = cc.scene_at(cc.spacing(resolution), max(times), VARIANTS["mu_I_1mm"] if d == 1.0e-3 else mu_i(d))
    mat = scene.materials["bars"]
    sim = Simulation(scene)
    soil = sim.plan.materials.soil
    rows = []
    for t in times:
        sim.advance_to(t)
        sim.current_state()
        ps = sim.particles
        n = ps.n_owned
        p, rate, s = ps["mean_stress"][:n], ps["shear_rate"][:n], ps["stress_dev"][:n]
        j = np.sqrt(
            0.5 * (s[:, 0] ** 2 + s[:, 1] ** 2 + s[:, 2] ** 2) + s[:, 3] ** 2 + s[:, 4] ** 2 + s[:, 5] ** 2
        )
        yielding = (p > 1.0) & (j >= 0.999 * 3.0 * soil.alpha_phi[0] * p)
        inertial = rate[yielding] * d / np.sqrt(p[yielding] / mat.grain_density)
        increment = mat.friction_increment * inertial / (inertial + mat.inertial_number_i0)
        rows.append({"t": t, "yielding": int(yielding.sum()), "particles": n,
                     "I_median": float(np.median(inertial)), "I_p90": float(np.percentile(inertial, 90)),
                     "mu_increment_median": float(np.median(increment)),
                     "mu_increment_p90": float(np.percentile(increment, 90)),
                     "shear_rate_median": float(np.median(rate[yielding])),
                     "p_median": float(np.median(p[yielding]))})  # fmt: skip
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variants", nargs="+", choices=list(VARIANTS), default=list(VARIANTS))
    parser.add_argument(
        "--inertial-numbers", action="store_true", help="I statistics of the mu(I) run at 4 mm"
    )
    args = parser.parse_args(argv)
    if args.inertial_numbers:
        for row in inertial_numbers():
            print(row)
        return 0
    rows = []
    for name in args.variants:
        for resolution in RESOLUTIONS:
            rows.append(run_variant(name, resolution))
            print(rows[-1], flush=True)
    write(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
