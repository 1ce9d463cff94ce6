"""Newtonian viscous stress of water, seed eqs. (10)-(11): tau = mu eps,
eps_ab = dv^b/dx^a + dv^a/dx^b - 2/3 (div v) delta_ab, from the SPH velocity gradient."""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..tensors import N_SYM
from ..term import Equation, Stage, Term
from ..timestep import Constraint
from . import velocity_gradient

TAU = FieldSpec(N_SYM, np.float64, "viscous stress (eqs. 10-11), symmetric", Mirror.TENSOR)


@kernel(parallel=True)
def viscous_stress(targets, start, index, x, v, rho, mass, material, viscosity, h, norm, tau, is3d=None):
    """tau_i = mu eps_i, seed eqs. (10)-(11), with the SPH velocity gradient (velocity_gradient.py).
    tau has 6 symmetric components (solver/tensors.py). is3d: None in 2D (z code pruned). A neighbour's
    x and v are read from flat views at j * dim + column, dim a compile-time constant (soil_rates.py)."""
    dim = 3 if is3d is not None else 2
    if x.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("viscous_stress: x and v must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    vf = v.reshape(v.size)
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        g = velocity_gradient.ZERO
        for s in range(start[t], start[t + 1]):
            j = index[s]
            xj = j * dim
            d0 = xi0 - xf[xj]
            d1 = xi1 - xf[xj + 1]
            d2 = u2 = 0.0
            if is3d is not None:
                d2 = xi2 - xf[xj + 2]
                u2 = vi2 - vf[xj + 2]
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            f = cubic_spline_dwdr(r, h, norm) / r * mass[j] / rho[j]
            g = velocity_gradient.add_pair(
                g, vi0 - vf[xj], vi1 - vf[xj + 1], u2, f, d0, d1, d2, is3d is not None
            )
        g00, g01, g02, g10, g11, g12, g20, g21, g22 = g
        mu = viscosity[material[i]]
        third_div = (g00 + g11 + g22) / 3.0
        tau[i, 0] = mu * (2.0 * g00 - 2.0 * third_div)  # eq. (11): g_ab + g_ba - 2/3 div delta_ab
        tau[i, 1] = mu * (2.0 * g11 - 2.0 * third_div)
        tau[i, 2] = mu * (2.0 * g22 - 2.0 * third_div)
        tau[i, 3] = mu * (g01 + g10)
        tau[i, 4] = mu * (g12 + g21)
        tau[i, 5] = mu * (g02 + g20)


def viscous_stress_on(scene, materials):
    """The term exists when it is switched on and some water has a viscosity."""
    water = materials.ids_of_phase(Phase.WATER)
    return bool(water) and scene.numerics.viscous_stress and max(materials.viscosity[k] for k in water) > 0


class ViscousStress(Term):
    """tau for every water particle from its water neighbours; the fluid rates take its divergence."""

    name = "viscous stress"
    stage = Stage.STATE
    targets = Phase.WATER
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if viscous_stress_on(scene, materials) else None

    def __init__(self, scene, materials):
        super().__init__()
        self.viscosity = materials.viscosity
        water = materials.ids_of_phase(Phase.WATER)
        nu_max = max(materials.viscosity[k] / materials.rho0[k] for k in water)
        self.fields = {"tau": TAU}
        self.reads = ("x", "v", "rho", "mass")
        self.writes = ("tau",)
        self.dt_limit = Constraint(
            "viscous", "seed eq. (30)", scene.numerics.cfl.viscous * scene.h**2 / nu_max
        )
        self.equations = (Equation("Newtonian viscous stress tau = mu eps", "seed eqs. (10)-(11)"),)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        start, index = nl.unsigned()  # no negative-index wrap-around per neighbour gather
        viscous_stress(
            nl.targets,
            start,
            index,
            ps["x"],
            ps["v"],
            ps["rho"],
            ps["mass"],
            ps["material"],
            self.viscosity,
            ctx.h,
            ctx.norm,
            ps["tau"],
            ctx.is3d,
        )
