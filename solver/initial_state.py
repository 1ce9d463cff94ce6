"""Particles at t = 0 from the scene's blocks."""

from __future__ import annotations

import numpy as np

from .geometry import block_points, block_span, block_top, clear_of_bodies
from .materials import tait_density
from .particles import ParticleSet
from .plan import Plan
from .scene import Scene, Seepage


def create_particles(scene: Scene, plan: Plan) -> ParticleSet:
    dim, dx = scene.dim, scene.scene.spacing
    mats = plan.materials
    blocks = [(b, block_points(b, scene)) for b in scene.blocks]
    blocks = [(b, pts[clear_of_bodies(pts, scene)]) for b, pts in blocks]  # bodies carve the blocks
    n = sum(len(pts) * (2 if b.saturated else 1) for b, pts in blocks)
    particles = ParticleSet(dim, plan.fields, capacity=int(n * 1.3) + 64)
    g_vertical = -scene.scene.gravity[-1]
    for block, pts in blocks:
        k = mats.index(block.material)
        rho0 = mats.rho0[k]
        if block.hydrostatic:
            # p = rho0 g (surface - z), then rho from the inverse Tait EOS (eq. 9)
            p = rho0 * g_vertical * (block_top(block) - pts[:, -1])
            rho = tait_density(p, rho0, mats.eos_b[k], mats.eos_exponent[k])
        else:
            rho = np.full(len(pts), rho0)
        extra = {}
        if block.geostatic:
            mat = scene.materials[block.material]
            weight = mat.density - buoyancy(scene, block, mats)  # buoyant in the mixture seepage
            rho, extra["stress_dev"] = geostatic_state(mat, pts, dx, g_vertical, weight)
        if "fixed" in plan.fields:
            extra["fixed"] = np.full(len(pts), bool(block.fixed))
        particles.append_owned(
            x=pts,
            rho=rho,
            mass=rho * dx**dim,
            material=np.full(len(pts), k, dtype=np.int32),
            **extra,
        )
        if block.saturated:
            particles.append_owned(**pore_water(scene, block, pts, mats, plan))
    return particles


def water_table(scene: Scene, block) -> float:
    """The free water surface above a saturated block: its `water_table`, else the highest top of
    the hydrostatic water blocks that overlap it horizontally, else its own top."""
    if block.water_table is not None:
        return float(block.water_table)
    lo, hi = block_span(block)
    tops = [block_top(block)]
    for other in scene.blocks:
        if other.hydrostatic and scene.materials[other.material].model == "water":
            olo, ohi = block_span(other)
            if np.all(olo[:-1] < hi[:-1]) and np.all(ohi[:-1] > lo[:-1]):
                tops.append(block_top(other))
    return max(tops)


def pore_water_material(scene: Scene, block) -> str:
    if block.pore_water is not None:
        return block.pore_water
    return next(name for name, m in scene.materials.items() if m.model == "water")


def buoyancy(scene: Scene, block, mats) -> float:
    """The density of the water the skeleton displaces, (1 - n) rho_w, for a saturated block in the
    mixture seepage (its skeleton carries gamma' z); 0 otherwise (dry soil, or the seed's coupling,
    where the skeleton carries its dry weight)."""
    if not (block.saturated and scene.numerics.seepage == Seepage.MIXTURE):
        return 0.0
    kw = mats.index(pore_water_material(scene, block))
    return (1.0 - scene.materials[block.material].porosity) * float(mats.rho0[kw])


def pore_water(scene: Scene, block, pts, mats, plan) -> dict:
    """Pore-water particles of a saturated block, one at each soil particle (docs/seepage.md): at
    the hydrostatic pressure below the water table, with the apparent density n rho_w(p) in the
    mixture seepage (its EOS reference n rho0) or the true density rho_w(p) in the seed's."""
    kw = mats.index(pore_water_material(scene, block))
    rho0 = mats.rho0[kw]
    g_vertical = -scene.scene.gravity[-1]
    p = np.maximum(rho0 * g_vertical * (water_table(scene, block) - pts[:, -1]), 0.0)
    rho = tait_density(p, rho0, mats.eos_b[kw], mats.eos_exponent[kw])
    fields = {"x": pts.copy(), "material": np.full(len(pts), kw, dtype=np.int32)}
    if "water_fraction" in plan.fields:
        n = scene.materials[block.material].porosity
        rho = n * rho
        fields["water_fraction"] = np.full(len(pts), n)
    if "pore_label" in plan.fields:  # the seed seepage's pore water (density diffusion leaves it out)
        fields["pore_label"] = np.full(len(pts), scene.materials[block.material].porosity)
    fields["rho"] = rho
    fields["mass"] = rho * scene.scene.spacing**scene.dim
    if "fixed" in plan.fields:
        fields["fixed"] = np.zeros(len(pts), dtype=bool)
    return fields


def geostatic_state(mat, pts, dx, g, weight=None):
    """At-rest stress of a soil block: sigma_v = rho' g d (d = depth below the block's own
    surface in that column; rho' = `weight`, the density whose weight the skeleton carries:
    rho0, or rho0 - (1 - n) rho_w when buoyant), sigma_h = K0 sigma_v with K0 = 1 - sin(phi) (Jaky 1944), both
    horizontal directions (plane strain keeps zz). Returns the density from eq. (17) for the
    mean stress p = sigma_v (1 + 2 K0) / 3 and the deviatoric stress s = sigma + p delta."""
    columns = np.round((pts[:, :-1] - pts[:, :-1].min(axis=0)) / dx).astype(np.int64)
    keys = np.unique(columns, axis=0, return_inverse=True)[1].ravel()
    top = np.full(keys.max() + 1, -np.inf)
    np.maximum.at(top, keys, pts[:, -1] + 0.5 * dx)
    depth = top[keys] - pts[:, -1]
    sv = (mat.density if weight is None else weight) * g * depth  # compression positive
    sh = mat.k0 * sv
    p = (sv + 2.0 * sh) / 3.0
    rho = mat.density * (1.0 + p / mat.bulk)  # inverse of eq. (17)
    s = np.zeros((len(pts), 6))
    vertical = pts.shape[1] - 1  # y in 2D, z in 3D
    for a in range(3):
        s[:, a] = p - (sv if a == vertical else sh)  # s = sigma + p delta, sigma = -stress magnitude
    return rho, s
