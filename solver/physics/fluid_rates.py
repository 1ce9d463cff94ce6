"""Water rates from water neighbours, exactly the terms of the seed paper, fused in one pass:

  continuity        seed eq. (6)
  momentum          seed eq. (7), sigma = -p delta + tau (8)
  artificial visc.  seed eq. (19), Monaghan (1992) form with beta phi^2 (erratum)
  XSPH              seed eq. (22)
Optional terms are optional arguments: passing None removes the term at compile time
(Numba prunes `is None` branches before typing), so an absent term costs nothing. The loop is
a gather over a target's neighbour row: each target writes only its own rates, so it runs in
parallel without races. Accumulators are scalars (no per-particle allocation) and z
components are guarded by `is3d is not None`, so the 2D specialisation has no z code at all.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import PORE_LABEL, RHO_HALF
from ..kernels import cubic_spline_dwdr, cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec
from ..scene import Leapfrog
from ..term import Equation, Integrated, Stage, Term
from .density_diffusion import pore_field
from .pore_pressure_gradient import corrected_weight, solve_m
from .tait_eos import saturated_mixture
from .viscous_stress import viscous_stress_on


@kernel(parallel=True)
def fluid_rates(
    targets, start, index, x, v, rho, p, mass, material, sound_speed, h, norm,
    drho, acc,
    tau=None,                      # viscous stress: eq. (7)-(8) with (10)
    av_alpha=None, av_beta=None,   # artificial viscosity per material: eq. (19)
    xsph=None, xsph_eps=0.0,       # XSPH velocity correction out: eq. (22)
    is3d=None,                     # None in 2D: every z term is pruned at compile time
    mixed=None,                    # None when the phase has one material: no per-pair look-ups
    apparent=None,                 # not None: the density-jump forms (pore water, docs/seepage.md)
    pore=None,                     # pore field (< 1: pore water): pressure by the corrected difference form
):  # fmt: skip
    """Continuity (6) and momentum (7) for each target; adds into drho and acc.

    With `apparent` (water of apparent density n rho_w in pores next to free water), the forms that
    stay consistent across a jump of density at a continuous pressure (Colagrossi & Landrini 2003):
    drho_i = rho_i sum_j V_j v_ij . grad W and -sum_j m_j (p_i + p_j) / (rho_i rho_j) grad W (and
    the same for tau), instead of eqs. (6)-(7), whose m_j p_i / rho_i^2 weighs a neighbour of
    another density wrongly.

    With `pore` (numerics.pore_pressure_gradient = "corrected"), targets with pore[i] < 1 (pore water)
    take the pressure part as -(1 / rho_i) M_i^-1 sum_j V_j (p_j - p_i) grad_i W_ij instead
    (pore_pressure_gradient.py: exact for a linear pressure, not pairwise momentum-conserving), blended
    to the symmetric form where their water support is cut; every other part is unchanged.

    A neighbour's x and v are read from flat views at j * dim + column, dim a compile-time
    constant: a 2D array's row stride is a run-time value (as in soil_rates.py)."""
    dim = 3 if is3d is not None else 2
    if x.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("fluid_rates: x and v must have 3 columns with is3d=True, 2 without")
    xflat = x.reshape(x.size)  # not vf/xf: the corrected pore branch has a scalar vf
    vflat = v.reshape(v.size)
    hh = 0.01 * h * h
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        rho_i = rho[i]
        ri2 = 1.0 / (rho_i * rho_i)
        pi_r2 = p[i] * ri2
        mi = material[i]
        c_bar, alpha, beta = 0.0, 0.0, 0.0
        if av_alpha is not None:
            c_bar, alpha, beta = sound_speed[mi], av_alpha[mi], av_beta[mi]
        d_rho = 0.0
        a0 = a1 = a2 = 0.0
        x0 = x1 = x2 = 0.0
        corrected = False
        if pore is not None:
            corrected = pore[i] < 1.0
        sp0 = sp1 = sp2 = g0 = g1 = g2 = den = 0.0  # corrected pore water only
        if pore is not None and corrected:
            den = mass[i] / rho_i * cubic_spline_w(0.0, h, norm)  # the lists hold no self pair
        m0 = m1 = m2 = m3 = m4 = m5 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            xj = j * dim
            d0 = xi0 - xflat[xj]
            d1 = xi1 - xflat[xj + 1]
            u0 = vi0 - vflat[xj]
            u1 = vi1 - vflat[xj + 1]
            d2 = u2 = 0.0
            if is3d is not None:
                d2 = xi2 - xflat[xj + 2]
                u2 = vi2 - vflat[xj + 2]
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            r = np.sqrt(r2) + 1e-300
            vr = u0 * d0 + u1 * d1 + u2 * d2
            fr = cubic_spline_dwdr(r, h, norm) / r  # grad_i W_ij = fr x_ij
            m_j = mass[j]
            rho_j = rho[j]
            rj2 = 1.0 / (rho_j * rho_j)
            if drho is not None:
                if apparent is not None:
                    d_rho += m_j / rho_j * vr * fr  # times rho_i after the loop
                else:
                    d_rho += m_j * vr * fr  # eq. (6)
            if apparent is not None:
                coef = -(p[i] + p[j]) / (rho_i * rho_j)
            else:
                coef = -(pi_r2 + p[j] * rj2)  # eq. (7): sigma = -p delta
            if pore is not None and corrected:  # the pressure part summed apart, in both forms
                sym = coef * m_j * fr
                sp0 += sym * d0
                sp1 += sym * d1
                sp2 += sym * d2
                coef = 0.0
                v_j = m_j / rho_j
                vf = v_j * fr * (p[j] - p[i])
                g0 += vf * d0  # sum_j V_j (p_j - p_i) grad_i W_ij, grad_i W_ij = fr x_ij
                g1 += vf * d1
                g2 += vf * d2
                vf = v_j * fr
                m0 -= vf * d0 * d0  # M = -sum_j V_j fr x_ij (x) x_ij
                m1 -= vf * d1 * d1
                m3 -= vf * d0 * d1
                if is3d is not None:
                    m2 -= vf * d2 * d2
                    m4 -= vf * d1 * d2
                    m5 -= vf * d0 * d2
                den += v_j * cubic_spline_w(r, h, norm)
            if av_alpha is not None:  # eq. (19), branch-free: zero unless vr < 0
                if mixed is not None:  # pair means of c, alpha, beta
                    mj = material[j]
                    c_bar = 0.5 * (sound_speed[mi] + sound_speed[mj])
                    alpha = 0.5 * (av_alpha[mi] + av_alpha[mj])
                    beta = 0.5 * (av_beta[mi] + av_beta[mj])
                phi = h * min(vr, 0.0) / (r2 + hh)
                coef -= (-alpha * c_bar * phi + beta * phi * phi) * 2.0 / (rho_i + rho_j)
            coef *= m_j * fr
            a0 += coef * d0
            a1 += coef * d1
            a2 += coef * d2
            if tau is not None:  # eq. (7): + (tau_i/rho_i^2 + tau_j/rho_j^2) . grad W
                fm = m_j * fr
                wi, wj = ri2, rj2
                if apparent is not None:
                    wi = wj = 1.0 / (rho_i * rho_j)
                s00 = tau[i, 0] * wi + tau[j, 0] * wj
                s11 = tau[i, 1] * wi + tau[j, 1] * wj
                s01 = tau[i, 3] * wi + tau[j, 3] * wj
                if is3d is not None:
                    s22 = tau[i, 2] * wi + tau[j, 2] * wj
                    s12 = tau[i, 4] * wi + tau[j, 4] * wj
                    s02 = tau[i, 5] * wi + tau[j, 5] * wj
                    a0 += fm * (s00 * d0 + s01 * d1 + s02 * d2)
                    a1 += fm * (s01 * d0 + s11 * d1 + s12 * d2)
                    a2 += fm * (s02 * d0 + s12 * d1 + s22 * d2)
                else:
                    a0 += fm * (s00 * d0 + s01 * d1)
                    a1 += fm * (s01 * d0 + s11 * d1)
            if xsph is not None:  # eq. (22): -eps sum_j (m_j/rho_j) v_ij W_ij
                w = xsph_eps * cubic_spline_w(r, h, norm) * m_j / rho_j
                x0 -= w * u0
                x1 -= w * u1
                x2 -= w * u2
        if drho is not None:
            if apparent is not None:
                d_rho *= rho_i
            drho[i] += d_rho
        if pore is not None and corrected:
            det, q0, q1, q2 = solve_m(m0, m1, m2, m3, m4, m5, g0, g1, g2, is3d)
            wc = corrected_weight(den, det)
            a0 += (1.0 - wc) * sp0 - wc * q0 / rho_i
            a1 += (1.0 - wc) * sp1 - wc * q1 / rho_i
            a2 += (1.0 - wc) * sp2 - wc * q2 / rho_i
        acc[i, 0] += a0
        acc[i, 1] += a1
        if is3d is not None:
            acc[i, 2] += a2
        if xsph is not None:
            xsph[i, 0] = x0
            xsph[i, 1] = x1
            if is3d is not None:
                xsph[i, 2] = x2


class FluidRates(Term):
    """Continuity, pressure gradient, viscous stress divergence, AV and XSPH of water."""

    name = "fluid rates"
    stage = Stage.RATES
    targets = Phase.WATER
    neighbours = Phase.WATER
    # continuity, AV and XSPH read the free-slip image velocity across no-slip walls; the shear reaches
    # the wall through tau, built from the no-slip velocity (viscous_stress.py; Adami et al. 2012)
    slip_image_velocity = True

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if materials.has_phase(Phase.WATER) else None

    def __init__(self, scene, materials):
        super().__init__()
        num = scene.numerics
        water = materials.ids_of_phase(Phase.WATER)
        self.sound_speed = materials.sound_speed
        # with the midpoint-density leap-frog, continuity runs after the drift (midpoint_continuity.py)
        self.continuity = num.leapfrog == Leapfrog.SEED
        self.viscous = viscous_stress_on(scene, materials)
        av = any(materials.av_alpha[k] > 0 or materials.av_beta[k] > 0 for k in water)
        self.av_alpha = materials.av_alpha if av else None
        self.av_beta = materials.av_beta if av else None
        self.xsph_eps = num.xsph_epsilon
        self.mixed = True if len(water) > 1 else None  # per-pair material look-ups only if needed
        self.apparent = True if saturated_mixture(scene) else None  # pore water next to free water
        # numerics.pore_pressure_gradient = "corrected": the pore water's pressure by the corrected
        # difference form (pore_pressure_gradient.py); the field that marks pore water, or None
        self.pore = pore_field(scene) if num.pore_pressure_gradient == "corrected" else None
        self.reads = (
            ("x", "v", "rho", "p", "mass")
            + (("tau",) if self.viscous else ())
            + (("material",) if self.mixed else ())
            + ((self.pore,) if self.pore else ())
        )
        if self.pore == "pore_label":
            self.fields["pore_label"] = PORE_LABEL
        self.adds_to = ("acc",) + (("drho",) if self.continuity else ())
        equations = [Equation("pressure gradient", "seed eqs. (7)-(9)")]
        if self.pore:
            equations.append(
                Equation(
                    "pore water: -(1/rho_i) M_i^-1 sum_j V_j (p_j - p_i) grad W_ij, "
                    "M_i = sum_j V_j grad W_ij (x) x_ji (not pairwise momentum-conserving)",
                    "Randles & Libersky (1996); Bonet & Lok (1999)",
                )
            )
        if self.continuity:
            self.fields["rho_half"] = RHO_HALF
            self.integrates = (Integrated("rho", "rho_half", "drho"),)
            equations.insert(0, Equation("continuity", "seed eq. (6)"))
        if self.viscous:
            equations.append(Equation("viscous stress divergence", "seed eqs. (7), (8), (10)"))
        if av:
            equations.append(
                Equation("Monaghan artificial viscosity", "seed eq. (19), erratum: + beta phi^2")
            )
        if self.xsph_eps > 0:
            self.fields["xsph"] = FieldSpec(scene.dim, np.float64, "XSPH correction (eq. 22)")
            self.writes = ("xsph",)
            self.position_correction = "xsph"
            equations.append(Equation("XSPH", "seed eq. (22)"))
        self.equations = tuple(equations)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        v = ctx.image_velocity(self, "v")
        start, index = nl.unsigned()  # no negative-index wrap-around per neighbour gather
        fluid_rates(
            nl.targets, start, index, ps["x"], v, ps["rho"], ps["p"], ps["mass"], ps["material"],
            self.sound_speed, ctx.h, ctx.norm, ps["drho"] if self.continuity else None, ps["acc"],
            ps["tau"] if self.viscous else None, self.av_alpha, self.av_beta,
            ps["xsph"] if self.xsph_eps > 0 else None, self.xsph_eps, ctx.is3d, self.mixed, self.apparent,
            ps[self.pore] if self.pore else None,
        )  # fmt: skip
