"""Hydrostatic image pressure (numerics.image_pressure = "hydrostatic"): an image's pressure is
its source's plus the hydrostatic difference between the two points, so the water layer next
to a floor is supported (the seed's mirror image, sec. 2.5, carries only the source's own)."""

from __future__ import annotations

from ..config import kernel
from ..materials import Phase
from ..scene import ImagePressure
from ..term import Equation, Stage, Term
from .wall_images import static_increment


@kernel
def add_hydrostatic_image_pressure(first, src, x, rho, gravity, p):
    """p_image = p_source + rho_source g . (x_image - x_source): the mirror pressure plus the
    hydrostatic difference between the two points (numerics.image_pressure = "hydrostatic")."""
    for k in range(src.shape[0]):
        p[first + k] += static_increment(gravity, x, rho, first + k, src[k])


class HydrostaticImagePressure(Term):
    """Adds rho g . (x_image - x_source) to each image's Tait pressure."""

    name = "hydrostatic image pressure"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.image_pressure == ImagePressure.HYDROSTATIC
        return cls() if wanted and materials.has_phase(Phase.WATER) and scene.walls.kinds() else None

    def __init__(self):
        super().__init__()
        self.reads = ("x", "rho", "p")
        self.equations = (
            Equation(
                "p_image = p_source + rho_source g . (x_image - x_source)",
                "this project (numerics.image_pressure = hydrostatic; README, still-water tank)",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        if ps.n_image:
            add_hydrostatic_image_pressure(
                ps.n_local, ctx.image_tables()[0], ps["x"], ps["rho"], ctx.gravity, ps["p"]
            )
