"""Soil in 3D: a slab between free-slip side walls is plane strain, so a 3D run must keep every
y-layer of particles identical (seed eq. 23 mirrors the stress across the side walls, and the
lattice is symmetric). Run with cohesion and the Gray et al. (2001) artificial stress, the
3D path of every soil kernel (stress divergence, Hooke-Jaumann rate, return mapping, the
positive part of the stress by Jacobi rotations) enters."""

import tomllib

import numpy as np
from roundoff import roundoff_tolerances

from solver.initial_state import create_particles
from solver.plan import build_plan
from solver.scene import parse_scene
from solver.simulation import Simulation
from verification.column_collapse import SCENE


def test_3d_slab_between_free_slip_walls_collapses_as_plane_strain():
    raw = tomllib.loads(SCENE.read_text())
    raw["scene"].update(dimension=3, spacing=0.01, end_time=0.3, gravity=[0.0, 0.0, -9.81])
    raw["domain"] = {"min": [0.0, 0.0, 0.0], "max": [0.3, 0.06, 0.15]}
    raw["walls"] = {
        "x_min": "free_slip",
        "x_max": "free_slip",
        "y_min": "free_slip",
        "y_max": "free_slip",
        "z_min": "no_slip",
    }
    raw["blocks"] = [
        {
            "name": "c",
            "material": "bars",
            "shape": "rectangle",
            "min": [0, 0, 0],
            "max": [0.1, 0.06, 0.1],
            "geostatic": True,
        }
    ]
    raw["materials"]["bars"]["cohesion"] = 200.0  # cohesive: the artificial stress has tension to act on
    scene = parse_scene(raw, SCENE)
    start = create_particles(scene, build_plan(scene))
    x0 = start["x"][: start.n_owned][np.argsort(start["id"][: start.n_owned])]
    sim = Simulation(scene)
    sim.advance_to(0.3)
    ps = sim.particles
    x = ps.owned("x")[np.argsort(ps.owned("id"))]
    assert np.isfinite(x).all()
    assert x[:, 0].max() > 0.15  # it collapsed (measured: front 0.168 m)
    assert np.abs(ps.owned("art_stress")).max() > 0.0  # the artificial stress acted
    # Each y-layer sums the same pair terms as the first, in a mirrored order: the summation-order
    # bound of tests/roundoff.py (written for MPI vs serial) applies. Measured: 3e-14 m.
    mat = scene.materials["bars"]
    sigma = np.abs(ps.owned("stress_dev")).max() + np.abs(ps.owned("mean_stress")).max()
    tol_x, tol_v, _ = roundoff_tolerances(
        {"x": x, "v": ps.owned("v"), "mass": ps.owned("mass"), "rho": ps.owned("rho")},
        {"t": sim.t, "steps": sim.step_count},
        0.01,
        mat.density,
        mat.sound_speed,
        sigma,
        1.0,
    )
    layers = np.unique(np.round(x0[:, 1], 9))
    first = x[np.isclose(x0[:, 1], layers[0])]
    for y in layers[1:]:
        assert np.abs(x[np.isclose(x0[:, 1], y)][:, [0, 2]] - first[:, [0, 2]]).max() <= tol_x
    assert np.abs(x[:, 1] - x0[:, 1]).max() <= tol_x and np.abs(ps.owned("v_half")[:, 1]).max() <= tol_v
