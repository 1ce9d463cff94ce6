"""Soil rates from soil neighbours (seed sec. 2.2, 2.4), fused in one pass:

continuity        over soil neighbours                                     seed eq. (6)
momentum          sigma = -p delta + s, eq. (20) without seepage            seed eqs. (12), (20)
artificial visc.  Monaghan, alpha = beta = 1 for soil                       seed eq. (19)
deviatoric rate   ds/dt = 2G (eps') + s R^T + R s  (Jaumann)               seed eqs. (13)-(15)
shear rate        gamma_dot = sqrt(2 eps':eps'), for mu(I) soils only        Jop et al. (2006)
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import RHO_HALF
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..particles import FieldSpec
from ..tensors import N_SYM
from ..term import Equation, Integrated, Stage, Term
from . import velocity_gradient
from .erodible import erosion_materials


@kernel
def jaumann(s0, s1, s2, s3, s4, s5, w01, w02, w12):
    """J = W s - s W (= s^{ag} R^{bg} + s^{gb} R^{ag} of seed eq. 13 with R antisymmetric),
    components (xx, yy, zz, xy, yz, xz); W_ab = (dv^a/dx^b - dv^b/dx^a)/2 (eq. 15)."""
    j00 = 2.0 * (w01 * s3 + w02 * s5)
    j11 = 2.0 * (w12 * s4 - w01 * s3)
    j22 = -2.0 * (w02 * s5 + w12 * s4)
    j01 = w01 * (s1 - s0) + w02 * s4 + w12 * s5
    j12 = w12 * (s2 - s1) - w01 * s5 - w02 * s3
    j02 = w02 * (s2 - s0) + w01 * s4 - w12 * s3
    return j00, j11, j22, j01, j12, j02


SHEAR_RATE = "shear_rate"
SHEAR_RATE_FIELD = FieldSpec(0, np.float64, "shear rate sqrt(2 eps':eps') of a mu(I) soil (1/s)")

# columns of the per-row table that soil_pair_terms prepares for the pair loop
Q00, Q11, Q01, VOL, MASS, Q22, Q12, Q02 = range(8)
PAIR_COLUMNS = 8


@kernel(parallel=True)
def soil_pair_terms(n, rho, mean_stress, s, mass, out):
    """What the pair loop reads of a neighbour j, once per row instead of once per pair, packed in
    one row of `out` (one cache line instead of five gathers; two divisions per pair less):
    sigma_j / rho_j^2 (eq. 12; columns Q00, Q11, Q01 and in 3D Q22, Q12, Q02), m_j / rho_j (VOL)
    and m_j (MASS). For the first n rows (owned, ghosts and images: every row a list can name)."""
    for j in prange(n):
        rj2 = 1.0 / (rho[j] * rho[j])
        pj = mean_stress[j]
        out[j, Q00] = (s[j, 0] - pj) * rj2
        out[j, Q11] = (s[j, 1] - pj) * rj2
        out[j, Q22] = (s[j, 2] - pj) * rj2
        out[j, Q01] = s[j, 3] * rj2
        out[j, Q12] = s[j, 4] * rj2
        out[j, Q02] = s[j, 5] * rj2
        out[j, VOL] = mass[j] / rho[j]
        out[j, MASS] = mass[j]


@kernel(parallel=True)
def soil_rates(
    targets, start, index, x, v, rho, s, pair, material, sound_speed, shear, h, norm,
    drho, acc, ds,
    av_alpha=None, av_beta=None,  # Monaghan artificial viscosity, seed eq. (19)
    is3d=None, mixed=None,
    shear_rate=None,  # mu(I): gamma_dot per row, from the same velocity gradient (docs/rheology.md)
    suspended=None, suspended_alpha=0.0, suspended_beta=0.0,  # erosion: the AV of pairs with picked-up soil
):  # fmt: skip
    """Continuity (6), momentum (20) without seepage, and the Hooke-Jaumann rate (13)-(15).
    Adds into drho and acc; writes ds. The velocity gradient is that of velocity_gradient.py.
    `pair` is the per-row table of soil_pair_terms (sigma / rho^2, m / rho, m) for every row.
    is3d is True in 3D and None in 2D, so that Numba compiles the 2D loop without the z terms
    (a value test such as x.shape[1] == 3 stays in the loop: 10 % of the 2D soil step).
    mixed=None (one soil material) takes the AV constants of the target for every pair, the
    same values as the pair means, without three gathers per pair; True for several soils
    (None rather than False so that Numba compiles the one-material loop without the branch).
    Call with the lists' unsigned views (NeighbourList.unsigned): signed ones work, slower.
    A neighbour's x, v and table row are read from flat views at j * dim + column, dim and the
    column count being compile-time constants: a 2D array's row stride is a run-time value
    that cost a 64-bit vector multiply per gathered array (with the unsigned lists, the pass
    took 0.68 of its time before, against 0.73 with the unsigned lists alone; one thread).
    The AV is evaluated for every pair with phi = 0 for receding ones (vr >= 0, where it adds
    exact zeros) rather than behind a branch on the sign of vr: for the benchmark's random
    velocities that branch was mispredicted half the time; branch-free the pass was 5-10 %
    faster, for random velocities and for a smooth rotation alike (one thread, CPU time).
    suspended (erosion, shields_pickup.py; None without): a pair with soil the flow has picked up takes
    suspended_alpha and suspended_beta, the water's AV constants, instead of the soil's."""
    three = is3d is not None
    dim = 3 if three else 2
    if x.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("soil_rates: x and v must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    vf = v.reshape(v.size)
    pf = pair.reshape(pair.size)
    hh = 0.01 * h * h
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = x[i, 2] if three else 0.0
        vi2 = v[i, 2] if three else 0.0
        rho_i = rho[i]
        # sigma_i / rho_i^2, eq. (12)
        q00 = pair[i, Q00]
        q11 = pair[i, Q11]
        q22 = pair[i, Q22]
        q01 = pair[i, Q01]
        q12 = pair[i, Q12]
        q02 = pair[i, Q02]
        mi = material[i]
        c_i = sound_speed[mi]
        alpha_i = av_alpha[mi] if av_alpha is not None else 0.0
        beta_i = av_beta[mi] if av_beta is not None else 0.0
        d_rho = 0.0
        a0 = a1 = a2 = 0.0
        g = velocity_gradient.ZERO
        for k in range(start[t], start[t + 1]):
            j = index[k]
            xj = j * dim
            pj = j * PAIR_COLUMNS
            d0 = xi0 - xf[xj]
            d1 = xi1 - xf[xj + 1]
            d2 = xi2 - xf[xj + 2] if three else 0.0
            u0 = vi0 - vf[xj]
            u1 = vi1 - vf[xj + 1]
            u2 = vi2 - vf[xj + 2] if three else 0.0
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            r = np.sqrt(r2) + 1e-300
            vr = u0 * d0 + u1 * d1 + u2 * d2
            fr = cubic_spline_dwdr(r, h, norm) / r  # grad_i W_ij = fr x_ij
            m_j = pf[pj + MASS]
            d_rho += m_j * vr * fr  # eq. (6)
            t00 = q00 + pf[pj + Q00]  # eq. (20): sigma_i/rho_i^2 + sigma_j/rho_j^2
            t11 = q11 + pf[pj + Q11]
            t01 = q01 + pf[pj + Q01]
            diag = 0.0
            if av_alpha is not None:
                # eq. (19) with beta phi^2 (erratum), phi = h vr / (r^2 + 0.01 h^2) for approaching
                # pairs, 0 for receding ones; Pi_ij = (-alpha c phi + beta phi^2) / rho_bar
                # = phi (-alpha c + beta phi) 2 / (rho_i + rho_j), with one division for both factors
                v_in = min(vr, 0.0)
                rho_ij = rho_i + rho[j]
                w = 1.0 / ((r2 + hh) * rho_ij)
                phi = h * v_in * rho_ij * w
                if mixed is not None:
                    mj = material[j]
                    c_bar = 0.5 * (c_i + sound_speed[mj])
                    alpha = 0.5 * (alpha_i + av_alpha[mj])
                    beta = 0.5 * (beta_i + av_beta[mj])
                else:
                    c_bar, alpha, beta = c_i, alpha_i, beta_i
                if suspended is not None and (suspended[i] != 0 or suspended[j] != 0):
                    alpha, beta = suspended_alpha, suspended_beta
                diag -= (-alpha * c_bar + beta * phi) * h * v_in * 2.0 * w
            fm = m_j * fr
            if three:
                t22 = q22 + pf[pj + Q22]
                t12 = q12 + pf[pj + Q12]
                t02 = q02 + pf[pj + Q02]
                a0 += fm * ((t00 + diag) * d0 + t01 * d1 + t02 * d2)
                a1 += fm * (t01 * d0 + (t11 + diag) * d1 + t12 * d2)
                a2 += fm * (t02 * d0 + t12 * d1 + (t22 + diag) * d2)
            else:
                a0 += fm * ((t00 + diag) * d0 + t01 * d1)
                a1 += fm * (t01 * d0 + (t11 + diag) * d1)
            f = fr * pf[pj + VOL]  # velocity gradient (Liu & Liu 2003)
            g = velocity_gradient.add_pair(g, u0, u1, u2, f, d0, d1, d2, three)
        g00, g01, g02, g10, g11, g12, g20, g21, g22 = g
        drho[i] += d_rho
        acc[i, 0] += a0
        acc[i, 1] += a1
        if three:
            acc[i, 2] += a2
        # eq. (14): strain rate e_ab = (g_ab + g_ba)/2;
        # eq. (15): W_ab = (dv^a/dx^b - dv^b/dx^a)/2 = (g_ba - g_ab)/2
        third = (g00 + g11 + g22) / 3.0
        two_g = 2.0 * shear[mi]
        w01 = 0.5 * (g10 - g01)
        w02 = 0.5 * (g20 - g02)
        w12 = 0.5 * (g21 - g12)
        j00, j11, j22, j01, j12, j02 = jaumann(
            s[i, 0], s[i, 1], s[i, 2], s[i, 3], s[i, 4], s[i, 5], w01, w02, w12
        )
        ds[i, 0] = two_g * (g00 - third) + j00  # eq. (13)
        ds[i, 1] = two_g * (g11 - third) + j11
        ds[i, 2] = two_g * (g22 - third) + j22
        ds[i, 3] = two_g * 0.5 * (g01 + g10) + j01
        ds[i, 4] = two_g * 0.5 * (g12 + g21) + j12
        ds[i, 5] = two_g * 0.5 * (g02 + g20) + j02
        if shear_rate is not None:
            # |gamma_dot| = sqrt(2 eps':eps') of the deviatoric strain rate (eq. 14): the shear rate of
            # the inertial number (GDR MiDi 2004; Jop et al. 2006), = |du/dy| in simple shear
            d00, d11, d22 = g00 - third, g11 - third, g22 - third
            e01, e12, e02 = 0.5 * (g01 + g10), 0.5 * (g12 + g21), 0.5 * (g02 + g20)
            dd = d00 * d00 + d11 * d11 + d22 * d22 + 2.0 * (e01 * e01 + e12 * e12 + e02 * e02)
            shear_rate[i] = np.sqrt(2.0 * dd)


class SoilRates(Term):
    """Continuity, stress divergence, AV, artificial stress and the Hooke-Jaumann rate of soil."""

    name = "soil rates"
    stage = Stage.RATES
    targets = Phase.SOIL
    neighbours = Phase.SOIL

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if materials.has_phase(Phase.SOIL) else None

    def __init__(self, scene, materials):
        super().__init__()
        soil = materials.ids_of_phase(Phase.SOIL)
        self.sound_speed = materials.sound_speed
        self.shear = materials.soil.shear
        av = any(materials.av_alpha[k] > 0 or materials.av_beta[k] > 0 for k in soil)
        self.av_alpha = materials.av_alpha if av else None
        self.av_beta = materials.av_beta if av else None
        self.mixed = True if len(soil) > 1 else None
        self.rate_dependent = materials.soil.rate_dependent  # mu(I): write the shear rate
        # Picked-up soil is a suspension, a fluid: its pairs take the water's AV (seed sec. 2.4: alpha 0.01,
        # beta 0), not the skeleton's alpha = beta = 1, whose viscosity alpha c h / 8 (c = 94 m/s: 8e4 times
        # the water's) held the picked-up top row on the bed under a 1 m/s stream (docs/erosion.md)
        water = materials.ids_of_phase(Phase.WATER)
        self.suspended_av = (
            (float(materials.av_alpha[water].max()), float(materials.av_beta[water].max()))
            if av and erosion_materials(scene, materials)
            else None
        )
        self._pair = np.empty((0, PAIR_COLUMNS))
        self.fields = {
            "rho_half": RHO_HALF,
            "stress_dev_half": FieldSpec(N_SYM, np.float64, "leap-frog s at n+1/2 (eq. 27)"),
            "dstress": FieldSpec(N_SYM, np.float64, "Hooke-Jaumann rate of s (eqs. 13-15)"),
        }
        self.integrates = (
            Integrated("rho", "rho_half", "drho"),
            Integrated("stress_dev", "stress_dev_half", "dstress"),
        )
        self.reads = ("x", "v", "rho", "mass", "material", "mean_stress", "stress_dev") + (
            ("suspended",) if self.suspended_av is not None else ()
        )
        self.adds_to = ("acc", "drho")
        self.writes = ("dstress",)
        if self.rate_dependent:  # read on owned rows only, by the return mapping (soil_stress.py)
            self.fields[SHEAR_RATE] = SHEAR_RATE_FIELD
            self.writes += (SHEAR_RATE,)
        equations = [
            Equation("continuity", "seed eq. (6)"),
            Equation("stress divergence", "seed eqs. (12), (20)"),
            Equation("Hooke-Jaumann deviatoric rate", "seed eqs. (13)-(15)"),
        ]
        if av:
            equations.append(
                Equation("Monaghan artificial viscosity", "seed eq. (19), alpha = beta = 1 for soil")
            )
        if self.rate_dependent:
            equations.append(
                Equation("shear rate sqrt(2 eps':eps') for mu(I)", "Jop et al. (2006); GDR MiDi (2004)")
            )
        self.equations = tuple(equations)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        n = ps.n_total
        if self._pair.shape[0] < n:  # scratch, not a particle field: rebuilt every step, never exchanged
            self._pair = np.empty((int(n * 1.25) + 16, PAIR_COLUMNS))
        soil_pair_terms(n, ps["rho"], ps["mean_stress"], ps["stress_dev"], ps["mass"], self._pair)
        start, index = nl.unsigned()
        soil_rates(
            nl.targets,
            start,
            index,
            ps["x"],
            ps["v"],
            ps["rho"],
            ps["stress_dev"],
            self._pair,
            ps["material"],
            self.sound_speed,
            self.shear,
            ctx.h,
            ctx.norm,
            ps["drho"],
            ps["acc"],
            ps["dstress"],
            self.av_alpha,
            self.av_beta,
            ctx.is3d,
            self.mixed,
            ps[SHEAR_RATE] if self.rate_dependent else None,
            ps["suspended"] if self.suspended_av is not None else None,
            *(self.suspended_av or (0.0, 0.0)),
        )
