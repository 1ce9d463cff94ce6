"""Erosion at the bed surface: the Shields threshold and the van Rijn pick-up (issue 24, item 2).

A soil with a grain size d50 (`materials.<name>.grain_size`) erodes grain by grain in nature; here a
bed-surface particle (bed fraction below SURFACE_LIMIT, solver/physics/bed_surface.py) is worn away
by the flow over it:

  bed shear     tau_b = rho_w <u*^2>,  u* from the transitional log law u_t = (u*/kappa) ln(y / z0)
                (Christoffersen & Jonsson 1985; k_s = 2.5 d50) for each water neighbour a above the
                bed: u_t = |tangential part of v_a - v_b| along the bed normal n_b, y = (x_a - x_b).n_b
                - dx/2 its height above the particle's top (the bed surface), pairs with y >= dx (the
                second water row and up: the first lies in the seepage drag's interface layer, which
                stops it within milliseconds, docs/erosion.md); <.> the kernel-weighted mean (V_a W_ab);
  Shields       theta_b = tau_b / ((rho_grain - rho_w) g d50)                        (Shields 1936)
  threshold     theta_cr of Soulsby & Whitehouse (1997), or the material's critical_shields;
  pick-up       E = van Rijn (1984) (solver/sediment.py), mass per bed area and time: the particle's
                eroded share grows by E A dt / m_b = E dt / (rho_dry dx) (its exposed area A = dx^(d-1)),
                so the bed lowers at E / rho_dry whatever the spacing;
  suspension    when the share reaches 1 the particle is suspended: it loses its shear strength (the
                deviatoric stress is zeroed, soil_stress.Constitution), keeps the pressure of eq. (17)
                against compression, and moves with the water through the seepage drag (Manenti et al.
                2012, J. Hydraul. Eng. 138:272; Zubeldia et al. 2018, Adv. Water Resour. 117:98: the
                Shields criterion on the surface layer over a plastic bed);
  deposition    a suspended particle that rests on the bed (its fraction as if bed >= DEPOSIT_LIMIT)
                where theta <= theta_cr rejoins the bed (stress-free, its share reset).

The particle is a packet of bed at the bed's porosity, not a dilute suspension: it settles through
still water at the bed's Darcy speed (1 - n)(s - 1) k / n^2 (mixture form), not at a grain's fall
velocity (docs/erosion.md, "What is not modelled"). The step's dt is the previous step's (the state
stage runs before the new dt is known): the share is a first-order time integral of E.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_w
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..sediment import (
    ROUGHNESS_PER_GRAIN,
    bed_friction_velocity,
    critical_shields,
    dimensionless_grain_size,
    pickup_rate,
)
from ..term import Equation, Stage, Term
from .bed_shear import SHEAR_WEIGHT, bed_shear_on, bed_shear_spec
from .bed_surface import surface_limits
from .erodible import erosion_materials

SUSPENDED = FieldSpec(0, np.uint8, "1: soil picked up by the flow (no shear strength)", Mirror.SCALAR)
ERODED_SHARE = FieldSpec(0, np.float64, "share of a bed-surface particle's mass eroded so far (0-1)")
SHIELDS = FieldSpec(0, np.float64, "Shields number of the flow over a bed-surface particle (0 elsewhere)")
MIN_HEIGHT = 1.0  # pairs with y >= MIN_HEIGHT dx sample the flow: the second water row up (docs/erosion.md)


class SedimentTable:
    """Per-material constants of the erosion law (zeros: a soil that does not erode)."""

    def __init__(self, scene, materials, ids):
        waters = materials.ids_of_phase(Phase.WATER)
        self.rho_w = max(float(materials.rho0[k]) for k in waters)
        self.nu = max(float(materials.viscosity[k] / materials.rho0[k]) for k in waters)
        self.g = float(np.linalg.norm(scene.scene.gravity))
        n = len(materials.names)
        self.d50, self.theta_cr, self.dstar, self.s, self.rho_grain = (np.zeros(n) for _ in range(5))
        for k in ids:
            mat = scene.materials[materials.names[k]]
            self.d50[k] = mat.grain_size
            self.rho_grain[k] = mat.density / (1.0 - mat.porosity)
            self.s[k] = self.rho_grain[k] / self.rho_w
            self.dstar[k] = dimensionless_grain_size(mat.grain_size, self.s[k], self.nu, max(self.g, 1e-12))
            self.theta_cr[k] = (
                mat.critical_shields if mat.critical_shields is not None else critical_shields(self.dstar[k])
            )


@kernel(parallel=True)
def shields_pickup(targets, start, index, x, v, mass, rho, material, fixed, suspended, share, shields,
                   fraction, normal, stress_dev, d50, theta_cr, dstar, s_rel, rho_grain, rho_w, nu, g, dx, h,
                   norm, dt, surface_limit, deposit_limit, bed_shear=None, shear_weight=None,
                   free=None):  # fmt: skip
    """The module doc's law for the owned soil rows `targets`, over their water neighbours. Writes
    shields (theta, 0 where not sampled), share, suspended, and zeroes the deviatoric stress of a
    particle it suspends. fixed: the wall flags (None without fixed blocks: walls are not water).
    bed_shear, shear_weight (the bed-shear traction, bed_shear.py; None without): the traction
    tau_b t_b the flow exerts on a bed-surface particle (t_b the direction of the sampled water's
    mean tangential velocity relative to it, weights V_a W_ab) and the sum of W_ab over its free
    pairs (free water above its top face, (x_a - x_b).n_b > dx/2; free: bed_shear.FreeWater), which
    share the reaction."""
    dim = x.shape[1]
    w0 = cubic_spline_w(0.0, h, norm)
    for t in prange(targets.shape[0]):
        b = targets[t]
        m = material[b]
        shields[b] = 0.0
        if shear_weight is not None:
            shear_weight[b] = 0.0
            for c in range(dim):
                bed_shear[b, c] = 0.0
        if d50[m] <= 0.0:
            continue
        vol_b = mass[b] / rho[b]
        lifted = suspended[b] != 0
        if not lifted and fraction[b] >= surface_limit:
            continue  # inside the bed
        if lifted and fraction[b] + w0 * vol_b < deposit_limit:
            continue  # carried in the water, away from the bed
        n0, n1 = normal[b, 0], normal[b, 1]
        n2 = normal[b, 2] if dim == 3 else 0.0
        if n0 * n0 + n1 * n1 + n2 * n2 == 0.0:
            continue
        k_s = ROUGHNESS_PER_GRAIN * d50[m]
        sum_w = sum_wu = free_w = tan0 = tan1 = tan2 = 0.0
        for q in range(start[t], start[t + 1]):
            a = index[q]
            if fixed is not None and fixed[a]:
                continue
            d0 = x[a, 0] - x[b, 0]
            d1 = x[a, 1] - x[b, 1]
            d2 = x[a, 2] - x[b, 2] if dim == 3 else 0.0
            y = d0 * n0 + d1 * n1 + d2 * n2 - 0.5 * dx
            if y <= 0.0:
                continue
            r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            kernel_w = cubic_spline_w(r, h, norm)
            if free is not None and free[a] != 0:
                free_w += kernel_w
            w = mass[a] / rho[a] * kernel_w
            if y < MIN_HEIGHT * dx or w <= 0.0:
                continue
            u0 = v[a, 0] - v[b, 0]
            u1 = v[a, 1] - v[b, 1]
            u2 = v[a, 2] - v[b, 2] if dim == 3 else 0.0
            un = u0 * n0 + u1 * n1 + u2 * n2
            t0, t1, t2 = u0 - un * n0, u1 - un * n1, u2 - un * n2
            ut = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
            us = bed_friction_velocity(ut, y, k_s, nu)
            sum_w += w
            sum_wu += w * us * us
            tan0 += w * t0
            tan1 += w * t1
            tan2 += w * t2
        if sum_w <= 0.0:
            continue
        theta = rho_w * sum_wu / sum_w / ((rho_grain[m] - rho_w) * g * d50[m])
        shields[b] = theta
        size = math.sqrt(tan0 * tan0 + tan1 * tan1 + tan2 * tan2)
        if shear_weight is not None and not lifted and size > 0.0:
            tau = rho_w * sum_wu / sum_w / size  # tau_b per unit of the summed tangential vector
            shear_weight[b] = free_w
            bed_shear[b, 0] = tau * tan0
            bed_shear[b, 1] = tau * tan1
            if dim == 3:
                bed_shear[b, 2] = tau * tan2
        if lifted:
            if theta <= theta_cr[m]:
                suspended[b] = 0  # deposited
                share[b] = 0.0
            continue
        rate = pickup_rate(theta, theta_cr[m], d50[m], s_rel[m], dstar[m], rho_grain[m], g)
        share[b] += rate * dt * vol_b ** ((dim - 1.0) / dim) / mass[b]
        if share[b] >= 1.0:
            suspended[b] = 1
            share[b] = 0.0
            for c in range(stress_dev.shape[1]):
                stress_dev[b, c] = 0.0


class ShieldsPickup(Term):
    """Shields threshold, van Rijn pick-up and deposition of the bed-surface soil particles."""

    name = "shields pick-up"
    stage = Stage.STATE
    targets = Phase.SOIL
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        ids = erosion_materials(scene, materials)
        return cls(scene, materials, ids) if ids else None

    def __init__(self, scene, materials, ids):
        super().__init__()
        self.table = SedimentTable(scene, materials, ids)
        self.dx = scene.scene.spacing
        self.surface_limit, self.deposit_limit = surface_limits(scene.dim, scene.numerics.h_over_dx)
        self.walls = any(b.fixed for b in scene.blocks)
        self.fields = {"suspended": SUSPENDED, "eroded_share": ERODED_SHARE, "shields": SHIELDS}
        self.reads = ("x", "v", "mass", "rho") + (("fixed",) if self.walls else ())
        self.writes = ("suspended", "eroded_share", "shields", "stress_dev")
        self.traction = bed_shear_on(scene, materials)  # the wall shear for bed_shear.py
        if self.traction:
            self.fields = {**self.fields, "bed_shear": bed_shear_spec(scene.dim)}
            self.fields["shear_weight"] = SHEAR_WEIGHT
            self.writes += ("bed_shear", "shear_weight")
            self.reads += ("free_water",)
        tb = self.table
        names = ", ".join(
            f"{materials.names[k]} (d50 {1e3 * tb.d50[k]:.3g} mm, theta_cr {tb.theta_cr[k]:.4f})" for k in ids
        )
        self.equations = (
            Equation(
                f"bed shear by log law, k_s = {ROUGHNESS_PER_GRAIN} d50", "Christoffersen & Jonsson (1985)"
            ),
            Equation(f"Shields threshold of {names}", "Soulsby & Whitehouse (1997)"),
            Equation("pick-up rate E = 0.00033 rho_s sqrt((s-1) g d) D*^0.3 T^1.5", "van Rijn (1984)"),
            Equation(
                "picked-up soil suspended, no shear strength", "Manenti et al. (2012); Zubeldia et al. (2018)"
            ),
        )

    def explain(self):
        return [
            f"bed surface below a bed fraction of {self.surface_limit:.3f}; suspended soil redeposits at "
            f"{self.deposit_limit:.3f} (lattice values, solver/physics/bed_surface.py)"
        ]

    def run(self, ctx):
        ps = ctx.particles
        nl = ctx.neighbours(self)
        tb = self.table
        shields_pickup(
            nl.targets, nl.start, nl.index, ps["x"], ps["v"], ps["mass"], ps["rho"], ps["material"],
            ps["fixed"] if self.walls else None, ps["suspended"], ps["eroded_share"], ps["shields"],
            ps["bed_fraction"], ps["bed_normal"], ps["stress_dev"], tb.d50, tb.theta_cr, tb.dstar, tb.s,
            tb.rho_grain, tb.rho_w, tb.nu, tb.g, self.dx, ctx.h, ctx.norm, ctx.dt, self.surface_limit,
            self.deposit_limit, ps["bed_shear"] if self.traction else None,
            ps["shear_weight"] if self.traction else None, ps["free_water"] if self.traction else None,
        )  # fmt: skip
