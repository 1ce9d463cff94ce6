"""Water pressure from the Tait equation of state, seed eq. (9): p = B [(rho/rho0)^lambda - 1],
B = rho0 c^2 / lambda, c = 10 v_typ (seed sec. 2.1)."""

from __future__ import annotations

from numba import prange

from ..config import kernel
from ..fields import PRESSURE, WATER_FRACTION
from ..materials import Phase
from ..scene import Seepage
from ..term import Equation, Stage, Term
from ..timestep import Constraint


@kernel(parallel=True)
def tait_pressure(n, rho, material, rho0, eos_b, exponent, p, fraction=None):
    """Seed eq. (9): p = B [(rho/rho0)^lambda - 1] for rows [0, n). With `fraction` (pore water of
    the mixture seepage, docs/seepage.md) the reference is fraction * rho0: rho is then the
    apparent density n rho_w of water in pores, and p the pore pressure."""
    for i in prange(n):
        m = material[i]
        ref = rho0[m]
        if fraction is not None:
            ref = ref * fraction[i]
        p[i] = eos_b[m] * ((rho[i] / ref) ** exponent[m] - 1.0)


class TaitEquationOfState(Term):
    """p on every row (owned, ghosts, images) from rho: nothing to exchange afterwards."""

    name = "Tait equation of state"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if materials.has_phase(Phase.WATER) else None

    def __init__(self, scene, materials):
        super().__init__()
        self.materials = materials
        water = materials.ids_of_phase(Phase.WATER)
        c_max = float(materials.sound_speed[water].max())
        self.fields = {"p": PRESSURE}
        self.reads = ("rho",)
        # mixture seepage with saturated blocks: pore water's EOS reference is n rho0 (docs/seepage.md)
        self.fraction = saturated_mixture(scene)
        if self.fraction:
            self.fields["water_fraction"] = WATER_FRACTION
            self.reads += ("water_fraction",)
        self.writes_everywhere = ("p",)
        self.dt_limit = Constraint("sound", "seed eq. (28)", scene.numerics.cfl.sound * scene.h / c_max)
        self.equations = (Equation("p = B [(rho/rho0)^lambda - 1], B = rho0 c^2 / lambda", "seed eq. (9)"),)

    def _pressure(self, ps, n):
        m = self.materials
        fraction = ps["water_fraction"] if self.fraction else None
        tait_pressure(n, ps["rho"], ps["material"], m.rho0, m.eos_b, m.eos_exponent, ps["p"], fraction)

    def run(self, ctx):
        self._pressure(ctx.particles, ctx.particles.n_total)

    def derive(self, ctx):
        self._pressure(ctx.particles, ctx.particles.n_owned)


def saturated_mixture(scene):
    """Does the scene have pore water of the mixture seepage (whose EOS reference is n rho0)?"""
    return scene.numerics.seepage == Seepage.MIXTURE and any(b.saturated for b in scene.blocks)
