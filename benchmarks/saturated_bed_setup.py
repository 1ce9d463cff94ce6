"""The two-phase benchmark scene: a saturated sand bed under a pond (benchmarks/saturated_bed_2d.toml),
at a chosen particle count, disordered like the water and soil benchmarks (dam_break_setup.py).

Every soil particle of a saturated bed carries a pore-water particle (solver/physics/seepage.py),
so the count is soil + pore water + pond = 3 x (0.2 m x 0.1 m) / dx^2."""

import tomllib
from pathlib import Path

import numpy as np
from dam_break_setup import disordered

from solver.scene import parse_scene
from solver.simulation import Simulation

SCENE = Path(__file__).with_name("saturated_bed_2d.toml")
AREA = 3 * 0.2 * 0.1  # m^2: soil, its pore water, the pond


def saturated_bed_scene(n_particles):
    raw = tomllib.loads(SCENE.read_text())
    raw["scene"]["spacing"] = float(np.sqrt(AREA / n_particles))
    return parse_scene(raw, SCENE)


def saturated_bed(n_particles):
    return disordered(Simulation(saturated_bed_scene(n_particles)))
