"""The midpoint-density leap-frog (numerics.leapfrog = "midpoint_density"): rho lives at whole
steps like x and is advanced after the drift with v at n+1/2 and the kernel gradient at the
drift's midpoint,

    rho_{n+1} = rho_n + dt [ sum_j m_j v_ij^{n+1/2} . grad_i W(x_i^mid - x_j^mid) + D_i ],
    x^mid = (x_n + x_{n+1}) / 2,                                 seed eq. (6) + density diffusion

Why the midpoint (the impact design note, not in the repository, sec. 1; README "Time integration"): over one
step a pair's summation density changes by m [W(r_{n+1}) - W(r_n)]; the midpoint rule integrates
that to second order and is time-reversible, where the end point x_{n+1} (the former
"symplectic_density" option) adds a first-order error (dt^2/2) v.(grad grad W).v of fixed sign
that made the density of oscillating pairs drift (+158 kg/m3 in 20,000 steps of one particle
over its floor image) and blew up dam breaks on impact. Linearly both are the staggered
leap-frog, neutrally stable for acoustics (verification/leapfrog_stability.py).

Two terms: MidpointStart keeps x_n in `x_prev` after the kick (owned rows; ghosts and images get
it by exchange and mirroring like x), and MidpointContinuity forms x^mid of both particles inside
its pair loop, so no mid-step position is ever exchanged. The density diffusion of
numerics.density_diffusion (density_diffusion.py) is fused into the same loop, at x^mid with rho_n.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import x_prev
from ..integrate import as_rows, lf_kick
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..scene import Leapfrog
from ..term import Equation, Stage, Term
from .density_diffusion import diffusion_equation, diffusion_settings
from .outlet import frozen_rows


@kernel(parallel=True)
def midpoint_continuity(
    targets, start, index, x, x_old, v, rho, mass, material, sound_speed, h, norm, drho,
    delta=0.0, diffuse=None, rho_ref=None, is3d=None,
):  # fmt: skip
    """drho_i = sum_j m_j (v_i - v_j) . grad_i W_ij + D_i with every position at the midpoint
    (x + x_old) / 2 (written, not added). `diffuse` not None adds the density diffusion
    D_i = delta h c0 sum_j 2 (q_i - q_j) (dW/dr / r) V_j, q = rho or rho - rho_ref (the pair
    form of density_diffusion.density_diffusion). A neighbour's x, x_old and v are read from flat
    views at j * dim + column, dim a compile-time constant (as in soil_rates.py)."""
    dim = 3 if is3d is not None else 2
    if x.shape[1] != dim or x_old.shape[1] != dim or v.shape[1] != dim:
        raise ValueError("midpoint_continuity: x, x_old and v must have 3 columns with is3d=True, 2 without")
    xf = x.reshape(x.size)
    of = x_old.reshape(x_old.size)
    vf = v.reshape(v.size)
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0 = 0.5 * (x[i, 0] + x_old[i, 0])
        xi1 = 0.5 * (x[i, 1] + x_old[i, 1])
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = 0.5 * (x[i, 2] + x_old[i, 2]), v[i, 2]
        q_i = rho[i]
        if rho_ref is not None:
            q_i -= rho_ref[i]
        d_rho = 0.0
        dif = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            xj = j * dim
            d0 = xi0 - 0.5 * (xf[xj] + of[xj])
            d1 = xi1 - 0.5 * (xf[xj + 1] + of[xj + 1])
            vr = (vi0 - vf[xj]) * d0 + (vi1 - vf[xj + 1]) * d1
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - 0.5 * (xf[xj + 2] + of[xj + 2])
                vr += (vi2 - vf[xj + 2]) * d2
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            fr = cubic_spline_dwdr(r, h, norm) / r
            d_rho += mass[j] * vr * fr
            if diffuse is not None:
                q_j = rho[j]
                if rho_ref is not None:  # each particle's dynamic part first: exactly 0 - 0 at rest
                    q_j -= rho_ref[j]
                dif += 2.0 * (q_i - q_j) * fr * mass[j] / rho[j]
        if diffuse is not None:
            d_rho += delta * h * sound_speed[material[i]] * dif
        drho[i] = d_rho


class MidpointStart(Term):
    """Keeps x_n in x_prev before the drift."""

    name = "midpoint leap-frog: keep x_n"
    stage = Stage.AFTER_KICK

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.leapfrog == Leapfrog.MIDPOINT_DENSITY
        return cls(scene.dim) if wanted and materials.has_phase(Phase.WATER) else None

    def __init__(self, dim):
        super().__init__()
        self.fields = {"x_prev": x_prev(dim)}
        self.writes = ("x_prev",)
        self.equations = (Equation("x_prev = x_n (for the midpoint continuity)", "this project, issue 15"),)

    def run(self, ctx):
        ps = ctx.particles
        n = ps.n_owned
        ps["x_prev"][:n] = ps["x"][:n]


class MidpointContinuity(Term):
    """Continuity (with the density diffusion, if any) at the drift's midpoint; rho at n+1."""

    name = "midpoint continuity"
    stage = Stage.AFTER_DRIFT
    targets = Phase.WATER
    neighbours = Phase.WATER
    slip_image_velocity = True  # div v sees a no-slip wall as impermeable only (Adami et al. 2012)

    @classmethod
    def build(cls, scene, materials):
        wanted = scene.numerics.leapfrog == Leapfrog.MIDPOINT_DENSITY
        return cls(scene, materials) if wanted and materials.has_phase(Phase.WATER) else None

    def __init__(self, scene, materials):
        super().__init__()
        self.sound_speed = materials.sound_speed
        settings = diffusion_settings(scene, materials)
        self.diffuse = settings is not None
        self.delta, self.hydrostatic = (settings[0], settings[1]) if settings else (0.0, False)
        self.reads = ("x", "x_prev", "v_half", "rho", "mass") + (("rho_ref",) if self.hydrostatic else ())
        self.writes = ("drho", "rho")
        equations = [
            Equation(
                "continuity with v at n+1/2 and grad W at x^mid = (x_n + x_{n+1})/2, rho at whole steps",
                "seed eq. (6); midpoint quadrature: this project, issue 15",
            )
        ]
        if self.diffuse:
            equations.append(diffusion_equation(self.delta, self.hydrostatic, False))
        self.equations = tuple(equations)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        v_half = ctx.image_velocity(self, "v_half")
        start, index = nl.unsigned()  # no negative-index wrap-around per neighbour gather
        midpoint_continuity(
            nl.targets, start, index, ps["x"], ps["x_prev"], v_half, ps["rho"], ps["mass"],
            ps["material"], self.sound_speed, ctx.h, ctx.norm, ps["drho"], self.delta,
            True if self.diffuse else None, ps["rho_ref"] if self.hydrostatic else None, ctx.is3d,
        )  # fmt: skip
        n = ps.n_owned
        ps["drho"][frozen_rows(ps, n)] = 0.0  # outlet buffer particles keep their density (outlet.py)
        lf_kick(n, ctx.dt, as_rows(ps["rho"], n), as_rows(ps["drho"], n))
