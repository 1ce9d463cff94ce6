"""Density diffusion for weakly compressible water: delta-SPH and its hydrostatic variant.

A term added to the continuity equation (seed eq. 6) that damps the high-frequency density
(pressure) noise of weakly compressible SPH:

  Molteni & Colagrossi (2009), eq. (8), with Antuono et al. (2010), eqs. (6)-(8) notation:
      D_i = delta h c0 sum_j psi_ij . grad_i W_ij V_j,          V_j = m_j / rho_j
      psi_ij = 2 (rho_j - rho_i) x_ji / |x_ji|^2,               x_ji = x_j - x_i
  Since x_ji . grad_i W_ij = -r dW/dr, each pair adds 2 delta h c0 (rho_i - rho_j) (dW/dr / r) V_j:
  the SPH Laplacian of Brookshaw (1985) / Cleary & Monaghan (1999) times delta h c0, a diffusion
  of rho with diffusivity delta h c0 (it vanishes as h -> 0, first order).

  Antuono et al. (2010), eq. (7) (optional, `grad_rho`): psi_ij also subtracts
  (<grad rho>_i^L + <grad rho>_j^L) . x_ji, the renormalised density gradients of
  renormalised_density_gradient below (their eq. 8). For a linear density field the two parts
  cancel pair by pair, so the term is consistent, at the price of one more neighbour pass (and
  an exchange of a vector field) per evaluation.

  Fourtakas et al. (2019), Computers & Fluids 190:346, eqs. (13)-(14) (optional, `rho_ref`):
  diffuse only the dynamic density: psi_ij = 2 [(rho_j - rho_i) - (rho_j^H - rho_i^H)] x_ji / r^2,
  so a fluid at rest in hydrostatic equilibrium (rho = rho^H) sees exactly zero diffusion, where
  the plain form pulls the stratified density together (and the water column sinks). Fourtakas et
  al. write rho_ji^H = rho0 [(1 + rho0 g z_ij / B)^(1/gamma) - 1] per pair; here rho^H is a
  per-particle field given by the caller (hydrostatic_reference_density below), which equals
  theirs to first order in rho0 g z_ij / B, keeps each pair term antisymmetric (so sum_i V_i D_i
  = 0: the diffusion creates no mass), and is exactly the state the hydrostatic start builds.

delta = 0.1: Molteni & Colagrossi (2009) and Antuono et al. (2010) recommend 0.1 (Antuono et al.
2010, sec. 6: results insensitive within 0.05-0.2); DualSPHysics' default DensityDT value is 0.1.

Gather loop over a target's neighbour row, in the style of fluid.py: each target writes only
its own rate (adds into drho), optional terms are None-pruned at compile time, is3d None in 2D.
Walls by image particles: an image carries its source's rho (and rho_ref), so the density
(dynamic density) is mirrored and has zero normal gradient at the wall: no diffusive flux through it.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import PORE_LABEL, RHO_REF
from ..kernels import cubic_spline_dwdr
from ..materials import Phase
from ..scene import DensityDiffusion, Leapfrog, Seepage
from ..term import Equation, Stage, Term
from .tait_eos import saturated_mixture


@kernel(parallel=True)
def density_diffusion(
    targets,
    start,
    index,
    x,
    rho,
    mass,
    material,
    sound_speed,
    delta,
    h,
    norm,
    drho,
    rho_ref=None,  # hydrostatic reference density per particle: Fourtakas et al. (2019)
    grad_rho=None,  # renormalised density gradient per particle: Antuono et al. (2010)
    is3d=None,
    fraction=None,  # < 1 marks pore water: the mixture's water_fraction or the seed's pore_label
):
    """drho_i += delta h c0 sum_j psi_ij . grad_i W_ij m_j / rho_j (see module doc for psi_ij).

    With `fraction` (the mixture seepage's water fractions or the seed seepage's pore labels,
    docs/seepage.md) pore water (fraction < 1) takes no part: neither as a target nor as a
    neighbour. In pores the diffusion of rho is a diffusion of the pore pressure with
    diffusivity delta h c0, i.e. a spurious permeability k_num = delta h c0 gamma_w
    (m_v + n / K_w) next to the soil's k: it drained Terzaghi's column 1.85 times too fast
    (docs/seepage.md, "Density diffusion and pore water"), while the drag, relaxing at
    n g / k, already damps the acoustic noise the diffusion is there for."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        if fraction is not None and fraction[i] < 1.0:
            continue
        xi0, xi1 = x[i, 0], x[i, 1]
        xi2 = 0.0
        if is3d is not None:
            xi2 = x[i, 2]
        dyn_i = rho[i]  # the density diffused: rho, or its dynamic part rho - rho^H (Fourtakas et al.)
        if rho_ref is not None:
            dyn_i -= rho_ref[i]
        gi0 = gi1 = gi2 = 0.0
        if grad_rho is not None:
            gi0, gi1 = grad_rho[i, 0], grad_rho[i, 1]
            if is3d is not None:
                gi2 = grad_rho[i, 2]
        acc = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            if fraction is not None and fraction[j] < 1.0:
                continue  # pore water: no flux either way (antisymmetric pairs, no mass created)
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            r = np.sqrt(r2) + 1e-300
            fr = cubic_spline_dwdr(r, h, norm) / r  # grad_i W_ij = fr x_ij, x_ij = x_i - x_j
            # psi_ij . grad_i W_ij = 2 (rho_j - rho_i) (x_ji . x_ij) fr / r^2 = 2 (rho_i - rho_j) fr
            dyn_j = rho[j]
            if rho_ref is not None:  # each particle's dynamic part first: exactly 0 - 0 at rest
                dyn_j -= rho_ref[j]
            term = 2.0 * (dyn_i - dyn_j) * fr
            if grad_rho is not None:  # - (g_i + g_j) . grad_i W_ij  (Antuono et al. 2010, eq. 7)
                gs = (gi0 + grad_rho[j, 0]) * d0 + (gi1 + grad_rho[j, 1]) * d1
                if is3d is not None:
                    gs += (gi2 + grad_rho[j, 2]) * d2
                term -= gs * fr
            acc += term * mass[j] / rho[j]
        drho[i] += delta * h * sound_speed[material[i]] * acc


@kernel
def renormalised_solve(m00, m01, m02, m11, m12, m22, u0, u1, u2, is3d):
    """M^-1 u for the symmetric moment matrix M = sum_j x_ji (x) grad_i W_ij V_j (Antuono et al. 2010, eq. 8),
    by cofactors; (0, 0, 0) where M is singular (an isolated particle). In 2D (is3d None) m02, m12, m22, u2
    are unused and the third component is 0. Shared by the water's and the pore water's gradients."""
    if is3d is not None:
        c00 = m11 * m22 - m12 * m12
        c01 = m02 * m12 - m01 * m22
        c02 = m01 * m12 - m02 * m11
        det = m00 * c00 + m01 * c01 + m02 * c02
        if abs(det) > 1e-300:
            c11 = m00 * m22 - m02 * m02
            c12 = m01 * m02 - m00 * m12
            c22 = m00 * m11 - m01 * m01
            return (
                (c00 * u0 + c01 * u1 + c02 * u2) / det,
                (c01 * u0 + c11 * u1 + c12 * u2) / det,
                (c02 * u0 + c12 * u1 + c22 * u2) / det,
            )
        return 0.0, 0.0, 0.0
    det = m00 * m11 - m01 * m01
    if abs(det) > 1e-300:
        return (m11 * u0 - m01 * u1) / det, (m00 * u1 - m01 * u0) / det, 0.0
    return 0.0, 0.0, 0.0


@kernel(parallel=True)
def renormalised_density_gradient(targets, start, index, x, rho, mass, h, norm, grad_rho, is3d=None):
    """<grad rho>_i^L = sum_j (rho_j - rho_i) L_i grad_i W_ij V_j, L_i = [sum_j x_ji (x) grad_i W_ij V_j]^-1
    (Antuono et al. 2010, eq. 8; Randles & Libersky 1996): exact for linear rho where the kernel
    support is full or truncated. A target whose matrix is singular (an isolated particle) gets 0."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        xi2 = 0.0
        if is3d is not None:
            xi2 = x[i, 2]
        rho_i = rho[i]
        # M_ab = sum_j x_ji^a (grad_i W)^b V_j = -sum_j fr V_j x_ij^a x_ij^b (symmetric);
        # u = sum_j (rho_j - rho_i) grad_i W_ij V_j
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        u0 = u1 = u2 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            fv = cubic_spline_dwdr(r, h, norm) / r * mass[j] / rho[j]
            m00 -= fv * d0 * d0
            m01 -= fv * d0 * d1
            m11 -= fv * d1 * d1
            dr = rho[j] - rho_i
            u0 += dr * fv * d0
            u1 += dr * fv * d1
            if is3d is not None:
                m02 -= fv * d0 * d2
                m12 -= fv * d1 * d2
                m22 -= fv * d2 * d2
                u2 += dr * fv * d2
        grad_rho[i, 0], grad_rho[i, 1], g2 = renormalised_solve(
            m00, m01, m02, m11, m12, m22, u0, u1, u2, is3d
        )
        if is3d is not None:
            grad_rho[i, 2] = g2


@kernel(parallel=True)
def hydrostatic_reference_density(n, x, material, gravity, level, rho0, eos_b, exponent, rho_ref):
    """rho^H_i = rho0 (1 + rho0 |g| (level - z_i) / B)^(1/gamma) for rows [0, n): the inverse Tait law
    (seed eq. 9) of the hydrostatic pressure rho0 |g| (level - z_i), z measured along -g. Only
    differences rho^H_j - rho^H_i enter the diffusion; `level` (e.g. the initial free surface)
    sets the base, and it moves those differences only at second order in rho0 |g| dz / B."""
    dim = x.shape[1]
    g2 = 0.0
    for a in range(dim):
        g2 += gravity[a] * gravity[a]
    gn = np.sqrt(g2)
    for i in prange(n):
        m = material[i]
        if eos_b[m] == 0.0:  # not water (soil rows): no Tait law, never diffused
            rho_ref[i] = rho0[m]
            continue
        depth = level  # level - z, z = -g^ . x
        for a in range(dim):
            if gn > 0.0:
                depth += gravity[a] / gn * x[i, a]
        rho_ref[i] = rho0[m] * (1.0 + rho0[m] * gn * depth / eos_b[m]) ** (1.0 / exponent[m])


# -- the terms ----------------------------------------------------------------------------------


def water_level(scene) -> float:
    """The initial free-surface height along -g (m): the highest point of any water block, or
    of a saturated soil block's pore water (its water_table, else its top). rho^H only enters
    through differences, which the level moves at second order (hydrostatic_reference_density)."""
    g = np.asarray(scene.scene.gravity, float)
    up = -g / np.linalg.norm(g) if np.any(g != 0.0) else np.zeros_like(g)
    level = -np.inf
    for block in scene.blocks:
        material = scene.materials[block.material]
        if material.model != "water" and not block.saturated:
            continue
        if hasattr(block, "vertices"):
            points = np.asarray(block.vertices, float)
        else:
            lo, hi = np.asarray(block.min, float), np.asarray(block.max, float)
            points = np.array(
                [[(hi if (k >> a) & 1 else lo)[a] for a in range(len(lo))] for k in range(2 ** len(lo))]
            )
        top = float(np.max(points @ up))
        if block.saturated and block.water_table is not None:
            top = float(block.water_table)
        level = max(level, top)
    return level if np.isfinite(level) else 0.0


def pore_field(scene):
    """The field that marks pore water (value < 1) for the density diffusion, or None: the
    mixture's water_fraction, or the seed seepage's pore_label (its pore water keeps its true
    density, so the EOS must not see a fraction). Both label the water a saturated block creates."""
    if saturated_mixture(scene):
        return "water_fraction"
    if scene.numerics.seepage == Seepage.SEED and any(b.saturated for b in scene.blocks):
        return "pore_label"
    return None


def diffusion_settings(scene, materials):
    """(delta, hydrostatic reference?, the pore-water field or None) of
    numerics.density_diffusion, or None when it is off or the scene has no water."""
    kind = scene.numerics.density_diffusion
    if kind == DensityDiffusion.NONE or not materials.has_phase(Phase.WATER):
        return None
    return (
        scene.numerics.density_diffusion_delta,
        kind == DensityDiffusion.FOURTAKAS,
        pore_field(scene),
    )


class HydrostaticReference(Term):
    """rho^H of every owned particle at step n (Fourtakas et al. 2019), for the density diffusion;
    images copy their source's (Mirror.SCALAR): computing it at an image's own position would
    give a flux through the floor in still water."""

    name = "hydrostatic reference density"
    stage = Stage.STATE

    @classmethod
    def build(cls, scene, materials):
        settings = diffusion_settings(scene, materials)
        return cls(scene, materials) if settings is not None and settings[1] else None

    def __init__(self, scene, materials):
        super().__init__()
        self.materials = materials
        self.level = water_level(scene)
        self.fields = {"rho_ref": RHO_REF}
        self.writes = ("rho_ref",)
        self.equations = (
            Equation(
                f"rho^H = rho0 (1 + rho0 |g| (z_s - z) / B)^(1/gamma), z_s = {self.level:g} m "
                "(initial water level)",
                "Fourtakas et al. (2019), eqs. (13)-(14), per particle; inverse of seed eq. (9)",
            ),
        )

    def run(self, ctx):
        ps, m = ctx.particles, self.materials
        hydrostatic_reference_density(
            ps.n_owned, ps["x"], ps["material"], ctx.gravity, self.level, m.rho0, m.eos_b, m.eos_exponent,
            ps["rho_ref"],
        )  # fmt: skip


def diffusion_equation(delta, hydrostatic, fraction):
    what = (
        f"delta-SPH density diffusion, delta = {delta:g}"
        + (", on rho - rho^H" if hydrostatic else "")
        + (", not in pore water" if fraction else "")
    )
    source = "Molteni & Colagrossi (2009) eq. (8); Antuono et al. (2010) eq. (6)" + (
        "; Fourtakas et al. (2019) eqs. (13)-(14)" if hydrostatic else ""
    )
    return Equation(what, source)


class DensityDiffusionRate(Term):
    """The density diffusion added to drho at step n, with the seed's half-step leap-frog (with
    numerics.leapfrog = "midpoint_density" it is fused into the midpoint continuity instead,
    midpoint_continuity.py)."""

    name = "density diffusion"
    stage = Stage.RATES
    targets = Phase.WATER
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        settings = diffusion_settings(scene, materials)
        if settings is None or scene.numerics.leapfrog != Leapfrog.SEED:
            return None
        return cls(materials, *settings)

    def __init__(self, materials, delta, hydrostatic, fraction):
        super().__init__()
        self.sound_speed = materials.sound_speed
        self.delta, self.hydrostatic, self.fraction = delta, hydrostatic, fraction
        self.reads = ("x", "rho", "mass") + (("rho_ref",) if hydrostatic else ())
        self.reads += (fraction,) if fraction else ()
        if fraction == "pore_label":
            self.fields = {"pore_label": PORE_LABEL}
        self.adds_to = ("drho",)
        self.equations = (diffusion_equation(delta, hydrostatic, fraction),)

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        density_diffusion(
            nl.targets, nl.start, nl.index, ps["x"], ps["rho"], ps["mass"], ps["material"], self.sound_speed,
            self.delta, ctx.h, ctx.norm, ps["drho"], ps["rho_ref"] if self.hydrostatic else None, None,
            ctx.is3d, ps[self.fraction] if self.fraction else None,
        )  # fmt: skip
