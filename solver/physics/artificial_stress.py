"""Artificial stress for soil in tension: the tensile-instability remedy of Gray, Monaghan &
Swift (2001), as used for soil by Bui et al. (2008). Per particle, R from its stress (this
term); per pair, f_ij^n (R_i + R_j) with f_ij = W_ij / W(dx) in the soil rates (soil_rates.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_normalisation, cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..tensors import N_SYM, positive_part
from ..term import Equation, Stage, Term

ART_STRESS = FieldSpec(N_SYM, np.float64, "artificial stress R (Gray et al. 2001)", Mirror.TENSOR)


@kernel(parallel=True)
def artificial_stress(rows, rho, mean_stress, s, eps, art, three=False):
    """Gray, Monaghan & Swift (2001) artificial stress, as used for soil by Bui et al. (2008):
    in the principal frame R'_aa = -eps sigma'_aa / rho^2 where sigma'_aa > 0 (tension), else 0,
    rotated back. 2D plane strain: the in-plane 2x2 part in closed form, zz is principal;
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
        theta = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
        c = np.cos(theta)
        sn = np.sin(theta)
        s1 = c * c * sxx + 2.0 * c * sn * sxy + sn * sn * syy
        s2 = sn * sn * sxx - 2.0 * c * sn * sxy + c * c * syy
        r1 = f * s1 if s1 > 0.0 else 0.0
        r2 = f * s2 if s2 > 0.0 else 0.0
        art[i, 0] = c * c * r1 + sn * sn * r2
        art[i, 1] = sn * sn * r1 + c * c * r2
        art[i, 2] = f * szz if szz > 0.0 else 0.0
        art[i, 3] = c * sn * (r1 - r2)
        art[i, 4] = 0.0
        art[i, 5] = 0.0


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
