"""Saturated bed at rest under still water (issue 10, item 4; docs/verification_seepage.md case 1).

A bed of saturated sand D = 0.1 m deep (soil particles and pore water on the same lattice,
`saturated = true`) under H_w - D = 0.1 m of still water, in a tank 0.1 m wide with free-slip
walls, started at the hydrostatic pore pressure and the geostatic effective stress. Exact
solution: nothing moves; the pore pressure is p = gamma_w (H_w - y) and the skeleton carries the
vertical effective stress sigma'_v = gamma' (D - y), gamma' = (1 - n)(rho_grain - rho_w) g
(Terzaghi's effective stress; `verification.analytic.seepage.saturated_bed_profiles`).

Measured over the last 0.1 s of a 0.3 s run (about 90 P-wave transits 2D/c_p of the bed), in
depth bins of two dx (ROW_MODE): the time-averaged profiles of sigma'_v (soil particles) and p (water
particles below the bed surface), the largest soil displacement and the largest speed.

Tolerances:
  * profiles: RMS(bin error) / (gamma' D) and / (gamma_w H_w) <= h / D: the SPH support is
    truncated within 2h of the bed surface (a density jump of the water, an end of the soil) and
    of the floor, and there the error is at most the change across that band (the same error
    analysis as the still-water tank, verification/hydrostatic.py);
  * slope of sigma'_v with depth over the interior bins (>= 2h from both ends) / gamma' - 1
    within h / D (the interior is where the claim "the bed carries gamma' z" lives);
  * drift: largest soil displacement < 0.1 dx; largest speed / c < 0.01 (an order below the
    seed's design Mach number 0.1, as for still water).

The seed's formulation (eqs. 18, 20, 21) has no pore pressure acting on the skeleton: the
skeleton carries its dry weight, sigma'_v = rho_dry g (D - y), i.e. rho_dry / (rho_dry - (1 - n)
rho_w) = rho_grain / (rho_grain - rho_w) = 1.606 gamma' z for rho_grain = 2650 (+61 %, whatever n).
The case cannot pass the buoyancy check with it: it says so and pins the measured slope to that
derived value (same tolerance h / D).

ROW_MODE: the soil's stress alternates from one particle row to the next (a zero-energy mode of
the SPH stress divergence, present in both formulations); a gauge averages over it, so the bins
hold two rows, and the amplitude of the row-to-row alternation is reported in the notes.

`resolution` = particles over the bed depth D.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from . import seepage_common as sc
from .common import RESULTS, CaseResult, Check, machine_load, rms, save_figure, save_study

D = 0.1  # bed depth (m)
H_W = 0.2  # water surface above the floor (m)
WIDTH = 0.1
T_END = 0.3
WINDOW = 0.1  # s averaged at the end
DEFAULT_RESOLUTION = 20  # dx = 5 mm
STUDY_RESOLUTIONS = (10, 20, 40)
OUT = RESULTS / "seepage_bed_at_rest"
SAND = sc.sand(porosity=0.4, grain_density=2650.0, permeability=1e-3)


def scene(resolution, formulation="mixture", **numerics):
    dx = D / resolution
    blocks = [
        {"name": "bed", "material": "sand", "shape": "rectangle", "min": [0.0, 0.0], "max": [WIDTH, D],
         "saturated": True, "geostatic": True},
        {"name": "pond", "material": "water", "shape": "rectangle", "min": [0.0, D], "max": [WIDTH, H_W],
         "hydrostatic": True},
    ]  # fmt: skip
    return sc.scene(
        "seepage_bed_at_rest", dx, T_END, [WIDTH, H_W + 0.05], {"water": sc.WATER, "sand": SAND}, blocks,
        formulation, **numerics,
    )  # fmt: skip


def dry_weight_ratio(mat=SAND):
    """sigma'_v / gamma' z when the skeleton carries its dry weight (seed formulation)."""
    return mat["density"] * sc.G / sc.buoyant_unit_weight(mat)


def run_one(resolution, formulation):
    from solver.simulation import Simulation

    sim = Simulation(scene(resolution, formulation))
    dx = D / resolution
    edges = np.arange(0.0, D + 0.5 * dx, 2 * dx)  # two rows a bin: see ROW_MODE
    fine = np.arange(0.0, D + 0.5 * dx, dx)  # one row a bin
    soil = sc.soil_rows(sim)
    ids = sim.particles["id"][soil]
    x0 = dict(zip(ids.tolist(), sim.particles["x"][soil].copy()))
    c = float(sim.plan.materials.sound_speed.max())

    def observe(s):
        ps = s.particles
        so, wa = sc.soil_rows(s), sc.water_rows(s)
        y_s, y_w = ps["x"][so, 1], ps["x"][wa, 1]
        in_bed = y_w < D
        sig = sc.bin_profile(y_s, sc.vertical_effective_stress(s, so), edges)
        p = sc.bin_profile(y_w[in_bed], ps["p"][wa][in_bed], edges)
        disp = max(np.linalg.norm(ps["x"][r] - x0[i]) for r, i in zip(so, ps["id"][so].tolist()))
        speed = float(np.sqrt((ps["v"][: ps.n_owned] ** 2).sum(axis=1)).max())
        rows = sc.bin_profile(y_s, sc.vertical_effective_stress(s, so), fine)
        return sig, p, disp, speed / c, rows

    times = np.linspace(0.0, T_END, 31)
    obs, wall, cpu = sc.run_timed(sim, times, observe)
    window = times >= T_END - WINDOW - 1e-12
    sig = np.nanmean([o[0] for o, w in zip(obs, window) if w], axis=0)
    p = np.nanmean([o[1] for o, w in zip(obs, window) if w], axis=0)
    yc = 0.5 * (edges[1:] + edges[:-1])
    rows = np.nanmean([o[4] for o, w in zip(obs, window) if w], axis=0)
    row_mode = rms(0.5 * (rows[1:-1] - 0.5 * (rows[:-2] + rows[2:]))) / (sc.buoyant_unit_weight(SAND) * D)
    gamma_p = sc.buoyant_unit_weight(SAND)
    sig_exact = gamma_p * (D - yc)
    p_exact = sc.GAMMA_W * (H_W - yc)
    interior = (yc > 2 * sim.h) & (yc < D - 2 * sim.h)
    slope = -np.polyfit(yc[interior], sig[interior], 1)[0]
    return dict(
        formulation=formulation, dx=dx, h=sim.h, particles=sim.particles.n_owned, steps=sim.step_count,
        wall=wall, cpu=cpu, y=yc, sigma=sig, sigma_exact=sig_exact, p=p, p_exact=p_exact,
        sigma_rms=rms(sig - sig_exact) / (gamma_p * D), p_rms=rms(p - p_exact) / (sc.GAMMA_W * H_W),
        slope_ratio=slope / gamma_p, displacement=max(o[2] for o in obs), mach=obs[-1][3],
        mach_max=max(o[3] for o in obs), t=times, row_mode=row_mode, speed=np.array([o[3] for o in obs]),
    )  # fmt: skip


def run(resolution=DEFAULT_RESOLUTION, out_dir=None):
    runs = {f: run_one(resolution, f) for f in sc.FORMULATIONS}
    mix, seed = runs["mixture"], runs["seed"]
    res = CaseResult(
        "seepage_bed_at_rest", resolution, mix["particles"], mix["steps"] + seed["steps"],
        mix["wall"] + seed["wall"], runs,
    )  # fmt: skip
    res.checks = checks(runs)
    res.notes = [
        f"{f}: sigma'_v slope / gamma' = {r['slope_ratio']:.4f}, RMS sigma'_v error {r['sigma_rms']:.4f} "
        f"gamma' D (row-to-row alternation {r['row_mode']:.3f} gamma' D), RMS pore-pressure error "
        f"{r['p_rms']:.4f} gamma_w H_w, largest soil displacement "
        f"{r['displacement'] / r['dx']:.3g} dx, max speed / c {r['mach_max']:.3g}; {r['steps']} steps, "
        f"{r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU"
        for f, r in runs.items()
    ]
    res.notes.append(
        f"seed formulation: no pore pressure on the skeleton, so it carries its dry weight: slope "
        f"{seed['slope_ratio']:.3f} gamma' (derived rho_dry / (rho_dry - (1 - n) rho_w) = "
        f"{dry_weight_ratio():.3f}, +{100 * (dry_weight_ratio() - 1):.0f} %): it cannot pass the "
        "buoyancy check, by that much"
    )
    if out_dir is not None:
        res.figure = figure(runs, Path(out_dir) / f"seepage_bed_at_rest_r{resolution}.png")
    return res


def checks(runs):
    out = []
    for f, r in runs.items():
        tol = r["h"] / D
        src = "error analysis: support truncation at the bed surface and floor, bound h/D"
        ref = 1.0 if f == "mixture" else dry_weight_ratio()
        sigma_rms = rms(r["sigma"] - ref * r["sigma_exact"]) / (sc.buoyant_unit_weight(SAND) * D)
        against = "" if f == "mixture" else "; against the seed's dry weight (derived)"
        out.append(
            Check(f"{f}: RMS(sigma'_v - {ref:.3f} gamma' z) / (gamma' D)", sigma_rms, tol, src + against)
        )
        expected = 1.0 if f == "mixture" else dry_weight_ratio()
        out.append(
            Check(
                f"{f}: interior slope of sigma'_v / gamma' - {expected:.3f}",
                r["slope_ratio"] - expected,
                tol,
                "effective stress gamma' z (mixture) or the dry weight (seed, derived; the seed cannot "
                "carry gamma' z); bound h/D",
            )
        )
        p_metric = f"{f}: RMS(p - gamma_w (H_w - y)) / (gamma_w H_w) in the bed"
        out.append(
            Check(p_metric, r["p_rms"], r["h"] / H_W, "error analysis as for still water, bound h/H_w")
        )
        out.append(Check(f"{f}: largest soil displacement / dx", r["displacement"] / r["dx"], 0.1,
                         "at rest: no drift (design, docs/verification_seepage.md)"))  # fmt: skip
        out.append(Check(f"{f}: max speed / c at the end", r["mach"], 0.01,
                         "an order below the seed's design Mach 0.1 (as hydrostatic.py)"))  # fmt: skip
    return out


def figure(runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 3, figsize=(12, 4))
    styles = {"mixture": "bo", "seed": "rs"}
    for f, r in runs.items():
        axs[0].plot(r["sigma"] / 1e3, r["y"], styles[f], ms=4, mfc="none", label=f"SPH, {f}")
        axs[1].plot(r["p"] / 1e3, r["y"], styles[f], ms=4, mfc="none", label=f"SPH, {f}")
        axs[2].semilogy(r["t"], np.maximum(r["speed"], 1e-12), styles[f][0] + "-", label=f"{f}")
    r = runs["mixture"]
    axs[0].plot(r["sigma_exact"] / 1e3, r["y"], "k-", label="gamma' (D - y)")
    axs[0].plot(
        dry_weight_ratio() * r["sigma_exact"] / 1e3, r["y"], "k--", label="dry weight (seed, derived)"
    )
    axs[1].plot(r["p_exact"] / 1e3, r["y"], "k-", label="gamma_w (H_w - y)")
    axs[0].set(xlabel="sigma'_v (kPa)", ylabel="y (m)", title=f"effective stress, dx = {1e3 * r['dx']:g} mm")
    axs[1].set(xlabel="pore pressure (kPa)", title="pore pressure in the bed (time-averaged)")
    axs[2].axhline(0.01, color="k", ls="--", lw=1, label="tolerance")
    axs[2].set(xlabel="t (s)", ylabel="max |v| / c", title="spurious speed")
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


def study(resolutions=STUDY_RESOLUTIONS, out_dir=OUT):
    rows = []
    for r in resolutions:
        res = run(r, out_dir=out_dir)
        for f, o in res.series.items():
            rows.append(
                {
                    "resolution": r, "formulation": f, "dx_mm": 1e3 * o["dx"], "particles": o["particles"],
                    "steps": o["steps"], "wall_time_s": o["wall"], "cpu_time_s": o["cpu"],
                    "slope_over_gamma_prime": o["slope_ratio"], "sigma_rms_over_gamma_D": o["sigma_rms"],
                    "p_rms_over_gamma_w_Hw": o["p_rms"], "displacement_over_dx": o["displacement"] / o["dx"],
                    "mach_end": o["mach"], "row_mode_over_gamma_D": o["row_mode"], "checks": "pass" if all(
                        c.passed for c in res.checks if c.metric.startswith(f)) else "FAIL",
                }
            )  # fmt: skip
    save_study(rows, out_dir, "resolution_study")
    note = (
        f"Wall and CPU time of the stepping, one process, NUMBA_NUM_THREADS="
        f"{os.environ.get('NUMBA_NUM_THREADS', 'default')}, {machine_load()}.\n"
    )
    (Path(out_dir) / "resolution_study_load.txt").write_text(note)
    return rows


if __name__ == "__main__":
    import sys

    from .common import case_main

    raise SystemExit(case_main(sys.modules[__name__]))
