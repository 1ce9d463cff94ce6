"""Monaghan's (1994) wall backstop at polygon bodies (solver/physics/bodies.py): the box walls'
repulsion (wall_repulsion.py) applied to every body edge and convex vertex.

Why. With image particles the force a particle feels from its own image is proportional to dW/dr
at r = 2 d, which vanishes as d -> 0, so a jet drove particles through body edges (the q = 0.11 jet
onto an inclined face: 106 particle-steps inside; a jet skimming a convex vertex: 11.5 mm inside and
a blow-up; tests/test_bodies.py). The box walls got this backstop in issue 15; the bodies had none.

    a = D [(r0/d)^12 - (r0/d)^4] / d   along the edge's outward normal, d < r0 = dx/2,
    D = 5 g H (Monaghan 1994; H from wall_repulsion.largest_height, the same as the box walls').

At a convex vertex, for a particle in the wedge outside both edges, d is the distance to the vertex
and the force is radial (the vertex rounded off to a point, as its image is in bodies.py). Zero
beyond dx/2, so no particle of an undisturbed lattice (first row at dx/2) feels it.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..term import Stage, Term
from .bodies import BodyGeometry
from .wall_repulsion import backstop


@kernel(parallel=True)
def body_repulsion(n, x, r0, d_coef, ea, et, en, elen, cv, cin, cout, acc):
    """acc_i += D [(r0/d)^12 - (r0/d)^4] / d along the outward normal of each body edge whose foot
    is on the edge, for |d| < r0 (d floored at 1e-6 r0: a particle on or just through the edge is
    pushed out), and radially from each convex vertex for a particle in its wedge within r0."""
    floor = 1e-6 * r0
    for i in prange(n):
        a0 = a1 = 0.0
        for e in range(ea.shape[0]):
            r_0 = x[i, 0] - ea[e, 0]
            r_1 = x[i, 1] - ea[e, 1]
            dist = r_0 * en[e, 0] + r_1 * en[e, 1]
            if dist >= r0 or dist <= -r0:
                continue
            foot = r_0 * et[e, 0] + r_1 * et[e, 1]
            if foot < 0.0 or foot > elen[e]:
                continue
            d = max(dist, floor)
            q = r0 / d
            q4 = q * q * q * q
            f = d_coef * (q4 * q4 * q4 - q4) / d
            a0 += f * en[e, 0]
            a1 += f * en[e, 1]
        for c in range(cv.shape[0]):
            r_0 = x[i, 0] - cv[c, 0]
            r_1 = x[i, 1] - cv[c, 1]
            if r_0 * cin[c, 0] + r_1 * cin[c, 1] <= 0.0 or r_0 * cout[c, 0] + r_1 * cout[c, 1] >= 0.0:
                continue  # not in the vertex's wedge
            r = np.sqrt(r_0 * r_0 + r_1 * r_1)
            if r >= r0 or r == 0.0:
                continue
            d = max(r, floor)
            q = r0 / d
            q4 = q * q * q * q
            f = d_coef * (q4 * q4 * q4 - q4) / d
            a0 += f * r_0 / r
            a1 += f * r_1 / r
        acc[i, 0] += a0
        acc[i, 1] += a1


class BodyRepulsion(Term):
    """Monaghan's (1994) wall backstop within dx/2 of every body edge and convex vertex, with the box
    walls' D = 5 g H (wall_repulsion.py); on with numerics.wall_repulsion."""

    name = "body wall repulsion"
    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        g = np.asarray(scene.scene.gravity, float)
        if not scene.bodies or not scene.numerics.wall_repulsion or not np.any(g != 0.0):
            return None
        return cls(scene)

    def __init__(self, scene):
        super().__init__()
        self.geo = BodyGeometry(scene)
        where = "along a body edge's normal (or from a convex vertex)"
        self.r0, self.height, self.d_coef, equation = backstop(scene, where)
        self.adds_to = ("acc",)
        self.equations = (equation,)

    def run(self, ctx):
        ps, g = ctx.particles, self.geo
        body_repulsion(ps.n_owned, ps["x"], self.r0, self.d_coef, g.a, g.t, g.n, g.length, g.corner, g.t_in,
                       g.t_out, ps["acc"])  # fmt: skip
