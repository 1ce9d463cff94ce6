"""Closed-form references for the seepage verification cases (issue 10): Darcy flow,
saturated-bed stresses, the critical hydraulic gradient and Terzaghi's 1D consolidation,
including the consolidation coefficient of a bed whose pore water is weakly compressible.

NumPy only; nothing here imports the solver. Units SI: pressures and stresses in Pa
(gauge), lengths in m, k the hydraulic conductivity in m/s, unit weights in N/m3.
Compression positive for effective stresses and excess pore pressures.

Sources (what each formula is, not how it is coded):
  * Darcy's law q = k i; seepage velocity q / n; critical gradient i_c = gamma'/gamma_w
    = (G_s - 1)/(1 + e); effective stress sigma' = sigma - u; upward seepage reduces the
    vertical effective stress by i gamma_w z: Craig's Soil Mechanics (Knappett & Craig,
    8th ed. 2012), ch. 2-3; Terzaghi (1943) Theoretical Soil Mechanics, ch. 12.
  * Terzaghi (1925, 1943) 1D consolidation, single drainage path H:
    u/u0 = sum_m (2/M) sin(M z/H) exp(-M^2 T_v), M = (2m+1) pi/2, T_v = c_v t / H^2;
    U = 1 - sum_m (2/M^2) exp(-M^2 T_v). Craig ch. 7; the same series generated
    the shared reference data's terzaghi_*.csv (copied to verification/data/).
  * Compressible pore water: the storage term of Biot's (1941) consolidation equation
    with incompressible grains, c_v = k / (gamma_w (m_v + n / K_w)) (Verruijt, Theory and
    Problems of Poroelasticity, 2013, ch. 1-2: S = n/K_w + m_v). The undrained response to
    a sudden load q splits it as u0 = B q, B = m_v / (m_v + n/K_w) (Skempton's B for
    incompressible grains); the rest, (1 - B) q, goes to the skeleton at once.
  * m_v = 1/E_oed, E_oed = E (1 - nu) / ((1 + nu)(1 - 2 nu)) (confined modulus).
  * K_w = rho_w c^2: the bulk modulus of a Tait/linear weakly compressible fluid at its
    reference density (dp/drho = c^2).
"""

from __future__ import annotations

import math

import numpy as np

G = 9.81  # m/s2, as the scenes use
RHO_W = 1000.0  # kg/m3


# ----------------------------------------------------------------------------- soil phase relations
def void_ratio(n: float) -> float:
    """e = n / (1 - n)."""
    return n / (1.0 - n)


def porosity(e: float) -> float:
    """n = e / (1 + e)."""
    return e / (1.0 + e)


def bed_densities(rho_s: float, n: float, rho_w: float = RHO_W) -> dict:
    """Densities of a saturated bed from the grain density rho_s (kg/m3) and porosity n.

    dry = (1-n) rho_s (solid mass per bed volume; the 'apparent' soil density of a
    mixture model), water_apparent = n rho_w, saturated = dry + n rho_w,
    buoyant = saturated - rho_w = (1-n)(rho_s - rho_w).
    """
    dry = (1.0 - n) * rho_s
    return {
        "grain": rho_s,
        "dry": dry,
        "water_apparent": n * rho_w,
        "saturated": dry + n * rho_w,
        "buoyant": (1.0 - n) * (rho_s - rho_w),
    }


# ----------------------------------------------------------------------------- Darcy
def darcy_discharge(k: float, i):
    """Specific discharge q = k i (m/s, volume per unit total area per second)."""
    return k * np.asarray(i, dtype=float)


def seepage_velocity(k: float, i, n: float):
    """Mean pore-water velocity relative to the skeleton, v_w - v_s = q / n = k i / n."""
    return darcy_discharge(k, i) / n


def critical_gradient_from_gs(g_s: float, e: float) -> float:
    """i_c = (G_s - 1) / (1 + e) (Craig ch. 3)."""
    return (g_s - 1.0) / (1.0 + e)


def critical_gradient(density: float, n: float, kind: str = "grain", rho_w: float = RHO_W) -> float:
    """i_c = gamma'/gamma_w from a scene's soil density and porosity.

    `kind` says what the scene's density is: "grain" (rho_s of the solid), "dry" (solid mass
    per bed volume, (1-n) rho_s: what a soil SPH particle carries in a mixture model) or
    "saturated" (rho_sat, a one-phase saturated soil). All three give (1-n)(rho_s - rho_w)/rho_w.
    """
    if kind == "grain":
        rho_s = density
    elif kind == "dry":
        rho_s = density / (1.0 - n)
    elif kind == "saturated":
        rho_s = (density - n * rho_w) / (1.0 - n)
    else:
        raise ValueError(f"kind must be grain, dry or saturated, not {kind!r}")
    return bed_densities(rho_s, n, rho_w)["buoyant"] / rho_w


def critical_gradient_without_buoyancy(rho_s: float, n: float, rho_w: float = RHO_W) -> float:
    """The gradient at which the seepage force gamma_w i alone lifts the skeleton's full
    (unbuoyed) weight (1-n) rho_s g: what a model without the pore-pressure term on the
    skeleton predicts when its soil keeps its dry weight (the seed's eqs. 18, 20, 21)."""
    return bed_densities(rho_s, n, rho_w)["dry"] / rho_w


# ----------------------------------------------------------------------------- bed at rest / upward seepage
def saturated_bed_profiles(
    depth,
    rho_s: float,
    n: float,
    water_depth: float = 0.0,
    upward_gradient: float = 0.0,
    rho_w: float = RHO_W,
    g: float = G,
) -> dict:
    """Vertical stresses in a laterally confined saturated bed under `water_depth` of still
    water, at `depth` below the bed surface (m). Gauge pressures (Pa).

    pore: u = gamma_w (water_depth + depth) + i gamma_w depth (an upward gradient i adds
    the excess head that drives the flow); total: sigma_v = gamma_w water_depth +
    gamma_sat depth; effective: sigma'_v = sigma_v - u = (gamma' - i gamma_w) depth.
    With i = 0 this is the bed at rest: sigma'_v = gamma' depth.
    """
    z = np.asarray(depth, dtype=float)
    d = bed_densities(rho_s, n, rho_w)
    gw = rho_w * g
    pore = gw * (water_depth + z) + upward_gradient * gw * z
    total = gw * water_depth + d["saturated"] * g * z
    return {"pore": pore, "total": total, "effective": total - pore}


# ----------------------------------------------------------------------------- consolidation
def oedometric_modulus(e_young: float, nu: float) -> float:
    """E_oed = E (1 - nu) / ((1 + nu)(1 - 2 nu)); m_v = 1 / E_oed."""
    return e_young * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def water_bulk_modulus(c: float, rho_w: float = RHO_W) -> float:
    """K_w = rho_w c^2 (weakly compressible water with sound speed c)."""
    return rho_w * c * c


def consolidation_coefficient(k: float, m_v: float, gamma_w: float = RHO_W * G) -> float:
    """c_v = k / (gamma_w m_v) (incompressible water)."""
    return k / (gamma_w * m_v)


def consolidation_coefficient_eff(
    k: float, m_v: float, n: float, k_w: float, gamma_w: float = RHO_W * G
) -> float:
    """c_v,eff = k / (gamma_w (m_v + n / K_w)) (compressible pore water, rigid grains)."""
    return k / (gamma_w * (m_v + n / k_w))


def skempton_b(m_v: float, n: float, k_w: float) -> float:
    """Share of a sudden load taken by the pore water at once: B = m_v / (m_v + n/K_w)."""
    return m_v / (m_v + n / k_w)


def time_factor(t, c_v: float, h_drain: float):
    """T_v = c_v t / H^2 (H = the drainage path: the layer thickness with one drained face)."""
    return c_v * np.asarray(t, dtype=float) / h_drain**2


def _terms(t_v: float, tail: float = 60.0, minimum: int = 20) -> int:
    """Series terms until exp(-M^2 T_v) < exp(-tail): M > sqrt(tail/T_v)."""
    m_max = math.sqrt(tail / t_v) if t_v > 0 else math.inf
    return max(minimum, int(m_max / math.pi) + 2)


def terzaghi_excess_pore_pressure(z_over_h, t_v: float) -> np.ndarray:
    """u/u0 at depth z/H below the drained face (z/H = 1 at the impermeable base), T_v > 0.

    Truncated once exp(-M^2 T_v) < e^-60, so the remainder is far below double round-off
    relative to u0; not defined at T_v = 0 (u/u0 = 1 inside, 0 at the face).
    """
    if t_v <= 0:
        raise ValueError("T_v must be positive (the series is the step u = u0 at T_v = 0)")
    z = np.atleast_1d(np.asarray(z_over_h, dtype=float))
    m = np.arange(_terms(t_v))
    big_m = (2 * m + 1) * math.pi / 2
    terms = (2.0 / big_m)[None, :] * np.sin(np.outer(z, big_m)) * np.exp(-(big_m**2) * t_v)[None, :]
    return terms.sum(axis=1)


def terzaghi_degree(t_v) -> np.ndarray:
    """Average degree of consolidation U(T_v) = 1 - sum (2/M^2) exp(-M^2 T_v).

    Equal to the settlement fraction and to 1 - mean(u)/u0 over the layer. For T_v > 0
    the series is summed until the exponential has killed the terms (|remainder| < e^-60);
    U(0) = 0.
    """
    tv = np.atleast_1d(np.asarray(t_v, dtype=float))
    out = np.zeros_like(tv)
    for idx, t in enumerate(tv):
        if t <= 0:
            continue
        m = np.arange(_terms(t))
        big_m = (2 * m + 1) * math.pi / 2
        out[idx] = 1.0 - np.sum(2.0 / big_m**2 * np.exp(-(big_m**2) * t))
    return out


def terzaghi_degree_approx(t_v) -> np.ndarray:
    """The textbook fits U = sqrt(4 T_v / pi) (U < 0.6) and 1 - 10^(-(T_v + 0.085)/0.933)
    (Craig ch. 7, after Terzaghi), as in the reference CSV's U_approx column."""
    tv = np.atleast_1d(np.asarray(t_v, dtype=float))
    small = np.sqrt(4.0 * tv / math.pi)
    large = 1.0 - 10.0 ** (-(tv + 0.085) / 0.933)
    return np.where(small < 0.6, small, large)


def profile_l2_error(u_num, u_ref, u0: float) -> float:
    """Pressure-profile error of issue 10: RMS of (u_num - u_ref) over the sample points,
    relative to the initial excess pore pressure u0 (points equally spaced in depth)."""
    d = np.asarray(u_num, dtype=float) - np.asarray(u_ref, dtype=float)
    return float(np.sqrt(np.mean(d * d)) / u0)


# ----------------------------------------------------------------------------- drag stiffness and cost
def drag_relaxation_rate(coeff: float, rho_bar_w: float, rho_bar_s: float) -> float:
    """Decay rate (1/s) of the water-soil relative velocity under a drag per unit mixture
    volume R = coeff (v_w - v_s), each phase having the given mass per mixture volume:
    d(dv)/dt = -coeff (1/rho_bar_w + 1/rho_bar_s) dv.

    Mixture theory (Biot/Prevost): coeff = n^2 gamma_w / k, rho_bar_w = n rho_w,
    rho_bar_s = (1-n) rho_s, so rate = (n g / k)(1 + n rho_w / ((1-n) rho_s)).
    """
    return coeff * (1.0 / rho_bar_w + 1.0 / rho_bar_s)


def terzaghi_cost(
    *,
    height: float,
    dx: float,
    k: float,
    e_young: float,
    nu: float,
    n: float,
    c_water: float,
    rho_s: float,
    width_cells: int = 4,
    t_v_end: float = 1.0,
    h_over_dx: float = 1.3,
    cfl: float = 0.25,
    rho_w: float = RHO_W,
    g: float = G,
) -> dict:
    """What a Terzaghi column of the given parameters costs with the explicit WCSPH step
    dt = cfl h / c_max (seed eq. 28; c_max = max(water c, soil P-wave speed
    sqrt(E_oed / rho_dry))), and the numbers that decide whether it tests the physics.

    `inertia_ratio` = c_v,eff / (H c_max): the wave transit time H/c_max over the
    consolidation time H^2/c_v,eff. Terzaghi's theory neglects inertia, so it must be small
    (steps to T_v = 1 = t_v_end / (inertia_ratio * cfl * h_over_dx) * H/dx).
    """
    e_oed = oedometric_modulus(e_young, nu)
    m_v = 1.0 / e_oed
    k_w = water_bulk_modulus(c_water, rho_w)
    gamma_w = rho_w * g
    cv = consolidation_coefficient(k, m_v, gamma_w)
    cv_eff = consolidation_coefficient_eff(k, m_v, n, k_w, gamma_w)
    dens = bed_densities(rho_s, n, rho_w)
    c_soil = math.sqrt(e_oed / dens["dry"])
    c_max = max(c_water, c_soil)
    dt = cfl * h_over_dx * dx / c_max
    t_end = t_v_end * height**2 / cv_eff
    rate = drag_relaxation_rate(n * n * gamma_w / k, dens["water_apparent"], dens["dry"])
    layers = round(height / dx)
    return {
        "E_oed": e_oed,
        "m_v": m_v,
        "K_w": k_w,
        "c_v": cv,
        "c_v_eff": cv_eff,
        "c_v_eff_over_c_v": cv_eff / cv,
        "B": skempton_b(m_v, n, k_w),
        "c_soil": c_soil,
        "c_max": c_max,
        "dt": dt,
        "t_end": t_end,
        "steps": math.ceil(t_end / dt),
        "inertia_ratio": cv_eff / (height * c_max),
        "drag_rate": rate,
        "drag_rate_dt": rate * dt,
        "particles_soil": layers * width_cells,
        "particles_water_in_bed": layers * width_cells,
    }


# ----------------------------------------------------------------------------- sheet pile (flow net)
