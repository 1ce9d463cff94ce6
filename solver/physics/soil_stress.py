"""Soil stress state: mean stress and the plastic return mapping (seed sec. 2.2; Bui et al. 2008).

  total stress      sigma = -p delta + s                                   seed eq. (12)
  mean stress       p = K (rho/rho0 - 1) (+ K eps_vp, plastic dilation)      seed eq. (17)
  yield             Mohr-Coulomb scale-back sqrt(J2) <= c + p tan(phi)       seed eq. (16)
                    or Drucker-Prager, plane-strain fit, non-associated flow,
                    tension cracking and scale-back                           Bui et al. (2008)
  once yielded      perfectly plastic (the above), or mu(I): the friction     Jop, Forterre & Pouliquen
                    rises with the inertial number, + (mu_2 - mu_s) I/(I+I_0)  (2006); GDR MiDi (2004)
                    times p, I = gamma_dot d50 / sqrt(p / rho_grain)          (docs/rheology.md)

Pressure p is positive in compression. Stress tensors are 6 components (solver/tensors.py);
2D is plane strain (s_zz is kept and evolves). Two terms: the state at step n before the pair
passes (SoilStressState), and the return mapping of the half-step stress after the kick, which
also accumulates the plastic dilation (SoilReturnMapping).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..materials import Phase, YieldModel
from ..particles import FieldSpec, Mirror
from ..tensors import N_SYM
from ..term import Equation, Stage, Term
from ..timestep import Constraint
from .erodible import erosion_materials
from .sand_state import plane_strain_return, relative_dilatancy_index, state_angles, state_constants
from .soil_rates import SHEAR_RATE  # the field SoilRates writes for mu(I) soils

MOHR_COULOMB = int(YieldModel.MOHR_COULOMB)  # plain ints: compile-time constants in the kernels
DRUCKER_PRAGER = int(YieldModel.DRUCKER_PRAGER)

STRESS_FIELDS = {
    "stress_dev": FieldSpec(
        N_SYM, np.float64, "soil deviatoric stress s at step n (eqs. 12-13)", Mirror.TENSOR
    ),
    "mean_stress": FieldSpec(
        0, np.float64, "soil mean stress p, compression positive (eq. 17)", Mirror.SCALAR
    ),
}
EPS_VP = FieldSpec(0, np.float64, "plastic volumetric strain (tension cracking, dilatancy psi)")


@kernel
def sqrt_j2(s0, s1, s2, s3, s4, s5):
    """sqrt(J2) = sqrt(s:s / 2) for a deviatoric tensor in 6 components."""
    return np.sqrt(0.5 * (s0 * s0 + s1 * s1 + s2 * s2) + s3 * s3 + s4 * s4 + s5 * s5)


@kernel
def _scaled(r, s0, s1, s2, s3, s4, s5):
    """Radial scale-back of the deviatoric stress by r (seed eq. 16; Bui et al. 2008)."""
    return r * s0, r * s1, r * s2, r * s3, r * s4, r * s5


@kernel
def rate_friction(p, shear_rate, friction_increment, i0, grain_inertia):
    """mu(I) - mu_s = (mu_2 - mu_s) / (I_0 / I + 1) = (mu_2 - mu_s) I / (I + I_0) (Jop, Forterre & Pouliquen
    2006), I = gamma_dot d50 / sqrt(p / rho_grain) (GDR MiDi 2004), with grain_inertia = d50 sqrt(rho_grain):
    I sqrt(p) = gamma_dot grain_inertia, so the ratio needs no division by p. Zero without confinement
    (p <= 0: the friction law has no strength to raise), at rest, and for a perfectly plastic soil
    (friction_increment = 0)."""
    if friction_increment <= 0.0 or p <= 0.0 or shear_rate <= 0.0:
        return 0.0
    a = shear_rate * grain_inertia
    return friction_increment * a / (a + i0 * np.sqrt(p))


@kernel
def return_map(
    p, s0, s1, s2, s3, s4, s5, model, bulk, shear, tan_phi, cohesion, alpha_phi, k_c, alpha_psi,
    friction_increment=0.0, i0=1.0, grain_inertia=0.0, shear_rate=0.0,
):  # fmt: skip
    """Admissible (p, s) from a trial state; returns (p, s0..s5, dvol, dcrack): dvol the plastic
    volumetric strain increment (dilation positive), dcrack the part of it that is tension cracking.

    The volumetric increment is what keeps p = K (rho/rho0 - 1 + eps_vp) incremental: a cracked
    (stretched) particle restarts from the cut-off when recompressed, as in the rate form
    dsigma/dt = K tr(eps) delta + ... of Bui et al. (2008), instead of carrying a tensile deficit
    that makes loosened soil flow like a zero-pressure fluid. soil_stress_state puts the cracking
    part into the density, not into eps_vp (see there).
    Mohr-Coulomb (seed eq. 16): tension cut-off p >= -c / tan(phi) (no tensile strength of a
    cohesionless soil), then s scaled by s_f / sqrt(J2) when sqrt(J2) > s_f = c + p tan(phi).
    Drucker-Prager (Bui et al. 2008, f = alpha_phi I1 + sqrt(J2) - k_c, I1 = -3p):
      tension cracking: p < -k_c / (3 alpha_phi) (beyond the apex) -> apex, s = 0;
      otherwise f > 0 -> plastic multiplier dl = f / (G + 9 K alpha_phi alpha_psi) of the
      non-associated potential g = alpha_psi I1 + sqrt(J2): sqrt(J2) -= G dl, p += 3 K alpha_psi dl
      (plastic dilation 3 alpha_psi dl raises p in a confined state); lands on f = 0 exactly.
    mu(I) (friction_increment > 0; docs/rheology.md): the admissible sqrt(J2) of either surface gains
    mu_r p, mu_r = rate_friction(p, shear_rate, ...) = mu(I) - mu_s, at the shear rate of the last rates
    pass: the rate-dependent yield surface of a consistency viscoplasticity (Wang, Sluys & de Borst
    1997), which makes the steady simple shear of a yielded soil sqrt(J2) = (mu_s + mu_r) p + c, the
    local mu(I) law (Jop et al. 2006) with mu_s the yield model's static friction (tan(phi), or
    3 alpha_phi for the Drucker-Prager fit). Below the static surface nothing changes: the skeleton
    stays elastic. mu_r is held at its trial-p value during the Drucker-Prager return, so the
    multiplier dl = f / (G + 9 K alpha_phi alpha_psi + 3 K alpha_psi mu_r) still lands on the raised
    f = 0 (the dilation raises p, and with it both frictions).
    """
    dvol = 0.0
    dcrack = 0.0
    if model == MOHR_COULOMB:
        if tan_phi > 0.0 and p < -cohesion / tan_phi:
            dvol = dcrack = (-cohesion / tan_phi - p) / bulk
            p = -cohesion / tan_phi
        sf = max(cohesion + p * tan_phi, 0.0)
        mu_r = rate_friction(p, shear_rate, friction_increment, i0, grain_inertia)
        if mu_r > 0.0:
            sf += mu_r * p
        j = sqrt_j2(s0, s1, s2, s3, s4, s5)
        if j > sf:
            s0, s1, s2, s3, s4, s5 = _scaled(sf / j, s0, s1, s2, s3, s4, s5)
    elif model == DRUCKER_PRAGER:
        p_apex = -k_c / (3.0 * alpha_phi) if alpha_phi > 0.0 else -1e300
        if p < p_apex:
            dvol = dcrack = (p_apex - p) / bulk
            p = p_apex
            s0 = s1 = s2 = s3 = s4 = s5 = 0.0
        else:
            j = sqrt_j2(s0, s1, s2, s3, s4, s5)
            f = j - k_c - 3.0 * alpha_phi * p
            stiffness = shear + 9.0 * bulk * alpha_phi * alpha_psi
            mu_r = rate_friction(p, shear_rate, friction_increment, i0, grain_inertia)
            if mu_r > 0.0:  # a branch, not a sum with 0: the perfectly plastic return stays bit for bit
                f -= mu_r * p
                stiffness += 3.0 * bulk * alpha_psi * mu_r
            if f > 0.0:
                dl = f / stiffness
                p += 3.0 * bulk * alpha_psi * dl
                dvol = 3.0 * alpha_psi * dl
                s0, s1, s2, s3, s4, s5 = _scaled(max(j - shear * dl, 0.0) / j, s0, s1, s2, s3, s4, s5)
    return p, s0, s1, s2, s3, s4, s5, dvol, dcrack


@kernel(parallel=True)
def soil_stress_state(
    rows,
    rho,
    s,
    material,
    rho0,
    bulk,
    shear,
    tan_phi,
    cohesion,
    alpha_phi,
    k_c,
    alpha_psi,
    yield_model,
    mean_stress,
    eps_vp=None,
    update_history=False,
    suspended=None,
    rate=None,
    state=None,
):
    """For each row: p from eq. (17) (with the stored plastic dilation, if any), then the
    return mapping; writes p to mean_stress and the admissible s in place. With
    update_history (after the leap-frog kick, on the half-step density) the plastic dilation
    (psi) is accumulated in eps_vp, and tension cracking resets the density instead:
        rho <- rho + rho0 dcrack,   i.e. rho = rho0 (1 + p_cut / K - eps_vp),
    the density at which eq. (17) gives the cut-off pressure p_cut. A crack opens between
    particles; the material keeps the density of its stress-free (cut-off) state. Carried in
    eps_vp instead (as before issue 14), the crack opening let a detached grain's density fall
    without bound: continuity (seed eq. 6) keeps lowering it while neighbours recede, and the
    cut-off keeps p = p_cut whatever rho is. At rho -> 0 the particle's volume m/rho and
    sigma/rho^2 grow without bound, and at rho_i + rho_j < 0 the artificial viscosity
    (eq. 19, 2 / (rho_i + rho_j)) pulls a particle into its image instead of resisting: the
    issue-14 column collapses ended so. p evolves exactly as before (continuity's rate does not
    depend on rho_i); only the density used as a volume and in eqs. (19), (20) changes.
    suspended (erosion, solver/physics/shields_pickup.py; None without): soil the flow has picked up
    has no shear strength, s = 0, and keeps p.
    rate (mu(I), None without: the perfectly plastic return of the seed): the tuple (friction_increment,
    inertial_number_i0, grain_inertia) per material and the shear rate per row (SoilRates).
    state (a sand with a state, None without: the constant cone of the material): the per-material
    constants of solver/physics/sand_state.py; the cone follows the void ratio (1 + e0) exp(eps_vp) - 1
    (the grains' rearrangement, not the elastic strain of a skeleton softer than sand) and the trial p'."""
    for t in prange(rows.shape[0]):
        i = rows[t]
        m = material[i]
        e = rho[i] / rho0[m] - 1.0
        if eps_vp is not None:
            e += eps_vp[i]
        d_mu, i0, inertia, rate_i = 0.0, 1.0, 0.0, 0.0
        if rate is not None and (suspended is None or suspended[i] == 0):  # suspended soil: no rheology
            d_mu, i0, inertia, rate_i = rate[0][m], rate[1][m], rate[2][m], rate[3][i]
        if state is not None and eps_vp is not None and state[2][m] > 0.0:  # e_max > 0: a sand with a state
            void = (1.0 + state[0][m]) * np.exp(eps_vp[i]) - 1.0  # de / (1 + e) = d eps_vp (docs/sand.md)
            i_r = relative_dilatancy_index(
                void, bulk[m] * e, state[1][m], state[2][m], state[3][m], state[4][m], state[5][m],
                state[6][m], state[7][m],
            )  # fmt: skip
            sin_phi, sin_psi = state_angles(i_r, state[8][m])
            p, a0, a1, a2, a3, a4, a5, dvol, dcrack = plane_strain_return(
                bulk[m] * e, s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5], sin_phi, sin_psi,
                cohesion[m], bulk[m], shear[m],
            )  # fmt: skip
        else:
            p, a0, a1, a2, a3, a4, a5, dvol, dcrack = return_map(
                bulk[m] * e, s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5], yield_model[m], bulk[m],
                shear[m], tan_phi[m], cohesion[m], alpha_phi[m], k_c[m], alpha_psi[m], d_mu, i0, inertia,
                rate_i,
            )  # fmt: skip
        mean_stress[i] = p
        if suspended is not None and suspended[i] != 0:
            a0 = a1 = a2 = a3 = a4 = a5 = 0.0
        s[i, 0] = a0
        s[i, 1] = a1
        s[i, 2] = a2
        s[i, 3] = a3
        s[i, 4] = a4
        s[i, 5] = a5
        if eps_vp is not None and update_history:
            if dcrack != 0.0:  # tension cracking (dvol = dcrack): back to the cut-off density
                rho[i] += rho0[m] * dcrack
            else:  # plastic dilatancy (psi)
                eps_vp[i] += dvol


def yield_excess(rows, mean_stress, s, material, soil, shear_rate=None):
    """f / (scale) for the given rows: > 0 means outside the yield surface (NumPy; diagnostics, tests).
    With shear_rate (mu(I) soils), the surface raised by mu(I) - mu_s at that rate (rate_friction)."""
    m = material[rows]
    p = mean_stress[rows]
    ss = s[rows]
    j = np.sqrt(
        0.5 * (ss[:, 0] ** 2 + ss[:, 1] ** 2 + ss[:, 2] ** 2) + ss[:, 3] ** 2 + ss[:, 4] ** 2 + ss[:, 5] ** 2
    )
    model = soil.yield_model[m]
    limit = np.where(
        model == YieldModel.DRUCKER_PRAGER,
        soil.k_c[m] + 3.0 * soil.alpha_phi[m] * p,
        soil.cohesion[m] + soil.tan_phi[m] * p,
    )
    if shear_rate is not None:
        a = shear_rate[rows] * soil.grain_inertia[m]
        root = soil.inertial_number_i0[m] * np.sqrt(np.maximum(p, 0.0))
        flowing = (p > 0) & (a > 0) & (soil.friction_increment[m] > 0)
        mu_r = np.where(flowing, soil.friction_increment[m] * a / np.where(flowing, a + root, 1.0), 0.0)
        limit = limit + mu_r * p
    scale = np.maximum(np.abs(p), 1.0) * np.maximum(soil.tan_phi[m], 1e-3) + soil.cohesion[m]
    return np.where(model == YieldModel.ELASTIC, -1.0, (j - limit) / scale)


class Constitution:
    """The per-material constants of eqs. (16)-(17), applied to the owned soil rows."""

    def __init__(self, materials, erodes=False):
        s = materials.soil
        self.erodes = erodes  # suspended soil has no shear strength (shields_pickup.py)
        self.rho0 = materials.rho0
        self.constants = (
            s.bulk,
            s.shear,
            s.tan_phi,
            s.cohesion,
            s.alpha_phi,
            s.k_c,
            s.alpha_psi,
            s.yield_model,
        )
        soil = materials.ids_of_phase(Phase.SOIL)
        self.plastic = any(s.yield_model[k] != YieldModel.ELASTIC for k in soil)
        self.rate_dependent = s.rate_dependent  # mu(I): the shear rate of SoilRates raises the surface
        self.rate_constants = (s.friction_increment, s.inertial_number_i0, s.grain_inertia)
        self.state = state_constants(s)  # a sand with a state: its cone follows e and p' (None: constant)

    def apply(self, ctx, rho, stress, update_history):
        """p from rho (eq. 17) and the return mapping of `stress`, in place."""
        ps = ctx.particles
        rate = (*self.rate_constants, ps[SHEAR_RATE]) if self.rate_dependent else None
        soil_stress_state(
            ctx.rows[Phase.SOIL].view(np.uint64),  # unsigned: no negative-index wrap-around (6 % of the pass)
            ps[rho],
            ps[stress],
            ps["material"],
            self.rho0,
            *self.constants,
            ps["mean_stress"],
            ps["eps_vp"] if self.plastic else None,
            update_history,
            ps["suspended"] if self.erodes else None,
            rate,
            self.state,
        )


def mu_i_equations(constitution):
    if not constitution.rate_dependent:
        return ()
    return (
        Equation(
            "mu(I) once yielded: sqrt(J2) <= static + (mu_2 - mu_s) I / (I + I_0) p",
            "Jop, Forterre & Pouliquen (2006); GDR MiDi (2004)",
        ),
    )


def state_equations(constitution):
    if constitution.state is None:
        return ()
    return (
        Equation(
            "a sand's state: critical line e_c(p'), I_R = (e_c - e)(Q - ln p') / (e_max - e_min), "
            "phi = phi_cv + 5 I_R, psi = 5 I_R / 0.8 (docs/sand.md)",
            "Li & Wang (1998); Been & Jefferies (1985); Bolton (1986)",
        ),
    )


def mu_i_lines(constitution, names):
    """--explain: each mu(I) soil's mu_2 - mu_s, I_0 and d50 sqrt(rho_grain)."""
    d_mu, i0, inertia = constitution.rate_constants
    return [
        f"mu(I) {names[k]}: mu_2 - mu_s = {d_mu[k]:g}, I_0 = {i0[k]:g}, d50 sqrt(rho_grain) = "
        f"{inertia[k]:.4g} m (kg/m^3)^0.5"
        for k in range(len(names))
        if d_mu[k] > 0.0
    ]


class SoilStressState(Term):
    """p (eq. 17) and the admissible s of every owned soil particle from the state at step n."""

    name = "soil stress state"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if materials.has_phase(Phase.SOIL) else None

    def __init__(self, scene, materials):
        super().__init__()
        self.constitution = Constitution(materials, bool(erosion_materials(scene, materials)))
        self.names = materials.names
        self.fields = dict(STRESS_FIELDS)
        if self.constitution.plastic:
            self.fields["eps_vp"] = EPS_VP
        self.writes = ("mean_stress", "stress_dev")
        c_max = float(materials.sound_speed[materials.ids_of_phase(Phase.SOIL)].max())
        self.dt_limit = Constraint(
            "soil sound",
            "seed eq. (28), c = sqrt((K + 4G/3) / rho0)",
            scene.numerics.cfl.sound * scene.h / c_max,
        )
        self.equations = (
            (
                Equation("mean stress", "seed eq. (17)"),
                Equation("return mapping", "seed eq. (16) Mohr-Coulomb / Bui et al. (2008) Drucker-Prager"),
            )
            + mu_i_equations(self.constitution)
            + state_equations(self.constitution)
        )

    def explain(self):
        return mu_i_lines(self.constitution, self.names)

    def run(self, ctx):
        self.constitution.apply(ctx, "rho", "stress_dev", False)

    def derive(self, ctx):
        self.constitution.apply(ctx, "rho", "stress_dev", False)


class SoilReturnMapping(Term):
    """The plastic return mapping of the new half-step stress, accumulating plastic dilation."""

    name = "soil return mapping"
    stage = Stage.AFTER_KICK

    @classmethod
    def build(cls, scene, materials):
        if not materials.has_phase(Phase.SOIL):
            return None
        return cls(materials, bool(erosion_materials(scene, materials)))

    def __init__(self, materials, erodes=False):
        super().__init__()
        self.constitution = Constitution(materials, erodes)
        # tension cracking resets the half-step density (soil_stress_state)
        self.writes = ("stress_dev_half", "mean_stress") + (
            ("eps_vp", "rho_half") if self.constitution.plastic else ()
        )
        self.equations = (
            (Equation("return mapping of s at n+1/2", "seed eqs. (16), (27); Bui et al. (2008)"),)
            + mu_i_equations(self.constitution)
            + state_equations(self.constitution)
        )

    def run(self, ctx):
        self.constitution.apply(ctx, "rho_half", "stress_dev_half", True)
