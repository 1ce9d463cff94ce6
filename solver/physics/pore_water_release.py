"""Pore water that leaves an eroding bed becomes free water (issue 24; docs/erosion.md).

In the mixture seepage a saturated block's water is pore water: its density is the apparent density
n rho_w of water in pores and its equation of state is referred to n rho0 (tait_eos.py, the field
water_fraction = n, fixed at creation). When the flow tears the top of a bed apart (the soil yields,
heaves or is picked up), pore water ends up in the free stream and kept that reference: among free
water it is a particle of apparent density in a medium without pores, whose dilation against n rho0
reads as a tension down to -B = -rho0 c^2 / 7. In the dam break over a mobile bed at 7 mm
(verification/mobile_bed_dam_break.py) such particles reached -196 kPa and blew the run up at
t = 0.51-0.57 s.

The release: a pore-water particle that is free water (bed_shear.FreeWater: its bed fraction is below
the free-water limit, i.e. it is outside the bed) is made free water,
    water_fraction -> 1,   rho -> rho / n   (and the leap-frog's rho_half likewise),
its mass unchanged. Its pressure is unchanged at that instant, B [(rho / (n rho0))^7 - 1] =
B [((rho / n) / rho0)^7 - 1] (seed eq. 9 with either reference), so the release adds no force; it only
gives the particle free water's density scale, in which it then evolves. It stands for a volume n V of
water (V its lattice volume). Free water that enters a bed is not turned into pore water (not needed
by the cases run so far). Built where the free-water flags exist (an eroding bed with the log-law bed
shear) in a scene with mixture pore water; never otherwise.
"""

from __future__ import annotations

from numba import prange

from ..config import kernel
from ..materials import Phase
from ..term import Equation, Stage, Term


@kernel(parallel=True)
def release_pore_water(rows, free, fraction, rho, rho_half=None):
    """For the water rows `rows`: a pore-water particle (fraction < 1) outside the bed (free = 1)
    takes fraction 1 and rho / fraction (rho_half / fraction), keeping its pressure."""
    for t in prange(rows.shape[0]):
        a = rows[t]
        f = fraction[a]
        if f < 1.0 and free[a] != 0:
            rho[a] /= f
            if rho_half is not None:
                rho_half[a] /= f
            fraction[a] = 1.0


class PoreWaterRelease(Term):
    name = "pore water release"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        from .bed_shear import bed_shear_on
        from .tait_eos import saturated_mixture

        return cls() if bed_shear_on(scene, materials) and saturated_mixture(scene) else None

    def __init__(self):
        super().__init__()
        self.reads = ("free_water", "water_fraction")
        self.writes = ("rho", "water_fraction")
        self.equations = (
            Equation("pore water outside the bed: water_fraction n -> 1, rho -> rho / n (p unchanged)",
                     "this project (module doc)"),
        )  # fmt: skip

    def run(self, ctx):
        ps = ctx.particles
        release_pore_water(
            ctx.rows[Phase.WATER], ps["free_water"], ps["water_fraction"], ps["rho"],
            ps["rho_half"] if "rho_half" in ps else None,
        )  # fmt: skip
