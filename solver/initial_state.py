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
        particles.append_owned(
            x=pts, rho=rho, rho_half=rho, mass=rho * dx**dim,
            material=np.full(len(pts), k, dtype=np.int32),
        )
    return particles
