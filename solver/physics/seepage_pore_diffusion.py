"""Density diffusion for pore water, consistent for linear and quadratic pressure fields
(numerics.pore_density_diffusion = "antuono"; docs/seepage.md, "The pore water's odd-even mode").

Why. Pore water is out of the water's density diffusion (density_diffusion.py: there a diffusion of rho is a
diffusion of the pore pressure, a spurious permeability that drained Terzaghi's column 1.85 times too fast).
But then nothing damps the pore pressure's odd-even (checkerboard) mode: on a lattice, p_j = (-1)^j eps
gives no SPH pressure gradient (sum_j (-1)^j grad W_ij = 0 by the support's symmetry) and the matching
velocity pattern no SPH divergence, so the pore water's continuity and momentum (and the drag) neither see
nor damp it. Any source of it (a wall's corner, the bed's surface where pond water enters) makes it grow
without bound: the Darcy flow of pore water is d p / dt = c_v div(grad p) with SPH's two first-derivative
operators composed, whose null space holds that mode, the collocated-grid defect that Rhie & Chow (1983,
AIAA J. 21:1525) cure by adding the difference between a direct Laplacian and the composed one.

The term is the same cure in SPH: delta-SPH with Antuono et al.'s (2010, Comput. Phys. Commun.
181:532) correction, eqs. (6)-(8),
    D_i = delta h c0 sum_j psi_ij . grad_i W_ij V_j,
    psi_ij = 2 (q_j - q_i) x_ji / |x_ji|^2 - (<grad q>_i^L + <grad q>_j^L),
    <grad q>_i^L = L_i sum_j (q_j - q_i) grad_i W_ij V_j,  L_i = [sum_j x_ji (x) grad_i W_ij V_j]^-1,
on the pore water's dynamic density q = rho / f - rho^H (f the water fraction: n for the mixture's
pore water, whose apparent density is n rho_w; 1 in the seed form, whose pore water is at its true
density and whose pore_label only marks it; rho^H the hydrostatic reference of Fourtakas et al. 2019
when that is on, else 0), and the rate is f_i D_i.

For a quadratic q the two parts of psi cancel pair by pair (q_j - q_i = g . x_ji + x_ji . H x_ji / 2,
g_j = g_i + H x_ji), so a smooth pore pressure, hydrostatic, seepage or consolidation profile alike,
is not diffused: what is left acts on the fourth derivative (h^2 delta h c0 d^4 q, a hyperdiffusion),
while the odd-even mode, whose renormalised gradient is zero, gets the full Laplacian and decays (the
checkerboard at 890 /s at dx = 10 mm, 1770 /s at 5 mm, c0 = 20 m/s). The pair terms are
antisymmetric (no mass created among pore water of one fraction). Only pore water takes part, as
target and as neighbour: free water keeps its own diffusion, and wall particles (fixed) are walls.
At a wall the images carry the source's q (rho and rho^H copied) and its gradient with the normal
part reversed (Mirror.VELOCITY read with the free-slip sign, slip_image_velocity): a zero normal
gradient of the dynamic density, which is exactly Darcy's no-flux condition d h / d n = 0 at an
impermeable wall.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import PORE_LABEL, WATER_FRACTION
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..particles import FieldSpec, Mirror
from ..scene import DensityDiffusion
from ..term import Equation, Stage, Term
from .density_diffusion import pore_field, renormalised_solve
from .fixed_particles import FIXED


def gradient_field(dim: int) -> FieldSpec:
    """A gradient mirrors as a free-slip velocity does (normal part reversed); the rate term reads it
    through ctx.image_velocity with slip_image_velocity, so across no-slip walls too."""
    return FieldSpec(
        dim, np.float64, "renormalised gradient of the pore water's dynamic density (Antuono et al. 2010)",
        Mirror.VELOCITY,
    )  # fmt: skip


@kernel
def dynamic_density(j, rho, fraction, rho_ref, scaled):
    """q_j = rho_j / f_j - rho^H_j: f_j the water fraction with `scaled` (the mixture's pore water, whose
    rho is the apparent n rho_w), else 1 (the seed's, at its true density; its pore_label only marks it);
    rho^H 0 when rho_ref is None."""
    q = rho[j]
    if scaled is not None:
        q /= fraction[j]
    if rho_ref is not None:
        q -= rho_ref[j]
    return q


@kernel(parallel=True)
def pore_density_gradient(targets, start, index, x, rho, mass, fraction, h, norm, grad, rho_ref=None,
                          fixed=None, is3d=None, scaled=None):  # fmt: skip
    """<grad q>_i^L over pore-water neighbours for pore-water targets i (fraction < 1, not fixed);
    0 elsewhere, and 0 where the moment matrix is singular (an isolated particle)."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        grad[i, 0] = grad[i, 1] = 0.0
        if is3d is not None:
            grad[i, 2] = 0.0
        if fraction[i] >= 1.0 or (fixed is not None and fixed[i]):
            continue
        xi0, xi1 = x[i, 0], x[i, 1]
        xi2 = x[i, 2] if is3d is not None else 0.0
        q_i = dynamic_density(i, rho, fraction, rho_ref, scaled)
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        u0 = u1 = u2 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            if fraction[j] >= 1.0 or (fixed is not None and fixed[j]):
                continue
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = xi2 - x[j, 2] if is3d is not None else 0.0
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            fv = cubic_spline_dwdr(r, h, norm) / r * mass[j] / rho[j]  # grad_i W_ij V_j = fv x_ij
            m00 -= fv * d0 * d0  # M = sum_j x_ji (x) grad_i W_ij V_j = -sum_j fv x_ij (x) x_ij
            m01 -= fv * d0 * d1
            m11 -= fv * d1 * d1
            dq = dynamic_density(j, rho, fraction, rho_ref, scaled) - q_i
            u0 += dq * fv * d0
            u1 += dq * fv * d1
            if is3d is not None:
                m02 -= fv * d0 * d2
                m12 -= fv * d1 * d2
                m22 -= fv * d2 * d2
                u2 += dq * fv * d2
        grad[i, 0], grad[i, 1], g2 = renormalised_solve(m00, m01, m02, m11, m12, m22, u0, u1, u2, is3d)
        if is3d is not None:
            grad[i, 2] = g2


@kernel(parallel=True)
def pore_density_diffusion(targets, start, index, x, rho, mass, material, fraction, grad, sound_speed, delta,
                           h, norm, drho, rho_ref=None, fixed=None, is3d=None, scaled=None):  # fmt: skip
    """drho_i += f_i delta h c0 sum_j [2 (q_i - q_j) - (g_i + g_j) . x_ij] (W'_ij / r) V_j over pore
    pairs (module docstring: psi_ij . grad_i W_ij with grad_i W_ij = (W'/r) x_ij); f_i = 1 unless scaled."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        if fraction[i] >= 1.0 or (fixed is not None and fixed[i]):
            continue
        xi0, xi1 = x[i, 0], x[i, 1]
        xi2 = x[i, 2] if is3d is not None else 0.0
        gi0, gi1 = grad[i, 0], grad[i, 1]
        gi2 = grad[i, 2] if is3d is not None else 0.0
        q_i = dynamic_density(i, rho, fraction, rho_ref, scaled)
        acc = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            if fraction[j] >= 1.0 or (fixed is not None and fixed[j]):
                continue
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = xi2 - x[j, 2] if is3d is not None else 0.0
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            fr = cubic_spline_dwdr(r, h, norm) / r
            gs = (gi0 + grad[j, 0]) * d0 + (gi1 + grad[j, 1]) * d1
            if is3d is not None:
                gs += (gi2 + grad[j, 2]) * d2
            q_j = dynamic_density(j, rho, fraction, rho_ref, scaled)
            acc += (2.0 * (q_i - q_j) - gs) * fr * mass[j] / rho[j]
        if scaled is not None:
            acc *= fraction[i]
        drho[i] += delta * h * sound_speed[material[i]] * acc


# -- the terms ----------------------------------------------------------------------------------


def pore_settings(scene, materials):
    """(delta, pore field, hydrostatic reference?, fixed walls?) when the option is on and the scene
    has pore water, else None."""
    if scene.numerics.pore_density_diffusion != "antuono" or not materials.has_phase(Phase.WATER):
        return None
    field = pore_field(scene)
    if field is None:
        return None
    # pore water means soil, and scenes with soil run the seed leap-frog (scene.py refuses the midpoint one)
    hydrostatic = scene.numerics.density_diffusion == DensityDiffusion.FOURTAKAS
    walls = any(b.fixed and scene.materials[b.material].model == "water" for b in scene.blocks)
    return scene.numerics.pore_density_diffusion_delta, field, hydrostatic, walls


class _PoreTerm(Term):
    targets = Phase.WATER
    neighbours = Phase.WATER

    def __init__(self, scene, settings):
        super().__init__()
        self.delta, self.fraction, self.hydrostatic, self.walls = settings
        self.fields = {"pore_density_gradient": gradient_field(scene.dim)}
        self.fields[self.fraction] = PORE_LABEL if self.fraction == "pore_label" else WATER_FRACTION
        self.reads = ("x", "rho", "mass", self.fraction) + (("rho_ref",) if self.hydrostatic else ())
        if self.walls:
            self.fields["fixed"] = FIXED
            self.reads += ("fixed",)

    def optional(self, ps):
        """The kernels' optional arguments: (rho^H or None, the fixed flags or None, scaled)."""
        scaled = True if self.fraction == "water_fraction" else None
        return ps["rho_ref"] if self.hydrostatic else None, ps["fixed"] if self.walls else None, scaled


class PoreDensityGradient(_PoreTerm):
    """<grad q>^L of every owned pore-water particle (state at step n), for the pore diffusion."""

    name = "pore density gradient"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        settings = pore_settings(scene, materials)
        return cls(scene, settings) if settings is not None else None

    def __init__(self, scene, settings):
        super().__init__(scene, settings)
        self.writes = ("pore_density_gradient",)
        self.equations = (
            Equation(
                "<grad q>_i = L_i sum_j (q_j - q_i) grad_i W_ij V_j over pore water, q = rho / f - rho^H",
                "Antuono et al. (2010) eq. (8); Randles & Libersky (1996)",
            ),
        )

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        ref, fixed, scaled = self.optional(ps)
        pore_density_gradient(
            nl.targets, nl.start, nl.index, ps["x"], ps["rho"], ps["mass"], ps[self.fraction], ctx.h,
            ctx.norm, ps["pore_density_gradient"], ref, fixed, ctx.is3d, scaled,
        )  # fmt: skip


class PoreDensityDiffusion(_PoreTerm):
    """The corrected delta-SPH term added to the pore water's drho at step n (seed leap-frog)."""

    name = "pore density diffusion"
    stage = Stage.RATES
    slip_image_velocity = True  # the gradient's images: normal part reversed across any wall

    @classmethod
    def build(cls, scene, materials):
        settings = pore_settings(scene, materials)
        return cls(scene, materials, settings) if settings is not None else None

    def __init__(self, scene, materials, settings):
        super().__init__(scene, settings)
        self.sound_speed = materials.sound_speed
        self.reads += ("pore_density_gradient",)
        self.adds_to = ("drho",)
        self.equations = (
            Equation(
                f"pore water: drho_i += f_i delta h c0 sum_j [2 (q_i - q_j) - (g_i + g_j) . x_ij] (W'/r) "
                f"V_j, delta = {self.delta:g}",
                "Antuono et al. (2010) eqs. (6)-(7) on the dynamic density (Fourtakas et al. 2019)",
            ),
        )

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        grad = ctx.image_velocity(self, "pore_density_gradient")
        ref, fixed, scaled = self.optional(ps)
        pore_density_diffusion(
            nl.targets, nl.start, nl.index, ps["x"], ps["rho"], ps["mass"], ps["material"], ps[self.fraction],
            grad, self.sound_speed, self.delta, ctx.h, ctx.norm, ps["drho"], ref, fixed, ctx.is3d, scaled,
        )  # fmt: skip
