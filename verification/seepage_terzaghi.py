"""Terzaghi 1D consolidation (issue 10, item 4; docs/verification_seepage.md case 3).

Set-up: a saturated elastic soil column H = 0.1 m tall between free-slip walls (laterally
confined: an oedometer) on an impermeable floor, under a saturated, permeable load layer
(permeability 100 k, thickness T_LOAD, its water table at its top): the column's top is drained
into it (the load layer's head loss is 1 % of the column's). The load is the layer's buoyant
weight, q = (RHO_LOAD - (1 - n) rho_w) g T_LOAD = 9.52 kPa (the seed form: its dry weight). No
traction term is needed, and the water expelled from the column enters pores of the same
porosity, so pore-water particles keep a consistent water fraction (docs/seepage.md). Gravity is
on; the excess pore pressure is u = p - gamma_w (H + T_LOAD - y).

The run starts in the state just after an instantaneous loading (`initial_state`): pore pressure
hydrostatic + B q (the column's water table raised by B q / gamma_w), the skeleton at its buoyant
geostatic stress + (1 - B) q, the load layer at its own geostatic stress: total stress in
equilibrium, and in the discrete equations too (each particle's mass rho dx^dim at its stressed
density, the weight above a row summed from these masses, wall images rebuilt: `initial_state`;
before, the column started 0.03-0.13 g out of balance and rang at +0.25 u0). Two earlier
versions failed, for reasons that matter to users:
  * the heavy layer placed dry on the column at t = 0 rang on the column's undrained stiffness
    at ~23 Hz with an amplitude of u0 (u = 1.66 u_series at T_v = 0.1, dx = 10 mm): Terzaghi's
    problem starts after the undrained response, which this initial state is;
  * a column of ordinary sand (dry density 1590) under the 20000 kg/m3 load: the soil-soil
    interface with a 12-fold density jump blew up at T_v ~ 0.45 (SPH's stress form weighs a
    neighbour by its mass; the water pass has density-jump forms, the soil pass does not). The
    column therefore has the load's dry density (RHO_COLUMN): it changes nothing in Terzaghi's
    problem (c_v, B and u0 do not depend on it) but the geostatic stress.
(A dry load layer also blew up, at T_v ~ 0.45: pore water expelled into dry pores lost its density.)

Reference (verification.analytic.seepage): with weakly compressible water, the load splits at
once into u0 = B q, B = m_v / (m_v + n / K_w), K_w = rho_w c^2 (Skempton), and u then follows
Terzaghi's series with c_v,eff = k / (gamma_w (m_v + n / K_w)), T_v = c_v,eff t / H^2. Here
E = 1 MPa, nu = 0 (E_oed = 1 MPa, m_v = 1e-6 1/Pa), n = 0.4, c = 40 m/s (K_w = 1.6e6 Pa,
B = 0.8), k = 7.5e-5 m/s: c_v,eff = 0.0061 m2/s and t(T_v = 1) = 1.64 s; the undrained P wave
(E_oed + K_w / n = 5 MPa over 20000 kg/m3: 16 m/s) crosses the column in 6 ms.

Terzaghi's series is quasi-static; the simulation solves the dynamic (Biot) problem. The drained
top, opened at t = 0, settles the column at a rate ~ t^-1/2, which the load layer's and column's
mass cannot follow: they ring on the column's undrained stiffness (`undrained_period`, T_p = 37 ms
here) with an amplitude ~ sqrt(c_v,eff T_p) / H in u / u0 (no quasi-static solution has it). The
case's parameters keep T_p small against t(T_v = 0.1) = 0.16 s: k = 7.5e-5 m/s (not 3e-4) and
c = 40 m/s (not 20; the Tait water's tangent bulk modulus K_w + 7 p then moves c_v,eff by 0.7 %,
not 5 %) cut T_p / t(T_v = 0.1) from 0.89 to 0.22, at 10 times the steps (the step is
drag-limited, dt ~ k / (n g)). Each check compares the mean over one undrained period centred on
its time (`window_times`, 8 samples) of u and of the series alike: the mean of the ringing over
its period is zero to first order, and the averaged series is what the check expects of a
quasi-static solution. (Earlier versions sampled +/- 2 % of t and had k = 3e-4, c = 20: 3.9 /
2.2 % at T_v = 0.1 / 0.2, most of it an initial state out of equilibrium: `initial_state`.)

Measured: u in depth bins of 2 dx (pore-water particles) at T_v = 0.1, 0.2, 0.5, 1; the issue's
profile error, RMS(u - u_series) / u0 (`profile_l2_error`), goal 2 % (issue 10; a two-phase MPM
code reaches 2.3 % at T_v = 0.2: Bandara & Soga 2015 as cited by Morikawa & Asai 2022); and
U(T_v) = 1 - mean(u) / u0 against `terzaghi_degree` (reported).

The seed's formulation has no storage term (the skeleton's compression does not squeeze the
pore water) and no pore pressure on the skeleton: it cannot produce u0 = B q nor hand the load from
the water to the skeleton. Started from the same pore pressure, its excess u drains by the water's
own compressibility alone (c = k K_w / (gamma_w n), 5 c_v,eff here) while its skeleton carries
its dry weight and all of q from the start. The case says so and reports its u against the series.

`resolution` = particles over H.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import seepage_common as sc
from .analytic import seepage as an
from .common import RESULTS, CaseResult, Check, load_1min, save_figure, save_study, timing_note

H = 0.1
WIDTH = 0.06
POROSITY = 0.4
K = 7.5e-5
V_TYP = 4.0  # the water's typical velocity: c = 10 V_TYP = 40 m/s (docstring: why not 20)
E = 1.0e6
RHO_LOAD = 20000.0  # dry density of the load layer (a dense, permeable surcharge)
RHO_COLUMN = RHO_LOAD  # the column's dry density: no density jump at the soil-soil interface (docstring)
T_LOAD = 0.05
TV_CHECK = (0.1, 0.2, 0.5, 1.0)
# Documented shortfalls (docs/seepage.md, Verification): the nightly shows them as known, not new.
_SEED_WHY = (
    "the seed formulation has no Biot storage term (docs/seepage.md), and its pore pressure does not "
    "follow the consolidation series"
)
KNOWN_FAILURES = {f"seed: RMS(u - u_series) / u0 at T_v = {tv:g}": _SEED_WHY for tv in TV_CHECK}
GOAL = 0.02  # issue 10
DEFAULT_RESOLUTION = 20
STUDY_RESOLUTIONS = (10, 20, 40)
OUT = RESULTS / "seepage_terzaghi"


def materials(typical_velocity=V_TYP):
    soil = sc.sand(POROSITY, RHO_COLUMN / (1.0 - POROSITY), K, youngs_modulus=E, poisson_ratio=0.0,
                   yield_model="elastic")  # fmt: skip
    load = {**soil, "density": RHO_LOAD, "permeability": 100 * K, "youngs_modulus": 5e6}
    return {"water": {**sc.WATER, "typical_velocity": typical_velocity}, "soil": soil, "load": load}


def scene(resolution, formulation="mixture", typical_velocity=V_TYP, t_end=None):
    dx = H / resolution
    mats = materials(typical_velocity)
    blocks = [
        {"name": "column", "material": "soil", "shape": "rectangle", "min": [0.0, 0.0], "max": [WIDTH, H],
         "saturated": True, "water_table": H + T_LOAD + water_table_rise(formulation, typical_velocity)},
        {"name": "load", "material": "load", "shape": "rectangle", "min": [0.0, H],
         "max": [WIDTH, H + T_LOAD], "geostatic": True, "saturated": True},
    ]  # fmt: skip
    t_end = t_end or reference(typical_velocity, formulation)["t1"] * 1.02
    return sc.scene("seepage_terzaghi", dx, t_end, [WIDTH, H + T_LOAD + 0.03], mats, blocks, formulation)


def initial_state(sim, formulation, typical_velocity=V_TYP):
    """Overwrite the column's skeleton stress with the state just after loading: sigma'_v = the
    weight of the skeleton above + q_s, sigma'_h = K0 sigma'_v (as solver.initial_state.geostatic_state),
    with the buoyant weight and q_s = (1 - B) q in the mixture; the seed's skeleton feels no pore
    pressure, so it carries its dry weight and all of q. Half-step fields follow.

    Self-consistent: the soil's mean stress is p = K (rho / rho0 - 1) (seed eq. 17), so a particle at
    stress p has rho = rho0 (1 + p / K), and its mass is rho dx^dim (its lattice volume, as
    create_particles sets it). At E = 1 MPa the column is compressed by up to 4 % (p / K), so the
    weight above a row is the sum of these masses, not rho0 g depth: a fixed point in sigma'_v,
    solved row by row from the top (it converges in a few sweeps: the correction is O(p / K)).
    Either shortcut leaves the column out of equilibrium by ~p/K of its weight (a mass rho0 dx^dim
    under rho: the SPH volume m / rho and the stress divergence shrink, -0.03..-0.13 g at dx = 10 mm;
    mass rho dx^dim under sigma'_v from rho0: -0.02..-0.03 g), and the column, 2 q heavy, then rings
    on its undrained stiffness (docs/seepage.md, Terzaghi: the start transient)."""
    ref = reference(typical_velocity, formulation)
    ps = sim.particles
    n = ps.n_owned
    dx, dim = sim.scene.scene.spacing, sim.scene.dim
    mat = sim.scene.materials["soil"]
    rows = np.flatnonzero(ps["material"][:n] == sim.plan.materials.index("soil"))
    y = ps["x"][rows, 1]
    mix = formulation == "mixture"
    buoyancy = (1.0 - POROSITY) * sc.RHO_W if mix else 0.0
    levels, level_of = np.unique(np.round(y / dx, 6), return_inverse=True)
    order = np.argsort(-levels)  # top row first
    sv_top = ((1.0 - ref["B"]) if mix else 1.0) * ref["q"]
    rho_level = np.full(len(levels), mat.density)
    for _ in range(20):
        sv_level = np.empty(len(levels))
        above = sv_top
        for j in order:  # each row carries the rows above and half of itself
            w = (rho_level[j] - buoyancy) * sc.G * dx
            sv_level[j] = above + 0.5 * w
            above += w
        p_level = sv_level * (1.0 + 2.0 * mat.k0) / 3.0
        new = mat.density * (1.0 + p_level / mat.bulk)  # inverse of seed eq. (17)
        if np.max(np.abs(new - rho_level)) < 1e-12 * mat.density:
            break
        rho_level = new
    sv = sv_level[level_of]
    sh = mat.k0 * sv
    p = (sv + 2.0 * sh) / 3.0
    rho = rho_level[level_of]
    s = np.zeros((len(rows), 6))
    s[:, 0], s[:, 1], s[:, 2] = p - sh, p - sv, p - sh
    for name, value in (("rho", rho), ("stress_dev", s), ("mean_stress", p)):
        for f in (name, name + "_half"):
            if f in ps:
                ps[f][rows] = value
    ps["mass"][rows] = rho * dx**dim
    sim.rebuild()  # the wall images copy mass and the rest of their sources' fields at a rebuild


def water_table_rise(formulation, typical_velocity=V_TYP):
    """B q / gamma_w: the undrained excess pore pressure as a raised water table (both forms start
    from the same pore pressure; the seed has no storage to produce it, see the docstring)."""
    ref = reference(typical_velocity, formulation)
    return ref["u0"] / sc.GAMMA_W


def reference(typical_velocity=V_TYP, formulation="mixture"):
    """q, m_v, K_w, B, u0, c_v, c_v,eff and the time of T_v = 1. q is the load layer's weight per
    area that its skeleton passes on: buoyant in the mixture form, (RHO_LOAD - (1 - n) rho_w) g T,
    dry in the seed's, RHO_LOAD g T."""
    buoyancy = (1.0 - POROSITY) * sc.RHO_W if formulation == "mixture" else 0.0
    q = (RHO_LOAD - buoyancy) * sc.G * T_LOAD
    m_v = 1.0 / an.oedometric_modulus(E, 0.0)
    k_w = an.water_bulk_modulus(10.0 * typical_velocity)
    b = an.skempton_b(m_v, POROSITY, k_w)
    c_eff = an.consolidation_coefficient_eff(K, m_v, POROSITY, k_w)
    return {"q": q, "m_v": m_v, "k_w": k_w, "B": b, "u0": b * q, "c_v": an.consolidation_coefficient(K, m_v),
            "c_eff": c_eff, "t1": H * H / c_eff}  # fmt: skip


def undrained_period(typical_velocity=V_TYP):
    """The period of the column's first undrained mode carrying the load layer: a mass M = the load
    layer's (skeleton and pore water) + a third of the column's on the stiffness (E_oed + K_w / n) / H
    (pore water moving with the skeleton), T_p = 2 pi sqrt(M H / (E_oed + K_w / n)). Terzaghi's
    series is quasi-static: it has no such mode (docstring)."""
    ref = reference(typical_velocity)
    mass = (RHO_LOAD + POROSITY * sc.RHO_W) * T_LOAD + (RHO_COLUMN + POROSITY * sc.RHO_W) * H / 3.0
    return 2.0 * np.pi * np.sqrt(mass * H / (1.0 / ref["m_v"] + ref["k_w"] / POROSITY))


N_WINDOW = 8  # samples per check window, at the midpoints of its eighths (exact for a sinusoid's mean)


def window_times(tv, typical_velocity=V_TYP):
    """The sample times of the check at T_v: one undrained period centred on it (docstring)."""
    t0, tp = tv * reference(typical_velocity)["t1"], undrained_period(typical_velocity)
    return [t0 + tp * ((k + 0.5) / N_WINDOW - 0.5) for k in range(N_WINDOW)]


def run_one(resolution, formulation="mixture", typical_velocity=V_TYP, tv_list=TV_CHECK):
    from solver.simulation import Simulation

    ref = reference(typical_velocity, formulation)
    sim = Simulation(scene(resolution, formulation, typical_velocity, ref["t1"] * max(tv_list) * 1.02))
    initial_state(sim, formulation, typical_velocity)
    dx = H / resolution
    edges = np.arange(0.0, H + 0.5 * dx, 2 * dx)
    yc = 0.5 * (edges[1:] + edges[:-1])

    def observe(s):
        ps = s.particles
        wa = sc.water_rows(s)
        y = ps["x"][wa, 1]
        inside = y < H
        u = ps["p"][wa][inside] - sc.GAMMA_W * (H + T_LOAD - y[inside])
        return sc.bin_profile(y[inside], u, edges)

    # each check is the mean over one undrained period centred on its time, of both u and the series
    windows = {tv: window_times(tv, typical_velocity) for tv in tv_list}
    times = sorted({t for w in windows.values() for t in w})
    obs, wall, cpu = sc.run_timed(sim, times, observe)
    by_time = dict(zip(times, obs))
    out = {"formulation": formulation, "dx": dx, "particles": sim.particles.n_owned, "steps": sim.step_count,
           "wall": wall, "cpu": cpu, "y": yc, "ref": ref, "c": 10 * typical_velocity, "tv": {},
           "windows": windows}  # fmt: skip
    z = (H - yc) / H  # depth below the drained top / H
    for tv in tv_list:
        u = np.nanmean([by_time[t] for t in windows[tv]], axis=0)
        tvs = np.array(windows[tv]) / ref["t1"]
        exact = ref["u0"] * np.mean([an.terzaghi_excess_pore_pressure(z, t) for t in tvs], axis=0)
        tv_cv = ref["c_v"] * tv * ref["t1"] / H**2  # the same instant measured with c_v (incompressible)
        out["tv"][tv] = {
            "u": u, "exact": exact, "error": an.profile_l2_error(u, exact, ref["u0"]),
            "U": 1.0 - float(np.nanmean(u)) / ref["u0"], "U_exact": float(np.mean(an.terzaghi_degree(tvs))),
            "exact_cv": ref["q"] * an.terzaghi_excess_pore_pressure(z, tv_cv),
        }  # fmt: skip
    return out


def run(resolution=DEFAULT_RESOLUTION, out_dir=None):
    runs = {f: run_one(resolution, f) for f in sc.FORMULATIONS}
    mix = runs["mixture"]
    res = CaseResult(
        "seepage_terzaghi", resolution, mix["particles"], sum(r["steps"] for r in runs.values()),
        sum(r["wall"] for r in runs.values()), runs,
    )  # fmt: skip
    for f, r in runs.items():
        for tv, o in r["tv"].items():
            res.checks.append(
                Check(
                    f"{f}: RMS(u - u_series) / u0 at T_v = {tv:g}",
                    o["error"],
                    GOAL,
                    "issue 10 goal (2 %; two-phase MPM 2.3 % at T_v = 0.2); series with c_v,eff and u0 = B q",
                )
            )
    ref = mix["ref"]
    res.notes = [
        f"q = {ref['q']:.0f} Pa, B = {ref['B']:.3f}, u0 = {ref['u0']:.0f} Pa, c_v = {ref['c_v']:.4g}, "
        f"c_v,eff = {ref['c_eff']:.4g} m2/s, t(T_v = 1) = {ref['t1']:.3f} s",
    ] + [
        f"{f}: " + "; ".join(f"T_v {tv:g}: error {o['error']:.4f}, U {o['U']:.3f} (series {o['U_exact']:.3f})"
                             for tv, o in r["tv"].items())
        + f"; {r['steps']} steps, {r['wall']:.1f} s wall, {r['cpu']:.1f} s CPU"
        for f, r in runs.items()
    ]  # fmt: skip
    c_seed = K * ref["k_w"] / (sc.GAMMA_W * POROSITY)
    res.notes.append(
        "seed formulation: no storage term and no pore pressure on the skeleton: started from the same "
        f"u0 = B q, its excess drains by the water's own compressibility (c = k K_w / (gamma_w n) = "
        f"{c_seed / ref['c_eff']:.3g} c_v,eff here) and its skeleton never takes the load over: it cannot "
        "pass; its errors show by how much"
    )
    if out_dir is not None:
        res.figure = figure(runs, Path(out_dir) / f"seepage_terzaghi_r{resolution}.png")
    return res


def figure(runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axs = plt.subplots(1, 3, figsize=(13, 4))
    colours = dict(zip(TV_CHECK, ("C0", "C1", "C2", "C3")))
    for ax, f in zip(axs[:2], ("mixture", "seed")):
        r = runs[f]
        u0 = r["ref"]["u0"]
        for tv, o in r["tv"].items():
            c = colours.get(tv, "k")
            ax.plot(o["u"] / u0, r["y"] / H, "o", color=c, mfc="none", ms=5, label=f"SPH T_v = {tv:g}")
            ax.plot(o["exact"] / u0, r["y"] / H, "-", color=c, lw=1)
            if f == "mixture":
                ax.plot(o["exact_cv"] / u0, r["y"] / H, ":", color=c, lw=1)
        ax.set(xlabel="u / u0", ylabel="y / H", title=f"{f}: lines c_v,eff series; dotted: c_v, u0 = q")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    tv = np.logspace(-2.5, 0.3, 60)
    axs[2].semilogx(tv, an.terzaghi_degree(tv), "k-", label="series")
    for f, m in (("mixture", "bo"), ("seed", "rs")):
        axs[2].semilogx(list(runs[f]["tv"]), [o["U"] for o in runs[f]["tv"].values()], m, mfc="none", label=f)
    axs[2].set(xlabel="T_v (c_v,eff)", ylabel="U = 1 - mean(u) / u0", title="degree of consolidation")
    axs[2].invert_yaxis()
    axs[2].legend(fontsize=7)
    axs[2].grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)


def study(resolutions=STUDY_RESOLUTIONS, out_dir=OUT):
    rows = []
    for res_ in resolutions:
        r = run_one(res_, "mixture")
        row = {"resolution": res_, "dx_mm": 1e3 * r["dx"], "particles": r["particles"], "steps": r["steps"],
               "wall_time_s": r["wall"], "cpu_time_s": r["cpu"], "load_1min": load_1min()}  # fmt: skip
        for tv, o in r["tv"].items():
            row[f"error_tv{tv:g}"] = o["error"]
            row[f"U_tv{tv:g}"] = o["U"]
        rows.append(row)
    note = (
        f"Terzaghi consolidation, mixture form, c = {10 * V_TYP:g} m/s, k = {K:g} m/s: profile error "
        "RMS(u - u_series) / u0 at each T_v (each the mean over one undrained period centred on it, of u "
        f"and of the series alike; goal {GOAL:g}) and U = 1 - mean(u) / u0.\n"
        + timing_note("NUMBA_NUM_THREADS=1 nice -n 10 python -m verification.seepage_terzaghi --study")
    )
    save_study(rows, out_dir, "resolution_study", note)
    return rows


def sound_speed_study(resolution=DEFAULT_RESOLUTION, out_dir=OUT, velocities=(2.0, 4.0, 8.0)):
    """What the water's c costs (issue 10): c = 10 v_typ = 20, 40, 80 m/s: c_v,eff / c_v, steps and
    CPU time to T_v = 1, and the profile errors."""
    rows = []
    for v in velocities:
        r = run_one(resolution, "mixture", v)
        ref = r["ref"]
        row = {"c": 10 * v, "c_eff_over_c_v": ref["c_eff"] / ref["c_v"], "B": ref["B"], "t_tv1_s": ref["t1"],
               "steps": r["steps"], "wall_time_s": r["wall"], "cpu_time_s": r["cpu"]}  # fmt: skip
        for tv, o in r["tv"].items():
            row[f"error_tv{tv:g}"] = o["error"]
        rows.append(row)
    save_study(rows, out_dir, "sound_speed_cost")
    return rows


TAIT_EXPONENT = 7.0  # the water's Tait exponent (seed eq. 9): tangent bulk modulus K = K_w + 7 p


def tangent_series_errors(r):
    """Profile errors of a run_one result against the series with c_v,eff from the Tait water's
    tangent bulk modulus K = K_w + 7 p at the column's mean pressure p = gamma_w (H/2 + T_LOAD) +
    u0 (1 - U), integrated in time (docs/seepage.md, Terzaghi: the tangent-K hypothesis)."""
    ref = r["ref"]
    c_eff = lambda p: K / (sc.GAMMA_W * (ref["m_v"] + POROSITY / (ref["k_w"] + TAIT_EXPONENT * p)))  # noqa: E731
    p_hydro = sc.GAMMA_W * (H / 2 + T_LOAD)
    ts = np.linspace(0.0, max(max(w) for w in r["windows"].values()), 400)
    u_deg = an.terzaghi_degree(np.maximum(ts * ref["c_eff"] / H**2, 1e-9))
    rates = c_eff(p_hydro + ref["u0"] * (1.0 - u_deg))
    tv_t = np.concatenate([[0.0], np.cumsum(0.5 * (rates[1:] + rates[:-1]) * np.diff(ts))]) / H**2
    z = (H - r["y"]) / H
    series = lambda tv: np.mean([an.terzaghi_excess_pore_pressure(z, float(np.interp(t, ts, tv_t)))  # noqa: E731
                                 for t in r["windows"][tv]], axis=0)  # fmt: skip
    return {tv: an.profile_l2_error(o["u"], ref["u0"] * series(tv), ref["u0"]) for tv, o in r["tv"].items()}


def shifted_face_errors(r, shift):
    """Profile errors against the series with the drained face moved by `shift` (m): the
    drained-boundary smearing hypothesis (H_eff = H + shift)."""
    h_eff, ref = H + shift, r["ref"]
    z = np.clip((h_eff - r["y"]) / h_eff, 0.0, None)
    out = {}
    for tv, o in r["tv"].items():
        tvs = [t / ref["t1"] * H**2 / h_eff**2 for t in r["windows"][tv]]  # the check's window, as run_one
        exact = ref["u0"] * np.mean([an.terzaghi_excess_pore_pressure(z, t) for t in tvs], axis=0)
        out[tv] = an.profile_l2_error(o["u"], exact, ref["u0"])
    return out


def hypotheses(resolution=10, typical_velocity=V_TYP, tv_list=(0.05,) + TV_CHECK):
    """The errors at each T_v against the series, the tangent-K series and shifted drained faces
    (`python -m verification.seepage_terzaghi --hypotheses [RESOLUTION] [V_TYP]`)."""
    r = run_one(resolution, "mixture", typical_velocity, tv_list)
    h = 1.3 * H / resolution
    rows = {"series": {tv: o["error"] for tv, o in r["tv"].items()}, "tangent K": tangent_series_errors(r)}
    rows.update({f"face {f:+g} h": shifted_face_errors(r, f * h) for f in (-1.0, -0.5, 0.5, 1.0)})
    rows["U (series)"] = {tv: f"{o['U']:.3f} ({o['U_exact']:.3f})" for tv, o in r["tv"].items()}
    u0 = r["ref"]["u0"]
    rows["u/u0 at the floor (series)"] = {
        tv: f"{o['u'][0] / u0:.3f} ({o['exact'][0] / u0:.3f})" for tv, o in r["tv"].items()
    }
    return r, rows


if __name__ == "__main__":
    import sys

    from .common import case_main

    if "--hypotheses" in sys.argv:
        args = [a for a in sys.argv[1:] if not a.startswith("--")]
        run_, table = hypotheses(int(args[0]) if args else 10, float(args[1]) if len(args) > 1 else V_TYP)
        print(f"dx = {run_['dx'] * 1e3:g} mm, c = {run_['c']:g} m/s: {run_['steps']} steps, ", end="")
        print(f"{run_['cpu']:.1f} s CPU")
        for name, row in table.items():
            print(f"{name:28s}", "  ".join(f"T_v {tv:g}: {v if isinstance(v, str) else f'{100 * v:.1f} %'}"
                                          for tv, v in row.items()))  # fmt: skip
        raise SystemExit(0)
    if "--sound-speed" in sys.argv:
        for row in sound_speed_study():
            print(row)
        raise SystemExit(0)
    raise SystemExit(case_main(sys.modules[__name__]))
