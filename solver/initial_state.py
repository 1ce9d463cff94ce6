"""Particles at t = 0 from the scene's blocks."""

from __future__ import annotations

import numpy as np

from .geometry import block_points, block_top
from .materials import tait_density
from .particles import ParticleSet
from .plan import Plan
from .scene import Scene


def create_particles(scene: Scene, plan: Plan) -> ParticleSet:
    dim, dx = scene.dim, scene.scene.spacing
    mats = plan.materials
    blocks = [(b, block_points(b, scene)) for b in scene.blocks]
    n = sum(len(pts) for _, pts in blocks)
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
        if getattr(block, "geostatic", False):
            rho, extra["stress_dev"] = geostatic_state(scene.materials[block.material], pts, dx, g_vertical)
        if "fixed" in plan.fields:
            extra["fixed"] = np.full(len(pts), bool(block.fixed))
        particles.append_owned(
            x=pts,
            rho=rho,
            mass=rho * dx**dim,
            material=np.full(len(pts), k, dtype=np.int32),
            **extra,
        )
    return particles


def geostatic_state(mat, pts, dx, g):
    """At-rest stress of a soil block: sigma_v = rho0 g d (d = depth below the block's own
    surface in that column), sigma_h = K0 sigma_v with K0 = 1 - sin(phi) (Jaky 1944), both
    horizontal directions (plane strain keeps zz). Returns the density from eq. (17) for the
    mean stress p = sigma_v (1 + 2 K0) / 3 and the deviatoric stress s = sigma + p delta."""
    columns = np.round((pts[:, :-1] - pts[:, :-1].min(axis=0)) / dx).astype(np.int64)
    keys = np.unique(columns, axis=0, return_inverse=True)[1].ravel()
    top = np.full(keys.max() + 1, -np.inf)
    np.maximum.at(top, keys, pts[:, -1] + 0.5 * dx)
    depth = top[keys] - pts[:, -1]
    sv = mat.density * g * depth  # compression positive
    sh = mat.k0 * sv
    p = (sv + 2.0 * sh) / 3.0
    rho = mat.density * (1.0 + p / mat.bulk)  # inverse of eq. (17)
    s = np.zeros((len(pts), 6))
    vertical = pts.shape[1] - 1  # y in 2D, z in 3D
    for a in range(3):
        s[:, a] = p - (sv if a == vertical else sh)  # s = sigma + p delta, sigma = -stress magnitude
    return rho, s
