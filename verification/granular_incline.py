"""Steady granular flow down a rough incline: the Bagnold profile of the mu(I) rheology (issue 24 item 1;
docs/rheology.md).

Reference (analytic): a layer of depth H on a rough base inclined at zeta, mu_s < tan(zeta) < mu_2, flows
steadily with the same inertial number I_zeta at every depth, mu(I_zeta) = tan(zeta):
    I_zeta = I_0 (tan(zeta) - mu_s) / (mu_2 - tan(zeta)),
    u(z) = (2/3) I_zeta sqrt(phi g cos(zeta)) (H^1.5 - (H - z)^1.5) / d          (the Bagnold profile)
(GDR MiDi 2004, Eur. Phys. J. E 14:341, sec. 3.4; Jop, Forterre & Pouliquen 2005, J. Fluid Mech.
541:167), with p = phi rho_grain g cos(zeta) (H - z) and tau = tan(zeta) p.

Set-up: the solver has no periodic boundaries, so the layer is finite (LENGTH long, open ends, the floor
a no-slip wall; gravity tilted by zeta instead of the floor) and starts in the Bagnold state itself:
velocity u(z), p(z) from the density (eq. 17 inverted), s_xy = tan(zeta) p, the other deviatoric
components zero. A steady solution stays put; what the case measures is whether the SPH layer holds it.
Its ends do not: the front runs out and the tail thins, and the news travels inwards, so the layer is
read over its middle CORE (0.35-0.65 of its length, 0.35 m from either end), over HOLD = 0.2 s (the
core of a 1 m layer and of a 2 m one agreed to 0.4 % at 0.2 s and parted after 0.3 s in prototype runs
at E = 1 MPa: docs/rheology.md).
A perfectly plastic layer (the ablation) accelerates at g (sin(zeta) - mu_s cos(zeta)) = 0.75 m/s^2 and
leaves the profile by 35 % of the surface speed over the hold (RMS at 4 mm).

Materials: Jop et al.'s (2005) glass beads, mu_s = tan(20.9 deg), mu_2 = tan(32.76 deg), I_0 = 0.279
(the defaults' increment 0.26), Mohr-Coulomb yield (seed eq. 16) so that mu_s = tan(phi) exactly, a solid
fraction 0.6 of rho_grain = 2500 kg/m^3; d = 4 mm under H = 40 mm (H/d = 10, within Jop et al.'s
flows), zeta = 25 deg: I_zeta = 0.134, surface speed 0.41 m/s. E = 0.2 MPa (elastic strain 0.3 % at
the base: the skeleton is stiff against the stresses) and nu = 0.3.
Numerics, chosen for this check, with reasons (docs/rheology.md):
  * artificial viscosity off (alpha = beta = 0): at the soil's alpha = beta = 1 its shear viscosity
    alpha h c / 8 (Monaghan 2005) would be of the rheology's own tau / (rho gamma_dot) here; the
    plastic flow carries the dissipation and the runs are stable without it;
  * image_pressure = "mirror" and no wall repulsion: both options are built for gravity normal to the
    floor (the equilibrium image stress adds q g^ g^, whose shear part is not the layer's static shear
    increment under tilted gravity, and the repulsion's strength D = 5 g H takes H along g, which here
    includes the layer's length).
The floor is the SPH no-slip wall (images with v' = -v, stress kept): its first row slips (`base slip`,
reported). The profile checks use the rows above one kernel support (2h) from the floor.

Checks (at the end of the hold, over the core):
  * effective friction of the core, mu_eff = tan(zeta) - <a_x> / (g cos(zeta)), <a_x> the depth-averaged
    acceleration (slope of the depth-averaged velocity over the second half of the hold), against
    mu(I_zeta) = tan(zeta): |mu_eff / tan(zeta) - 1| within FRICTION_TOLERANCE;
  * the Bagnold profile: RMS over the rows above 2h of (u - u_Bagnold(z)) / u_surface within
    PROFILE_TOLERANCE, u_Bagnold at each row's current mean height.
Tolerances: error analysis of what the check must resolve. The rate-dependent part of the friction at
I_zeta is mu(I_zeta) - mu_s = 0.084 (tan(zeta) - mu_s); the check must tell a rheology whose friction at
I_zeta is off by a tenth of that (0.0084, 1.8 % of tan(zeta)) from the right one. FRICTION_TOLERANCE =
0.018 is that tenth; over the hold, such a friction error moves the layer by 0.0084 g cos(zeta) HOLD =
0.015 m/s, 3.6 % of the surface speed: PROFILE_TOLERANCE = 0.036. The perfectly plastic ablation is 9.7x
the first and 9.6x the second (4 mm). The resolution study (4, 2, 1 mm) shows where the SPH errors lie against
them.

resolution = particles across H (10, 20, 40: dx = 4, 2, 1 mm).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .common import RESULTS, CaseResult, Check, machine_load, save_figure, save_study

G = 9.81
ZETA = 25.0  # degrees
PHI = 20.9  # degrees: mu_s = tan(20.9 deg) (Jop et al. 2005, glass beads)
FRICTION_INCREMENT, I0 = 0.26, 0.279  # mu_2 - mu_s, I_0 (Jop et al. 2005; the defaults)
D = 4.0e-3  # m, grain size
H = 0.04  # m, layer depth
LENGTH = 1.0  # m
X0 = 0.2  # m, the layer's tail at t = 0
RUNOUT_ROOM = 0.5  # m of domain beyond the front (the front's bottom grain travels < 0.35 m in HOLD)
SOLID_FRACTION, RHO_GRAIN = 0.6, 2500.0
YOUNGS, POISSON = 2.0e5, 0.3
HOLD = 0.2  # s
SAMPLES = 9  # times over the hold
CORE = (0.35, 0.65)  # fractions of the layer's length read
FRICTION_TOLERANCE = 0.018  # module doc: a tenth of mu(I_zeta) - mu_s, as a fraction of tan(zeta)
PROFILE_TOLERANCE = 0.036  # module doc: that friction error's velocity over the hold / surface speed
DEFAULT_RESOLUTION = 10
STUDY_RESOLUTIONS = (10, 20, 40)
OUT = RESULTS / "granular_incline"


def mu_s():
    return float(np.tan(np.radians(PHI)))


def inertial_number_at_slope(zeta=ZETA):
    """I_zeta = I_0 (tan(zeta) - mu_s) / (mu_2 - tan(zeta)): mu(I_zeta) = tan(zeta) (GDR MiDi 2004)."""
    t = np.tan(np.radians(zeta))
    return I0 * (t - mu_s()) / (mu_s() + FRICTION_INCREMENT - t)


def bagnold(z, zeta=ZETA, depth=H, d=D):
    """u(z) = (2/3) I_zeta sqrt(phi g cos(zeta)) (H^1.5 - (H - z)^1.5) / d (GDR MiDi 2004; Jop et al.
    2005)."""
    c = np.cos(np.radians(zeta))
    below = np.clip(depth - np.asarray(z, float), 0.0, None)
    return 2.0 / 3.0 * inertial_number_at_slope(zeta) * np.sqrt(SOLID_FRACTION * G * c) * (
        depth**1.5 - below**1.5
    ) / d  # fmt: skip


def scene(resolution, end_time=HOLD, rheology="mu_I"):
    from solver.scene import parse_scene

    dx = H / resolution
    z = np.radians(ZETA)
    raw = {
        "scene": {"name": "granular_incline", "dimension": 2, "spacing": dx, "end_time": end_time,
                  "gravity": [G * np.sin(z), -G * np.cos(z)]},
        "domain": {"min": [0.0, 0.0], "max": [X0 + LENGTH + RUNOUT_ROOM, 3.0 * H]},
        "walls": {"y_min": "no_slip"},
        "materials": {"beads": {
            "model": "soil", "density": SOLID_FRACTION * RHO_GRAIN, "porosity": 1.0 - SOLID_FRACTION,
            "youngs_modulus": YOUNGS, "poisson_ratio": POISSON, "friction_angle": PHI, "cohesion": 0.0,
            "yield_model": "mohr_coulomb", "rheology": rheology, "grain_size": D,
            "friction_increment": FRICTION_INCREMENT, "inertial_number_i0": I0}},
        "blocks": [{"name": "layer", "material": "beads", "shape": "rectangle", "min": [X0, 0.0],
                    "max": [X0 + LENGTH, H]}],
        "numerics": {"artificial_viscosity": {"beads": {"alpha": 0.0, "beta": 0.0}},
                     "image_pressure": "mirror", "wall_repulsion": False},
        "output": {"interval": end_time, "vtk": False, "render": False, "fields": ["velocity", "density"]},
    }  # fmt: skip
    return parse_scene(raw, "<verification granular_incline>")


def layer_in_bagnold_state(resolution, rheology="mu_I", end_time=HOLD):
    """A Simulation of the layer started in the steady Bagnold state (module doc)."""
    from solver.simulation import Simulation

    sc = scene(resolution, end_time, rheology)
    sim = Simulation(sc)
    ps = sim.particles
    n = ps.n_owned
    y = ps["x"][:n, 1]
    mat = sc.materials["beads"]
    z = np.radians(ZETA)
    p = mat.density * G * np.cos(z) * (H - y)
    rho = mat.density * (1.0 + p / mat.bulk)  # eq. (17) inverted
    for name in ("rho", "rho_half"):
        ps[name][:n] = rho
    for name in ("stress_dev", "stress_dev_half"):
        ps[name][:n] = 0.0
        ps[name][:n, 3] = np.tan(z) * p  # s_xy = tau = tan(zeta) p
    for name in ("v", "v_half"):
        ps[name][:n] = 0.0
        ps[name][:n, 0] = bagnold(y)
    return sim


def run_one(resolution, rheology="mu_I"):
    from .common import Stopwatch

    sim = layer_in_bagnold_state(resolution, rheology)
    dx = H / resolution
    ps = sim.particles
    n = ps.n_owned
    x0 = ps["x"][:n, 0]
    core = (x0 > X0 + CORE[0] * LENGTH) & (x0 < X0 + CORE[1] * LENGTH)
    row_of = dict(zip(ps["id"][:n][core], np.floor(ps["x"][:n, 1][core] / dx).astype(int)))
    rows = np.array(sorted(set(row_of.values())))
    times = np.linspace(0.0, HOLD, SAMPLES)
    profiles, heights = [], []
    clock = Stopwatch()
    for t in times:
        if t > sim.t:
            sim.advance_to(t)
        sim.current_state()
        n = sim.particles.n_owned
        ids = sim.particles["id"][:n]
        sel = np.flatnonzero(np.isin(ids, list(row_of)))
        r = np.array([row_of[i] for i in ids[sel]])
        u = sim.particles["v"][sel, 0]
        y = sim.particles["x"][sel, 1]
        profiles.append(np.array([u[r == k].mean() for k in rows]))
        heights.append(np.array([y[r == k].mean() for k in rows]))
    wall, cpu = clock.read()
    profiles, heights = np.array(profiles), np.array(heights)
    return {"resolution": resolution, "dx": dx, "rheology": rheology, "particles": sim.particles.n_owned,
            "steps": sim.step_count, "wall": wall, "cpu": cpu, "t": times, "rows": rows,
            "profiles": profiles, "heights": heights, **metrics(times, profiles, heights, dx)}  # fmt: skip


def pair_means(a):
    """Means of adjacent rows, (a_k + a_k+1) / 2: the filter that removes the odd-even mode."""
    return 0.5 * (a[:-1] + a[1:])


def metrics(times, profiles, heights, dx):
    """The checks' values (module doc) from the core's row profiles over the hold. The profile is
    compared as means of adjacent rows, the SPH rows and the reference alike: the rows' velocities carry
    an odd-even mode (rows k and k + 2 faster than k + 1), which the SPH velocity gradient cannot see
    (sum_j V_j (v_j - v_i) grad W_ij differences rows k + 1 and k - 1 across row k), so neither the
    strain rate nor the stress responds to it and it is undamped without artificial viscosity; it says
    nothing about the rheology, and its size is reported (`odd_even`: RMS of u_k - (u_k-1 + u_k+1) / 2
    over the interior rows, / u_surface)."""
    z = np.radians(ZETA)
    h = 1.3 * dx
    u_end, y_end = profiles[-1], heights[-1]
    reference = bagnold(y_end)
    surface = float(bagnold(H))
    above = pair_means(y_end) > 2.0 * h + 0.5 * dx  # both rows beyond one kernel support from the floor
    error = (pair_means(u_end) - pair_means(reference)) / surface
    half = times >= 0.5 * times[-1]
    mean_u = profiles.mean(axis=1)  # rows are equally spaced: the depth average
    accel = float(np.polyfit(times[half], mean_u[half], 1)[0])
    mu_eff = np.tan(z) - accel / (G * np.cos(z))
    wiggle = u_end[1:-1] - 0.5 * (u_end[:-2] + u_end[2:])
    return {
        "mu_eff": float(mu_eff),
        "friction_error": float(mu_eff / np.tan(z) - 1.0),
        "profile_rms": float(np.sqrt(np.mean(error[above] ** 2))),
        "profile_rms_all_rows": float(np.sqrt(np.mean(error**2))),
        "odd_even": float(np.sqrt(np.mean(wiggle**2)) / surface),
        "surface_error": float((u_end[-1] - reference[-1]) / surface),
        "base_slip": float((u_end[0] - reference[0]) / surface),
    }


def checks(r):
    return [
        Check("|mu_eff / tan(zeta) - 1| of the core over the hold", r["friction_error"], FRICTION_TOLERANCE,
              "a tenth of mu(I_zeta) - mu_s (module doc)"),
        Check("RMS (u - u_Bagnold) / u_surface, pairs of rows above 2h", r["profile_rms"], PROFILE_TOLERANCE,
              "that friction error's velocity over the hold (module doc)"),
    ]  # fmt: skip


def run(resolution=DEFAULT_RESOLUTION, out_dir=None):
    r = run_one(resolution)
    plastic = run_one(resolution, rheology="perfectly_plastic")
    res = CaseResult("granular_incline", resolution, r["particles"], r["steps"], r["wall"],
                     {"mu_I": r, "perfectly_plastic": plastic}, cpu_time=r["cpu"])  # fmt: skip
    res.checks = checks(r)
    res.notes = [
        f"dx = {1e3 * r['dx']:g} mm, I_zeta = {inertial_number_at_slope():.4f}, Bagnold surface speed "
        f"{bagnold(H):.4f} m/s; mu_eff {r['mu_eff']:.4f} (tan(zeta) {np.tan(np.radians(ZETA)):.4f}, mu_s "
        f"{mu_s():.4f}); profile RMS {r['profile_rms']:.4f} (all rows {r['profile_rms_all_rows']:.4f}); "
        f"odd-even mode {r['odd_even']:.4f}; "
        f"surface {r['surface_error']:+.4f}; base slip {r['base_slip']:+.4f} of the surface speed",
        f"ablation, perfectly plastic (not checked): mu_eff {plastic['mu_eff']:.4f}, profile RMS "
        f"{plastic['profile_rms']:.4f}, surface {plastic['surface_error']:+.4f}",
    ]
    if out_dir is not None:
        res.figure = figure([r, plastic], Path(out_dir) / f"granular_incline_r{resolution}.png")
    return res


def figure(runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 4))
    z = np.linspace(0.0, H, 200)
    ax.plot(bagnold(z), 1e3 * z, "k-", label="Bagnold (mu(I), analytic)")
    for r, style in zip(runs, ("o", "s")):
        ax.plot(r["profiles"][-1], 1e3 * r["heights"][-1], style, mfc="none",
                label=f"SPH {r['rheology']}, t = {r['t'][-1]:g} s")  # fmt: skip
    ax.plot(runs[0]["profiles"][0], 1e3 * runs[0]["heights"][0], "x", color="0.5", label="SPH, t = 0")
    ax.set_xlabel("u (m/s)")
    ax.set_ylabel("z (mm)")
    ax.set_title(f"Granular flow down a {ZETA:g} deg incline, dx = {1e3 * runs[0]['dx']:g} mm")
    ax.legend(fontsize=7)
    return save_figure(fig, path)


def study(resolutions=STUDY_RESOLUTIONS, out_dir=OUT):
    rows = []
    for resolution in resolutions:
        r = run_one(resolution)
        rows.append({"resolution": resolution, "dx_mm": 1e3 * r["dx"], "particles": r["particles"],
                     "steps": r["steps"], "mu_eff": r["mu_eff"], "friction_error": r["friction_error"],
                     "profile_rms": r["profile_rms"], "profile_rms_all_rows": r["profile_rms_all_rows"],
                     "odd_even": r["odd_even"],
                     "surface_error": r["surface_error"], "base_slip": r["base_slip"],
                     "wall_time_s": r["wall"], "cpu_time_s": r["cpu"]})  # fmt: skip
        figure([r], Path(out_dir) / f"granular_incline_r{resolution}.png")
        np.savez(Path(out_dir) / f"profiles_r{resolution}.npz", t=r["t"], rows=r["rows"],
                 profiles=r["profiles"], heights=r["heights"])  # fmt: skip
    save_study(rows, out_dir, "resolution_study",
               note="Reproduce: `python -m verification.granular_incline --study`; the mu(I) layer only, "
               f"{HOLD:g} s hold; NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}, "
               f"{machine_load()}")  # fmt: skip
    return rows


if __name__ == "__main__":
    import sys

    from .common import case_main

    raise SystemExit(case_main(sys.modules[__name__]))
