"""The bed shear between the free water and an eroding bed: the log-law traction in place of the
seepage drag (issue 24; docs/erosion.md, "The bed shear").

The seepage drag (seepage.py, C = n^2 gamma_w / k) acts on every water-soil pair within a kernel. On
pore water it is Darcy's law; on the free water above a bed it is not: there the bed is a rough wall
whose Brinkman layer is sqrt(k nu / g) ~ 10 um thin, and the water feels the wall shear tau_b, not a
Darcy drag over a kernel (which stopped the first water row above a sand bed within 3 ms, against
the 0.06 % of theta a flow loses to bed friction in 10 ms: verification/sediment_threshold.py). With
numerics.bed_shear = "log_law" (the default where a soil erodes):

  * free water is water outside the bed: its bed fraction phi_a = sum_b V_b W_ab over the bed (soil
    not suspended) is below DEPOSIT_LIMIT (bed_surface.py: halfway between a flat bed's top row,
    0.763, where pore water sits, and a point a spacing above it, 0.24). Its pairs with the bed of
    an eroding soil carry no drag (seepage.py reads free_water);
  * instead each bed-surface particle b and the free water above it ((x_a - x_b).n_b > dx/2)
    exchange the wall shear of the log law, tau_b = rho_w <u*^2> along the water's mean tangential
    velocity t_b (shields_pickup.py computes both, the same u* the Shields number uses): b gets
    A_b tau_b t_b, A_b = V_b^((d-1)/d) its exposed area, and each free water particle a the share
    W_ab / sum_a' W_a'b of -A_b tau_b t_b (the sum over b's free pairs: shear_weight). Pair by pair
    equal and opposite: momentum is conserved.

This is the wall function of wall_function.py (Launder & Spalding 1974; the traction as a boundary
sum, Ferrand et al. 2013) with the bed's surface particles as the wall and Christoffersen & Jonsson's
(1985) rough-wall law. Time step: the traction's relaxation rate is of order u*/h, far below the
acoustic limit (wall_function.py), so no dt limit is declared.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..term import Equation, Stage, Term
from .bed_surface import surface_limits
from .erodible import erosion_materials

SHEAR_WEIGHT = FieldSpec(
    0, np.float64, "sum of W over a bed-surface particle's free-water pairs (0: no traction)", Mirror.SCALAR
)


def bed_shear_spec(dim):
    return FieldSpec(
        dim, np.float64, "log-law wall shear tau_b t_b the flow exerts on a bed-surface particle (Pa)",
        Mirror.DIRECTION,
    )  # fmt: skip


def bed_shear_on(scene, materials):
    """Whether the traction replaces the drag on the free water over an eroding bed."""
    return scene.numerics.bed_shear == "log_law" and bool(erosion_materials(scene, materials))


FREE_WATER = FieldSpec(0, np.uint8, "1: water outside the bed (wall shear, no drag, from an eroding bed)",
                       Mirror.SCALAR)  # fmt: skip


@kernel(parallel=True)
def free_water_flags(targets, start, index, x, mass, rho, suspended, h, norm, limit, free):
    """free_a = 1 where the bed fraction sum_b V_b W_ab over non-suspended soil b is below `limit`."""
    dim = x.shape[1]
    for t in prange(targets.shape[0]):
        a = targets[t]
        phi = 0.0
        for q in range(start[t], start[t + 1]):
            b = index[q]
            if suspended[b]:
                continue
            d0 = x[a, 0] - x[b, 0]
            d1 = x[a, 1] - x[b, 1]
            d2 = x[a, 2] - x[b, 2] if dim == 3 else 0.0
            phi += mass[b] / rho[b] * cubic_spline_w(np.sqrt(d0 * d0 + d1 * d1 + d2 * d2), h, norm)
        free[a] = 1 if phi < limit else 0


@kernel
def is_free_pair(b, dx0, dx1, dx2, shear_weight, bed_normal, half_dx):
    """Water at offset (dx0, dx1, dx2) = x_a - x_b is above the top face of bed-surface particle b
    (one with free water, shear_weight > 0); the caller checks that the water is free."""
    if shear_weight[b] <= 0.0:
        return False
    up = dx0 * bed_normal[b, 0] + dx1 * bed_normal[b, 1]
    if bed_normal.shape[1] == 3:
        up += dx2 * bed_normal[b, 2]
    return up > half_dx


@kernel(parallel=True)
def bed_shear_on_water(targets, start, index, x, mass, rho, fixed, free, bed_shear, shear_weight, bed_normal,
                       dx, h, norm, acc):  # fmt: skip
    """acc_a -= sum_b A_b tau_b t_b W_ab / shear_weight_b / m_a over the bed-surface particles b whose
    free water a is (module doc); wall particles (fixed) take no part."""
    dim = x.shape[1]
    for t in prange(targets.shape[0]):
        a = targets[t]
        if (fixed is not None and fixed[a]) or free[a] == 0:
            continue
        f0 = f1 = f2 = 0.0
        for q in range(start[t], start[t + 1]):
            b = index[q]
            d0 = x[a, 0] - x[b, 0]
            d1 = x[a, 1] - x[b, 1]
            d2 = x[a, 2] - x[b, 2] if dim == 3 else 0.0
            if not is_free_pair(b, d0, d1, d2, shear_weight, bed_normal, 0.5 * dx):
                continue
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            area = (mass[b] / rho[b]) ** ((dim - 1.0) / dim)
            share = area * cubic_spline_w(r, h, norm) / shear_weight[b]
            f0 += share * bed_shear[b, 0]
            f1 += share * bed_shear[b, 1]
            if dim == 3:
                f2 += share * bed_shear[b, 2]
        inv_m = 1.0 / mass[a]
        acc[a, 0] -= f0 * inv_m
        acc[a, 1] -= f1 * inv_m
        if dim == 3:
            acc[a, 2] -= f2 * inv_m


@kernel(parallel=True)
def bed_shear_on_soil(targets, mass, rho, bed_shear, shear_weight, acc):
    """acc_b += A_b tau_b t_b / m_b for the bed-surface particles with free water (shear_weight > 0)."""
    dim = acc.shape[1]
    for t in prange(targets.shape[0]):
        b = targets[t]
        if shear_weight[b] <= 0.0:
            continue
        area = (mass[b] / rho[b]) ** ((dim - 1.0) / dim)
        for c in range(dim):
            acc[b, c] += area * bed_shear[b, c] / mass[b]


class _BedShear(Term):
    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        return cls(scene) if bed_shear_on(scene, materials) else None

    def __init__(self, scene):
        super().__init__()
        self.adds_to = ("acc",)
        self.equations = (
            Equation(
                "wall shear tau_b = rho_w <u*^2> (log law) between the bed surface and its free water, in "
                "place of the seepage drag", "Launder & Spalding (1974); Christoffersen & Jonsson (1985)"
            ),
        )  # fmt: skip


class BedShearOnWater(_BedShear):
    """The free water's share of the bed's wall shear."""

    name = "bed shear on water"
    targets = Phase.WATER
    neighbours = Phase.SOIL

    def __init__(self, scene):
        super().__init__(scene)
        self.dx = scene.scene.spacing
        self.walls = any(b.fixed for b in scene.blocks)
        self.reads = ("x", "mass", "rho", "bed_shear", "shear_weight", "bed_normal") + (
            ("fixed",) if self.walls else ()
        )
        self.writes = ()

    def run(self, ctx):
        ps = ctx.particles
        nl = ctx.neighbours(self)
        bed_shear_on_water(
            nl.targets, nl.start, nl.index, ps["x"], ps["mass"], ps["rho"],
            ps["fixed"] if self.walls else None, ps["free_water"], ps["bed_shear"], ps["shear_weight"],
            ps["bed_normal"],
            self.dx, ctx.h, ctx.norm, ps["acc"],
        )  # fmt: skip


class BedShearOnSoil(_BedShear):
    """The bed's wall shear on its surface particles."""

    name = "bed shear on soil"
    targets = Phase.SOIL

    def run(self, ctx):
        ps = ctx.particles
        bed_shear_on_soil(
            ctx.rows[Phase.SOIL], ps["mass"], ps["rho"], ps["bed_shear"], ps["shear_weight"], ps["acc"]
        )


class FreeWater(Term):
    """Which water is outside the bed (module doc), for the pick-up's traction weights and the drag."""

    name = "free water"
    stage = Stage.STATE
    targets = Phase.WATER
    neighbours = Phase.SOIL

    @classmethod
    def build(cls, scene, materials):
        return cls(scene) if bed_shear_on(scene, materials) else None

    def __init__(self, scene):
        super().__init__()
        self.limit = surface_limits(scene.dim, scene.numerics.h_over_dx)[1]
        self.fields = {"free_water": FREE_WATER}
        self.reads = ("x", "mass", "rho", "suspended")
        self.writes = ("free_water",)
        self.equations = (
            Equation(f"free water: bed fraction sum V_b W_ab < {self.limit:.3f}", "bed_surface.py lattice"),
        )

    def run(self, ctx):
        ps = ctx.particles
        nl = ctx.neighbours(self)
        free_water_flags(
            nl.targets, nl.start, nl.index, ps["x"], ps["mass"], ps["rho"], ps["suspended"], ctx.h, ctx.norm,
            self.limit, ps["free_water"],
        )  # fmt: skip
