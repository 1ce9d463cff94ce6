"""Artificial stress for soil in tension: the tensile-instability remedy of Gray, Monaghan &
Swift (2001), as used for soil by Bui et al. (2008). Two terms: per particle, R from its stress
(ArtificialStress, before the rates); per pair, the momentum contribution
    dv_i/dt += sum_j m_j f_ij^n (R_i + R_j) . grad_i W_ij,   f_ij = W_ij / W(dx)
(ArtificialStressForce), a pass of its own so that the soil rates carry no test for it: R is
zero for every particle in compression, nearly all of a cohesionless soil, and the pass skips
a pair whose two R vanish (it would add exact zeros), and is not run at all when no row
(owned, ghost or image) is in tension: a geostatic or confined soil has none.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr, cubic_spline_normalisation, cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..tensors import N_SYM, positive_part
from ..term import Equation, Stage, Term

ART_STRESS = FieldSpec(N_SYM, np.float64, "artificial stress R (Gray et al. 2001)", Mirror.TENSOR)


@kernel(parallel=True)
def artificial_stress(rows, rho, mean_stress, s, eps, art, three=False):
    """Gray, Monaghan & Swift (2001) artificial stress, as used for soil by Bui et al. (2008):
    in the principal frame R'_aa = -eps sigma'_aa / rho^2 where sigma'_aa > 0 (tension), else 0,
    rotated back. 2D plane strain: the in-plane 2x2 part by its spectral projectors, zz is principal;
    3D: the positive part of the full tensor by Jacobi rotations (tensors.positive_part)."""
    for t in prange(rows.shape[0]):
        i = rows[t]
        p = mean_stress[i]
        sxx = s[i, 0] - p
        syy = s[i, 1] - p
        szz = s[i, 2] - p
        sxy = s[i, 3]
        f = -eps / (rho[i] * rho[i])
        if three:
            pos = positive_part(sxx, syy, szz, sxy, s[i, 4], s[i, 5])
            for k in range(6):
                art[i, k] = f * pos[k]
            continue
        # in-plane principal values m +- q; the positive part sum_k max(l_k, 0) P_k with the
        # projectors P_+ = (S - l_- I) / 2q, P_- = I - P_+ (no angle: trig was 40 % of the term)
        m = 0.5 * (sxx + syy)
        d = 0.5 * (sxx - syy)
        q = np.sqrt(d * d + sxy * sxy)
        r1 = f * (m + q) if m + q > 0.0 else 0.0
        r2 = f * (m - q) if m - q > 0.0 else 0.0
        if q > 0.0:
            c = 0.5 / q
            art[i, 0] = c * (r1 * (q + d) + r2 * (q - d))
            art[i, 1] = c * (r1 * (q - d) + r2 * (q + d))
            art[i, 3] = c * (r1 - r2) * sxy
        else:  # isotropic in the plane
            art[i, 0] = r1
            art[i, 1] = r1
            art[i, 3] = 0.0
        art[i, 2] = f * szz if szz > 0.0 else 0.0
        art[i, 4] = 0.0
        art[i, 5] = 0.0


@kernel(parallel=True)
def tension_flags(n, art, flags):
    """flags[i] = 1 where R_i != 0 (particle i in tension), for every row up to n (ghosts, images);
    returns the number of such rows."""
    count = 0
    for i in prange(n):
        tense = 0
        for k in range(art.shape[1]):
            if art[i, k] != 0.0:
                tense = 1
        flags[i] = tense
        count += tense
    return count


@kernel(parallel=True)
def artificial_stress_force(
    targets, start, index, x, mass, art, flags, h, norm, art_n, inv_w_dx, acc, is3d=None
):
    """acc_i += sum_j m_j f_ij^n (R_i + R_j) . grad_i W_ij (Gray et al. 2001, with the
    stress term's rho^-2 already in R), f_ij = W_ij inv_w_dx; pairs with R_i = R_j = 0 skipped."""
    three = is3d is not None
    for t in prange(targets.shape[0]):
        i = targets[t]
        tense_i = flags[i] != 0
        a0 = a1 = a2 = 0.0
        for k in range(start[t], start[t + 1]):
            j = index[k]
            if not tense_i and flags[j] == 0:
                continue
            d0 = x[i, 0] - x[j, 0]
            d1 = x[i, 1] - x[j, 1]
            d2 = x[i, 2] - x[j, 2] if three else 0.0
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            fm = mass[j] * cubic_spline_dwdr(r, h, norm) / r  # m_j grad_i W_ij = fm x_ij
            fn = fm * (cubic_spline_w(r, h, norm) * inv_w_dx) ** art_n
            r00 = art[i, 0] + art[j, 0]
            r11 = art[i, 1] + art[j, 1]
            r01 = art[i, 3] + art[j, 3]
            if three:
                r22 = art[i, 2] + art[j, 2]
                r12 = art[i, 4] + art[j, 4]
                r02 = art[i, 5] + art[j, 5]
                a0 += fn * (r00 * d0 + r01 * d1 + r02 * d2)
                a1 += fn * (r01 * d0 + r11 * d1 + r12 * d2)
                a2 += fn * (r02 * d0 + r12 * d1 + r22 * d2)
            else:
                a0 += fn * (r00 * d0 + r01 * d1)
                a1 += fn * (r01 * d0 + r11 * d1)
        acc[i, 0] += a0
        acc[i, 1] += a1
        if three:
            acc[i, 2] += a2


@dataclass(frozen=True)
class ArtificialStressSettings:
    """epsilon and n of Gray et al. (2001), and 1 / W(dx) for f_ij = W_ij / W(dx)."""

    epsilon: float
    exponent: float
    inv_w_dx: float

    @classmethod
    def of(cls, scene):
        """The settings of a scene, or None when numerics.artificial_stress = 0 or there is no soil."""
        num = scene.numerics
        if num.artificial_stress <= 0 or not any(m.model == "soil" for m in scene.materials.values()):
            return None
        h = scene.h
        w_dx = float(cubic_spline_w(scene.scene.spacing, h, cubic_spline_normalisation(scene.dim, h)))
        return cls(num.artificial_stress, num.artificial_stress_exponent, 1.0 / w_dx)


class ArtificialStress(Term):
    """R of every owned soil particle from its stress at step n."""

    name = "artificial stress"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        settings = ArtificialStressSettings.of(scene)
        return cls(settings, scene.dim) if settings and materials.has_phase(Phase.SOIL) else None

    def __init__(self, settings, dim):
        super().__init__()
        self.settings = settings
        self.three = dim == 3
        self.fields = {"art_stress": ART_STRESS}
        self.writes = ("art_stress",)
        self.equations = (
            Equation(
                f"R = -eps sigma'_+ / rho^2 in the principal frame, eps = {settings.epsilon:g}",
                "Gray, Monaghan & Swift (2001); Bui et al. (2008)",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        artificial_stress(
            ctx.rows[Phase.SOIL],
            ps["rho"],
            ps["mean_stress"],
            ps["stress_dev"],
            self.settings.epsilon,
            ps["art_stress"],
            self.three,
        )


class ArtificialStressForce(Term):
    """The pair force of the artificial stress on soil particles."""

    name = "artificial stress force"
    stage = Stage.RATES
    targets = Phase.SOIL
    neighbours = Phase.SOIL

    @classmethod
    def build(cls, scene, materials):
        settings = ArtificialStressSettings.of(scene)
        return cls(settings) if settings and materials.has_phase(Phase.SOIL) else None

    def __init__(self, settings):
        super().__init__()
        self.settings = settings
        self.fields = {"tension": FieldSpec(0, np.uint8, "1 where the artificial stress R is non-zero")}
        self.writes_everywhere = ("tension",)
        self.reads = ("x", "mass", "art_stress")
        self.adds_to = ("acc",)
        self.equations = (
            Equation(
                f"artificial stress force f_ij^n (R_i + R_j), n = {settings.exponent:g}",
                "Gray, Monaghan & Swift (2001)",
            ),
        )

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        if tension_flags(ps.n_total, ps["art_stress"], ps["tension"]) == 0:
            return  # no row in tension: every pair would add exact zeros (the pass was 12 % of a step)
        artificial_stress_force(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["mass"],
            ps["art_stress"],
            ps["tension"],
            ctx.h,
            ctx.norm,
            self.settings.exponent,
            self.settings.inv_w_dx,
            ps["acc"],
            ctx.is3d,
        )
