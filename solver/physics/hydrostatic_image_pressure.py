"""Hydrostatic image pressure (numerics.image_pressure = "hydrostatic"): an image's pressure is
its source's plus the hydrostatic difference between the two points, so the water layer next
to a floor is supported (the seed's mirror image, sec. 2.5, carries only the source's own).
Body images (bodies.py) get it too: without it the water on a caisson's crown was held only by
the mirror pressure (its first row fell at 5.5 m/s^2 more than a floor's first row), and round a
convex corner the point images carried the pressure of their sources' height, not their own,
pulling the wedge's water towards the crown at 1.2 m/s^2: the still pond's start current beside
the corner (docs/history/scour_study_history.md, "The residual current (corner10)"). The soil's
equilibrium image stress (equilibrium_soil_images.py) stays on the box walls' images: on an inclined edge its
increment of the vertical stress is not free slip."""

from __future__ import annotations

from ..config import kernel
from ..fields import WATER_FRACTION
from ..materials import Phase
from ..scene import ImagePressure
from ..term import Equation, Stage, Term
from .tait_eos import saturated_mixture
from .wall_images import static_increment


@kernel
def add_hydrostatic_image_pressure(first, src, x, rho, gravity, p, fraction=None):
    """p_image = p_source + rho_source g . (x_image - x_source): the mirror pressure plus the
    hydrostatic difference between the two points (numerics.image_pressure = "hydrostatic").
    With `fraction` (pore water of apparent density n rho_w, docs/seepage.md) the increment uses
    the intrinsic density rho / n: the pore pressure's hydrostatic gradient is rho_w g."""
    for k in range(src.shape[0]):
        dp = static_increment(gravity, x, rho, first + k, src[k])
        if fraction is not None:
            dp /= fraction[src[k]]
        p[first + k] += dp


class HydrostaticImagePressure(Term):
    """Adds rho g . (x_image - x_source) to each image's Tait pressure (box walls' and bodies')."""

    name = "hydrostatic image pressure"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.image_pressure == ImagePressure.HYDROSTATIC
        imaged = scene.walls.kinds() or scene.bodies
        return cls(scene) if wanted and materials.has_phase(Phase.WATER) and imaged else None

    def __init__(self, scene):
        super().__init__()
        self.reads = ("x", "rho", "p")
        self.fraction = saturated_mixture(scene)  # pore water: increment from rho / n
        if self.fraction:
            self.fields = {"water_fraction": WATER_FRACTION}
            self.reads += ("water_fraction",)
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
                ps.n_local, ctx.image_sources(), ps["x"], ps["rho"], ctx.gravity, ps["p"],
                ps["water_fraction"] if self.fraction else None,
            )  # fmt: skip
