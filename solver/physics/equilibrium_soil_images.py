"""Equilibrium image stress for soil (numerics.image_pressure = "hydrostatic"): the soil
analogue of the hydrostatic image pressure. The seed's mirror image (eq. 23) leaves a particle
pressed onto the floor in neutral equilibrium; with the static increment of the normal stress
along gravity the image below is more compressed than its source and pushes it back."""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..materials import Phase
from ..scene import ImagePressure
from ..term import Equation, Stage, Term
from .wall_images import static_increment


@kernel  # images are a thin layer: a serial loop
def add_equilibrium_image_stress(first, src, x, rho, gravity, mean_stress, stress):
    """The soil analogue of add_hydrostatic_image_pressure (numerics.image_pressure =
    "hydrostatic"): the image's stress is its source's plus the static increment of the normal
    stress along gravity, sigma' = sigma - q g^ g^ with q = rho_source g . (x_image - x_source)
    (compression positive: static equilibrium d sigma_vv / dv = rho g along the vertical v). An
    image below its source is then more compressed than it, as the soil below a floor would
    be, so a particle pressed into the image layer is pushed back, where the mirror image
    alone (seed eq. 23) leaves it in neutral equilibrium at the wall. As p and s:
    dp = q / 3, ds = -q (g^ g^ - I / 3). Side walls: g . dx = 0, no change. On a frictional
    wall that slips, frictional_images then sets the image shear itself, replacing the shear
    part of this increment, which is non-zero only when gravity is not normal to the wall."""
    dim = x.shape[1]
    g2 = 0.0
    for a in range(dim):
        g2 += gravity[a] * gravity[a]
    if g2 == 0.0:
        return
    gn = np.zeros(3)
    for a in range(dim):
        gn[a] = gravity[a] / np.sqrt(g2)
    for k in range(src.shape[0]):
        i = first + k
        q = static_increment(gravity, x, rho, i, src[k])
        mean_stress[i] += q / 3.0
        stress[i, 0] -= q * (gn[0] * gn[0] - 1.0 / 3.0)
        stress[i, 1] -= q * (gn[1] * gn[1] - 1.0 / 3.0)
        stress[i, 2] -= q * (gn[2] * gn[2] - 1.0 / 3.0)
        stress[i, 3] -= q * gn[0] * gn[1]
        stress[i, 4] -= q * gn[1] * gn[2]
        stress[i, 5] -= q * gn[0] * gn[2]


class EquilibriumSoilImages(Term):
    """Adds the static increment to each soil image's stress after the stress update."""

    name = "equilibrium soil image stress"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.image_pressure == ImagePressure.HYDROSTATIC
        return cls() if wanted and materials.has_phase(Phase.SOIL) and scene.walls.kinds() else None

    def __init__(self):
        super().__init__()
        self.reads = ("x", "rho", "mean_stress", "stress_dev")
        self.equations = (
            Equation(
                "sigma_image = sigma_source - q g^ g^, q = rho_source g . (x_image - x_source)",
                "this project (numerics.image_pressure = hydrostatic; verification/results/column_collapse)",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        if ps.n_image:
            add_equilibrium_image_stress(
                ps.n_local,
                ctx.image_tables()[0],
                ps["x"],
                ps["rho"],
                ctx.gravity,
                ps["mean_stress"],
                ps["stress_dev"],
            )
