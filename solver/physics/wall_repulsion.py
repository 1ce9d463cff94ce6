"""Short-range wall repulsion (numerics.wall_repulsion): a backstop that acts only on a particle
closer than half a particle spacing to a wall plane, where no particle of the initial lattice sits.

Monaghan (1994), J. Comput. Phys. 110:399, the Lennard-Jones force of his boundary particles,
f(r) = D [(r0/r)^p1 - (r0/r)^p2] r / r^2, applied here to the distance d from the wall plane along
its normal n (into the fluid) instead of to boundary particles:

    a = D [(r0/d)^p1 - (r0/d)^p2] / d  n     for d < r0,   0 otherwise,
    p1 = 12, p2 = 4 (Monaghan's values), r0 = dx/2 (Monaghan: the initial particle spacing; here
    half of it, so that no particle of the initial lattice, the first row at dx/2, is ever touched).

D: Monaghan chooses D of the magnitude of the square of the largest velocity and, for his dam
break of height H, D = 5 g H (the free-fall speed is sqrt(2 g H), so 5 g H = 2.5 v^2; the
paper's section and equation numbers were not re-checked here: the phase-1 memo's reading).
Here H is the scene's largest initial height of a block above the lowest point of any block
along -g, so D = 5 |g| H; with g = 0 the term is absent.

Why it is needed (issue 15; the impact design note, not in the repository, sec. 4): with image particles the
repulsion a particle feels from its own image is proportional to dW/dr at r = 2 d, which
vanishes as d -> 0 (the cubic spline's gradient is zero at r = 0); nothing in the image model
stops a particle that is already closer than dx/2 (slow bottom-row and toe particles, 5 mm/s),
and the drift's specular reflection had to. At d >= dx/2 the force is exactly zero, so
well-behaved particles never feel it; it enters the force time-step limit (seed eq. 29) like
every acceleration.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..scene_open import inlet_width
from ..term import Equation, Stage, Term
from .wall_images import wall_planes

D_OVER_GH = 5.0  # Monaghan (1994): D = 5 g H for a dam break of height H (exponents 12 and 4 in the kernel)


@kernel(parallel=True)
def wall_repulsion(n, x, r0, d_coef, has_lo, lo, has_hi, hi, acc):
    """acc_i += D [(r0/d)^12 - (r0/d)^4] / d along each wall's inward normal, for d < r0."""
    dim = x.shape[1]
    floor = 1e-6 * r0  # a particle on (or through) the plane: the force at d = 1e-6 r0, inward
    for i in prange(n):
        for a in range(dim):
            if has_lo[a]:
                d = max(x[i, a] - lo[a], floor)
                if d < r0:
                    q = r0 / d
                    q4 = q * q * q * q
                    acc[i, a] += d_coef * (q4 * q4 * q4 - q4) / d
            if has_hi[a]:
                d = max(hi[a] - x[i, a], floor)
                if d < r0:
                    q = r0 / d
                    q4 = q * q * q * q
                    acc[i, a] -= d_coef * (q4 * q4 * q4 - q4) / d


def largest_height(scene) -> float:
    """The head H (m) of the water a scene can bring against a wall, along -g: the largest height
    of a block's top, or of an inlet's section plus its velocity head u^2 / 2g, above the lowest
    block point (the domain's floor when the scene has no block, e.g. inflow only)."""
    g = np.asarray(scene.scene.gravity, float)
    g_norm = float(np.linalg.norm(g))
    up = -g / g_norm
    tops, bottoms = [], []
    for block in scene.blocks:
        if hasattr(block, "vertices"):
            points = np.asarray(block.vertices, float)
        else:
            points = _corners(np.asarray(block.min, float), np.asarray(block.max, float))
        heights = points @ up
        tops.append(heights.max())
        bottoms.append(heights.min())
    for inlet in scene.inlets:
        origin = np.asarray(inlet.origin, float)
        width = inlet_width(inlet, scene.scene.spacing, g_norm)
        speed = inlet.speed or inlet.discharge / width
        if inlet.across is not None:
            across = np.asarray(inlet.across, float)
        else:  # 2D default of scene_open.Inlet: the direction turned +90 degrees
            across = np.array([-inlet.direction[1], inlet.direction[0]], float)
        across = across / np.linalg.norm(across)
        head = 0.5 * speed * speed / g_norm
        tops.append(max(origin @ up, (origin + width * across) @ up) + head)
    if not bottoms:
        bottoms.append(
            (_corners(np.asarray(scene.domain.min, float), np.asarray(scene.domain.max, float)) @ up).min()
        )
    return float(max(tops) - min(bottoms))


def backstop(scene, where):
    """(r0, H, D, equation) of Monaghan's backstop for a scene: r0 = dx/2, H = largest_height(scene),
    D = 5 g H, shared by the box walls and the body walls (body_repulsion.py)."""
    r0 = 0.5 * scene.scene.spacing
    height = largest_height(scene)
    d_coef = D_OVER_GH * float(np.linalg.norm(scene.scene.gravity)) * height
    equation = Equation(
        f"a = D [(r0/d)^12 - (r0/d)^4] / d {where} for d < r0 = dx/2, "
        f"D = 5 g H = {d_coef:.4g} m^2/s^2 (H = {height:.4g} m)",
        "Monaghan (1994), Lennard-Jones boundary force, D = 5 g H",
    )
    return r0, height, d_coef, equation


def _corners(lo, hi):
    dim = len(lo)
    return np.array([[(hi if (k >> a) & 1 else lo)[a] for a in range(dim)] for k in range(2**dim)])


class WallRepulsion(Term):
    """The Monaghan (1994) backstop within dx/2 of each wall plane, on every owned particle."""

    name = "wall repulsion"
    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        g = np.asarray(scene.scene.gravity, float)
        if not scene.numerics.wall_repulsion or not scene.walls.kinds() or not np.any(g != 0.0):
            return None
        return cls(scene)

    def __init__(self, scene):
        super().__init__()
        self.planes = wall_planes(scene)
        self.r0, self.height, self.d_coef, equation = backstop(scene, "normal to a wall")
        self.adds_to = ("acc",)
        self.equations = (equation,)

    def run(self, ctx):
        ps = ctx.particles
        has_lo, lo, has_hi, hi = self.planes
        wall_repulsion(ps.n_owned, ps["x"], self.r0, self.d_coef, has_lo, lo, has_hi, hi, ps["acc"])
