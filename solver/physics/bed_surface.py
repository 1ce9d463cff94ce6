"""Where the erodible bed's surface is: each soil particle's bed fraction and outward normal.

The bed is the soil that is not suspended (solver/physics/shields_pickup.py). For a soil particle b
    phi_b = sum_c V_c W_bc        (c: bed particles, b itself included when it is bed)
    n_b   = -grad phi_b / |grad phi_b|,   grad phi_b = sum_c V_c W'(r_bc) (x_b - x_c) / r_bc,
the kernel sum of the bed (its Shepard completeness, 1 inside) and the unit normal out of it (the
colour-function normal of Brackbill et al. 1992, J. Comput. Phys. 100:335, as SPH free-surface
detection uses it: Marrone et al. 2010, Comput. Methods Appl. Mech. Eng. 199:1233). Soil images take
part, so walls do not make a surface; water does not, so a saturated bed's surface is found too.

The thresholds come from the lattice the particles start on (`lattice_fractions`): at h = 1.3 dx a
flat bed's top row has phi = 0.763 and the row below 0.990 (2D). A bed particle is at the surface
when phi < SURFACE_LIMIT, halfway between the two; a suspended particle rests on the bed when its
fraction as if it were bed reaches DEPOSIT_LIMIT, halfway between the top row's and that of a
particle one spacing above it.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr, cubic_spline_w, kernel_values
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..term import Equation, Stage, Term
from .erodible import erosion_materials

BED_FRACTION = FieldSpec(0, np.float64, "kernel sum of the bed (non-suspended soil) at soil particles")


def bed_normal_spec(dim):
    return FieldSpec(
        dim, np.float64, "unit normal out of the bed at soil particles (0 inside)", Mirror.DIRECTION
    )


def lattice_fractions(dim, h_over_dx, rows=(-1, 0, 1)):
    """The bed fraction of a point `row` spacings above the top row of a flat lattice half-space
    (square in 2D, cubic in 3D), for each row asked: -1 the second row, 0 the top row, 1 above."""
    h = float(h_over_dx)
    n = int(np.ceil(2.0 * h)) + 2
    r = np.arange(-n, n + 1, dtype=float)
    depth = np.arange(-2 * n, 1, dtype=float)
    if dim == 2:
        gx, gy = np.meshgrid(r, depth)
        pts = np.c_[gx.ravel(), gy.ravel()]
    else:
        gx, gz, gy = np.meshgrid(r, r, depth)
        pts = np.c_[gx.ravel(), gy.ravel(), gz.ravel()]
    out = []
    for row in rows:
        at = np.zeros(dim)
        at[1] = row
        out.append(float(kernel_values(np.linalg.norm(pts - at, axis=1), h, dim).sum()))
    return tuple(out)


def surface_limits(dim, h_over_dx):
    """(SURFACE_LIMIT, DEPOSIT_LIMIT) of the module doc."""
    second, top, above = lattice_fractions(dim, h_over_dx)
    return 0.5 * (second + top), 0.5 * (top + above)


@kernel(parallel=True)
def bed_surface(targets, start, index, x, mass, rho, suspended, h, norm, fraction, normal):
    """phi_b and n_b (module doc) for the soil rows `targets`, over their soil neighbours."""
    dim = x.shape[1]
    w0 = cubic_spline_w(0.0, h, norm)
    for t in prange(targets.shape[0]):
        b = targets[t]
        phi = 0.0 if suspended[b] else w0 * mass[b] / rho[b]
        g0 = g1 = g2 = 0.0
        for s in range(start[t], start[t + 1]):
            c = index[s]
            if suspended[c]:
                continue
            d0 = x[b, 0] - x[c, 0]
            d1 = x[b, 1] - x[c, 1]
            d2 = x[b, 2] - x[c, 2] if dim == 3 else 0.0
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            vol = mass[c] / rho[c]
            phi += vol * cubic_spline_w(r, h, norm)
            if r > 0.0:
                f = vol * cubic_spline_dwdr(r, h, norm) / r
                g0 += f * d0
                g1 += f * d1
                g2 += f * d2
        fraction[b] = phi
        size = np.sqrt(g0 * g0 + g1 * g1 + g2 * g2)
        inv = -1.0 / size if size > 0.0 else 0.0
        normal[b, 0] = g0 * inv
        normal[b, 1] = g1 * inv
        if dim == 3:
            normal[b, 2] = g2 * inv


class BedSurface(Term):
    """The bed fraction and normal of every owned soil particle, for the erosion law."""

    name = "bed surface"
    stage = Stage.STATE
    targets = Phase.SOIL
    neighbours = Phase.SOIL

    @classmethod
    def build(cls, scene, materials):
        return cls(scene) if erosion_materials(scene, materials) else None

    def __init__(self, scene):
        super().__init__()
        self.fields = {"bed_fraction": BED_FRACTION, "bed_normal": bed_normal_spec(scene.dim)}
        self.reads = ("x", "mass", "rho", "suspended")
        self.writes = ("bed_fraction", "bed_normal")
        self.equations = (
            Equation(
                "bed fraction phi = sum V W over non-suspended soil and normal -grad phi / |grad phi|",
                "Brackbill et al. (1992); Marrone et al. (2010)",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        nl = ctx.neighbours(self)
        bed_surface(
            nl.targets, nl.start, nl.index, ps["x"], ps["mass"], ps["rho"], ps["suspended"], ctx.h, ctx.norm,
            ps["bed_fraction"], ps["bed_normal"],
        )  # fmt: skip
