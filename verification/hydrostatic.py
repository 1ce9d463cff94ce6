"""Still-water tank: hydrostatic pressure and spurious velocities.

Exact solution: v = 0, p = rho0 g (H - y). Metrics at the end of the run (t = 0.5 s,
about 35 acoustic periods 2H/c):
  * e_p = RMS(<p_probe> - rho0 g (H - y)) / (rho0 g H) over pressure probes (SPH interpolation,
    verification/probes.py) on the tank's vertical centre line, every dx from the bottom to
    the surface, averaged over the last 0.1 s (~7 acoustic periods 2H/c) as a gauge with a
    finite response time measures the mean pressure. Error analysis: the
    cubic spline reproduces a linear field exactly where its support is complete, so the
    error lives within the support (2h) of the free surface and the bottom wall; there
    it is at most the pressure change across that band, so e_p <= h / H bounds it.
  * max |v| / c. Error analysis: weak compressibility ties density noise to the Mach
    number, drho/rho ~ M^2 (Monaghan 1994); the seed sizes c for 1 % density variation
    (M = 0.1). Spurious motion must be an order below that design speed: M <= 0.01.
  * no particle crossed a wall (the reflection safeguard never acted).
The RMS of the per-particle pressure error is reported too: it is dominated by acoustic
noise (amplitude ~ rho0 c |v|), which the seed's weak artificial viscosity (alpha = 0.01)
hardly damps; it is a property of the scheme, shown and not hidden.

Scheme: the solver's defaults (numerics.scheme = "default": midpoint-density leap-frog, Fourtakas
density diffusion, hydrostatic image pressure, wall repulsion); the study also runs the seed's
scheme (numerics.scheme = "seed") and each remedy alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .common import (
    RESULTS,
    CaseResult,
    Check,
    case_main,
    load_1min,
    rms,
    save_figure,
    save_study,
    scene_from_file,
    timed_run,
    timing_note,
)
from .probes import probe

DEPTH = 0.1
WIDTH = 0.2
G = 9.81
RHO0 = 1000.0
DEFAULT_RESOLUTION = 20  # particles over the depth
AVERAGING_WINDOW = 0.1  # s, the gauges' response time (~7 acoustic periods 2H/c)
STUDY_RESOLUTIONS = (10, 20, 40)


def scene(resolution, **overrides):
    return scene_from_file("hydrostatic_tank_2d.toml", **{"scene.spacing": DEPTH / resolution, **overrides})


def observe(sim):
    ps = sim.particles
    x, p, v = ps.owned("x"), ps.owned("p"), ps.owned("v")
    dx = sim.scene.scene.spacing
    depth = np.arange(0.5 * dx, DEPTH, dx)
    gauges = np.stack([np.full_like(depth, 0.5 * WIDTH), depth], axis=1)
    p_probe = probe(gauges, x, p, ps.owned("mass"), ps.owned("rho"), sim.h, 2)
    e_particle = rms(p - RHO0 * G * (DEPTH - x[:, 1])) / (RHO0 * G * DEPTH)
    mach = float(np.sqrt((v * v).sum(axis=1).max())) / sim.plan.materials.sound_speed[0]
    return (p_probe - RHO0 * G * (DEPTH - depth)) / (RHO0 * G * DEPTH), mach, e_particle


def run(resolution=DEFAULT_RESOLUTION, out_dir=None, **overrides):
    sc = scene(resolution, **overrides)
    times = np.linspace(0.0, sc.scene.end_time, 101)
    sim, obs, wall, cpu = timed_run(sc, times, observe)
    probe_err = np.array([o[0] for o in obs])  # (time, gauge) error / (rho0 g H)
    mach = np.array([o[1] for o in obs])
    e_particle = np.array([o[2] for o in obs])
    e_p = np.sqrt(np.nanmean(probe_err**2, axis=1))  # instantaneous RMS over gauges
    window = times >= sc.scene.end_time - AVERAGING_WINDOW
    e_mean = rms(np.nanmean(probe_err[window], axis=0))
    res = CaseResult(
        "hydrostatic",
        resolution,
        sim.particles.n_owned,
        sim.step_count,
        wall,
        {"t": times, "pressure_error": e_p, "mach": mach, "particle_pressure_noise": e_particle},
        cpu_time=cpu,
    )
    h_over_depth = sc.h / DEPTH
    res.checks = [
        Check(
            "RMS error of time-averaged gauge pressure / (rho0 g H)",
            e_mean,
            h_over_depth,
            "error analysis: support truncation at surface and wall, bound h/H",
        ),
        Check(
            "max spurious speed / c at the end",
            mach[-1],
            0.01,
            "error analysis: Mach 0.01, an order below the seed's design Mach 0.1",
        ),
        Check(
            "particles reflected at walls (safeguard acted)",
            float(sim.wall_reflections),
            0.0,
            "still water must never reach a wall plane",
        ),
    ]
    res.series["mean_pressure_error"] = e_mean
    res.sim_reflections = sim.wall_reflections
    res.notes = [
        f"instantaneous gauge pressure error at the end {e_p[-1]:.3g} (max over the run {e_p.max():.3g}); "
        f"max Mach over the run {mach.max():.3g}",
        f"per-particle pressure noise at the end (RMS / rho0 g H): {e_particle[-1]:.3g} (acoustic, see "
        "docstring)",
    ]
    if out_dir is not None:
        res.figure = figure(res, sim, Path(out_dir) / f"hydrostatic_r{resolution}.png")
    return res


def figure(res, sim, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ps = sim.particles
    y, p = ps.owned("x")[:, 1], ps.owned("p")
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax1.plot(p, y, ".", ms=2, label="ScourSPH particles")
    yy = np.linspace(0, DEPTH, 50)
    ax1.plot(RHO0 * G * (DEPTH - yy), yy, "k-", label="rho0 g (H - y)")
    ax1.set(xlabel="p (Pa)", ylabel="y (m)", title=f"pressure at t = {sim.t:.2f} s, H/dx = {res.resolution}")
    ax2.semilogy(res.series["t"], np.maximum(res.series["mach"], 1e-12), label="max |v| / c")
    ax2.semilogy(
        res.series["t"], np.maximum(res.series["pressure_error"], 1e-12), label="RMS p error / (rho0 g H)"
    )
    ax2.axhline(0.01, color="k", ls="--", lw=1, label="Mach tolerance")
    ax2.set(xlabel="t (s)", title="errors over time")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


STRONGER_AV = {"numerics.artificial_viscosity": {"water": {"alpha": 0.1, "beta": 0.0}}}


SEED = {"numerics.scheme": "seed"}


def study(resolutions=STUDY_RESOLUTIONS, out_dir=RESULTS):
    """Error and wall time per resolution with the defaults and with the seed's scheme, and at the
    finest resolution the seed's scheme with each remedy alone: alpha = 0.1, the midpoint-density
    leap-frog, the hydrostatic image pressure, the density diffusion. What accuracy costs in time."""
    fine = resolutions[-1]
    variants = (
        [(r, {}, "defaults") for r in resolutions]
        + [(r, SEED, "seed scheme (alpha 0.01, mirror images, half-step rho)") for r in resolutions]
        + [
            (fine, {**SEED, **STRONGER_AV}, "seed + alpha 0.1"),
            (fine, {**SEED, "numerics.leapfrog": "midpoint_density"}, "seed + midpoint_density"),
            (fine, {**SEED, "numerics.image_pressure": "hydrostatic"}, "seed + hydrostatic image pressure"),
            (fine, {**SEED, "numerics.density_diffusion": "fourtakas"}, "seed + Fourtakas density diffusion"),
            (fine, {**SEED, "numerics.wall_repulsion": True}, "seed + wall repulsion"),
        ]
    )
    rows = []
    for r, overrides, label in variants:
        res = run(r, **overrides)
        rows.append(
            dict(
                resolution=r,
                options=label,
                max_mach_over_run=float(res.series["mach"].max()),
                wall_reflections=res.sim_reflections,
                particles=res.particles,
                steps=res.steps,
                wall_time_s=res.wall_time,
                cpu_time_s=res.cpu_time,
                load_1min=load_1min(),
                mean_pressure_error=float(res.series["mean_pressure_error"]),
                instantaneous_pressure_error=float(res.series["pressure_error"][-1]),
                mach=float(res.series["mach"][-1]),
                particle_pressure_noise=float(res.series["particle_pressure_noise"][-1]),
            )
        )
    return save_study(
        rows,
        out_dir,
        "hydrostatic_study",
        note=timing_note("NUMBA_NUM_THREADS=1 python -m verification.hydrostatic --study"),
    )


# The study columns the nightly report plots against wall and CPU time (docs/nightly_report.md)
ACCURACY_COLUMNS = {
    "mean_pressure_error": "time-averaged gauge pressure error / (rho0 g H)",
    "mach": "spurious speed / c at the end",
}


if __name__ == "__main__":
    import sys

    raise SystemExit(case_main(sys.modules[__name__]))
