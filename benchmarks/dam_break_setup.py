"""The benchmark scene: the 2D dam break at a chosen particle count, disordered.

A perfect lattice hides branch and cache costs (DESIGN.md), so positions get a random
+-0.15 dx jitter and velocities a random field before timing; lists are rebuilt after."""

import numpy as np

from solver.simulation import Simulation
from verification.common import scene_from_file

A = 0.05715


def dam_break_scene(n_particles, **overrides):
    per_a = int(round(np.sqrt(n_particles / 2)))
    return scene_from_file("dam_break_2d.toml", **{"scene.spacing": A / per_a, **overrides})


def dam_break(n_particles, **overrides):
    return disordered(Simulation(dam_break_scene(n_particles, **overrides)))


def disordered(sim, seed=1):
    """Jitter positions by +-0.15 dx and give random velocities, then rebuild the lists and take one
    step: the state a benchmark times. Positions stay at least dx/2 from the lower walls, where the
    lattice's first row sits: nearer, the default wall repulsion (a backstop within dx/2) would kick
    those particles off at metres per second and the lists would be rebuilt every other step, a
    state no run reaches (issue 15: it doubled the timed water step)."""
    rng = np.random.default_rng(seed)
    ps = sim.particles
    n = ps.n_owned
    dx = sim.scene.scene.spacing
    ps["x"][:n] += rng.uniform(-0.15, 0.15, (n, 2)) * dx
    ps["x"][:n] = np.clip(ps["x"][:n], 0.5 * dx, None)
    ps["v_half"][:n] = rng.normal(0, 0.05, (n, 2))
    ps["v"][:n] = ps["v_half"][:n]
    sim.rebuild()
    sim.step()
    return sim
