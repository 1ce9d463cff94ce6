"""Continuity after the drift, for the symplectic leap-frog (numerics.leapfrog =
"symplectic_density"): rho lives at whole steps like x and is advanced with v at n+1/2,

    rho_{n+1} = rho_n + dt (drho/dt)(x_{n+1}, v_{n+1/2}),    drho/dt from seed eq. (6),

which makes the acoustic (rho, v) pair a symplectic leap-frog (verification/leapfrog_stability.py).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..integrate import as_rows, lf_kick
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..scene import Leapfrog
from ..term import Equation, Stage, Term


@kernel(parallel=True)
def continuity(targets, start, index, x, v, mass, h, norm, drho, is3d=None):
    """Seed eq. (6) alone: drho_i = sum_j m_j (v_i - v_j) . grad_i W_ij (written, not added).
    With v = v_{n+1/2} and x = x_{n+1} it advances rho at whole steps (numerics.leapfrog =
    "symplectic_density")."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        d_rho = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            vr = (vi0 - v[j, 0]) * d0 + (vi1 - v[j, 1]) * d1
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
                vr += (vi2 - v[j, 2]) * d2
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            d_rho += mass[j] * vr * cubic_spline_dwdr(r, h, norm) / r
        drho[i] = d_rho


class SymplecticContinuity(Term):
    name = "symplectic continuity"
    stage = Stage.AFTER_DRIFT
    targets = Phase.WATER
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.leapfrog == Leapfrog.SYMPLECTIC_DENSITY
        return cls() if wanted and materials.has_phase(Phase.WATER) else None

    def __init__(self):
        super().__init__()
        self.reads = ("x", "v_half", "mass")
        self.writes = ("drho", "rho")
        self.equations = (Equation("continuity with v at n+1/2, rho at whole steps", "seed eq. (6)"),)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        continuity(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["v_half"],
            ps["mass"],
            ctx.h,
            ctx.norm,
            ps["drho"],
            ctx.is3d,
        )
        n = ps.n_owned
        lf_kick(n, ctx.dt, as_rows(ps["rho"], n), as_rows(ps["drho"], n))
