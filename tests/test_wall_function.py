"""The log-law wall shear (solver/physics/wall_function.py) against its NumPy twin
(tests/naive_wall_function.py), the traction it exerts on a log-law profile, and its place in the plan."""

import math

import naive_wall_function as naive
import numpy as np
import pytest

from solver.physics import wall_function as W
from solver.physics.wall_function import WallFunctionShear
from solver.scene import parse_scene
from solver.simulation import Simulation

NU, RHO = 1.0e-6, 1000.0


@pytest.mark.parametrize(
    "u, y", [(2.0, 3.75e-3), (0.5, 7.5e-3), (3.0, 1e-3), (1e-3, 1e-3), (0.02, 2e-3), (5.0, 0.05)]
)
def test_friction_velocity_matches_the_law(u, y):
    """Both branches: the viscous sublayer (y+ < 11.06) and the log layer."""
    us = W.friction_velocity(u, y, NU)
    assert us == pytest.approx(naive.friction_velocity(u, y, NU), rel=1e-9)
    yp = us * y / NU
    law = yp if yp < naive.Y_LAM else math.log(naive.E * yp) / naive.KAPPA
    assert u / us == pytest.approx(law, rel=1e-9)


@pytest.mark.parametrize("dim", [2, 3])
def test_plane_weight_table_matches_direct_quadrature(dim):
    h = 0.013
    table = W.wall_weight_table(h, dim)
    d = np.linspace(0.0, 2.0 * h, len(table))
    for k in (0, 37, 100, 160, 199):
        assert table[k] == pytest.approx(naive.plane_weight(d[k], h, dim), rel=2e-3, abs=1e-6 / h)
    if dim == 3:  # the in-plane radius against a square grid of the plane, at two distances
        for k in (0, 100):
            assert naive.plane_weight(d[k], h, 3, grid=True) == pytest.approx(table[k], rel=5e-3)
    # a half-space of fluid feels the wall once: integral of w over d in [0, 2h] = 1/2
    assert np.sum(0.5 * (table[1:] + table[:-1]) * np.diff(d)) == pytest.approx(0.5, rel=1e-5)


@pytest.mark.parametrize("dim", [2, 3])
def test_kernel_matches_numpy_twin_on_disordered_particles(dim):
    """Particles scattered near the floor and the x_max wall (corner included), random velocities.
    Tolerance: the linear interpolation of the 201-point w(d) table (relative 3e-3 where w is large;
    near d = 2h, where w ~ (2 - d/h)^4 is tiny, an absolute 1e-4 of the largest acceleration)."""
    rng = np.random.default_rng(7)
    h, dx = 0.013, 0.01
    n = 60 if dim == 2 else 25
    hi = 0.3
    x = rng.uniform(0.0, 0.04, (n, dim))
    x[:, 0] = hi - x[:, 0]  # near the x_max wall at 0.3 and the floor (axis 1) at 0
    v = rng.normal(0.0, 1.5, (n, dim))
    planes = np.array([(1, 0.0, 1.0), (0, hi, -1.0)])
    acc = np.zeros((n, dim))
    W.wall_function_acc(
        np.arange(n, dtype=np.int64), x, v, np.zeros(n, np.int64), np.array([NU]), planes, h, 0.5 * dx,
        W.wall_weight_table(h, dim), acc,
    )  # fmt: skip
    ref = naive.wall_function_acc(x, v, NU, planes, h, 0.5 * dx)
    assert np.count_nonzero(np.abs(ref).sum(axis=1)) > n // 2  # most particles are within 2h of a wall
    np.testing.assert_allclose(acc, ref, rtol=3e-3, atol=1e-4 * np.abs(ref).max())


def test_traction_on_a_log_law_profile_is_rho_u_star_squared():
    """A lattice of water over the floor moving with the log-law profile of one u*: every particle finds
    that u*, so the total force per unit wall length is -rho u*^2 up to the lattice's midpoint sum of
    w(d) (the lattice at d = (k + 1/2) dx against the integral 1/2: 0.1 % here)."""
    h, dx, us = 0.013, 0.01, 0.08
    ny, length = 6, 1.0
    ys = (np.arange(ny) + 0.5) * dx
    xs = (np.arange(int(length / dx)) + 0.5) * dx
    x = np.array([(a, b) for a in xs for b in ys])
    u = us / 0.41 * np.log(9.8 * x[:, 1] * us / NU)
    v = np.stack([u, np.zeros_like(u)], axis=1)
    acc = np.zeros_like(v)
    table = W.wall_weight_table(h, 2)
    W.wall_function_acc(np.arange(len(x), dtype=np.int64), x, v, np.zeros(len(x), np.int64), np.array([NU]),
                        np.array([(1, 0.0, 1.0)]), h, 0.5 * dx, table, acc)  # fmt: skip
    force = np.sum(RHO * dx * dx * acc[:, 0]) / length
    lattice_sum = dx * np.interp(ys, np.linspace(0, 2 * h, len(table)), table).sum()
    assert lattice_sum == pytest.approx(0.5, rel=2e-3)
    assert force == pytest.approx(-RHO * us * us * 2.0 * lattice_sum, rel=1e-6)
    assert force == pytest.approx(-RHO * us * us, rel=3e-3)


def _layer(walls):
    """A water layer 0.05 m deep over the floor, sliding at 1 m/s, no gravity."""
    raw = {
        "scene": {"name": "slide", "dimension": 2, "spacing": 0.01, "end_time": 0.01, "gravity": [0.0, 0.0]},
        "domain": {"min": [0.0, 0.0], "max": [1.0, 0.2]},
        "walls": {"y_min": walls, "x_min": "free_slip", "x_max": "free_slip"},
        "materials": {"water": {"model": "water", "density": RHO, "viscosity": NU * RHO,
                                "typical_velocity": 1.0}},
        "blocks": [{"name": "layer", "material": "water", "shape": "rectangle", "min": [0.3, 0.0],
                    "max": [0.7, 0.05]}],
        "output": {"interval": 0.01, "fields": ["velocity"], "vtk": False, "render": False,
                   "render_field": "speed"},
    }  # fmt: skip
    return Simulation(parse_scene(raw, "tests/test_wall_function.py"))


def test_the_term_is_planned_only_for_wall_function_walls_and_adds_the_twin_acceleration():
    assert _layer("free_slip").plan.term(WallFunctionShear) is None
    assert _layer("no_slip").plan.term(WallFunctionShear) is None
    accs = {}
    for walls in ("free_slip", "wall_function"):
        sim = _layer(walls)
        ps = sim.particles
        n = ps.n_owned
        ps["v"][:n] = [1.0, 0.0]
        sim.refresh(("v",))
        sim.compute_rates()
        accs[walls] = ps["acc"][:n].copy()
        x = ps["x"][:n].copy()
    term = _layer("wall_function").plan.term(WallFunctionShear)
    assert term is not None and term.planes.tolist() == [[1.0, 0.0, 1.0]]
    ref = naive.wall_function_acc(x, np.tile([1.0, 0.0], (len(x), 1)), NU, term.planes, 0.013, 0.005)
    np.testing.assert_allclose(accs["wall_function"] - accs["free_slip"], ref, rtol=3e-3,
                               atol=1e-4 * np.abs(ref).max())  # fmt: skip
    assert (ref[:, 0] < 0).sum() >= 40  # the floor's first layers (40 particles each) are slowed


def test_a_sliding_layer_loses_the_momentum_the_wall_traction_takes():
    """Momentum balance over a short run: the layer's x-momentum changes only by the wall traction (the
    pair terms and the floor's free-slip images exchange no net x-momentum), so its loss over 0.01 s
    equals the twin's total traction at the start times 0.01 s. The layer's speed changes by 0.05 % over
    the run, its traction (~ u*^2) by ~0.1 %: tolerance 0.5 % (measured 0.19 %, 31 steps)."""
    sim = _layer("wall_function")
    ps = sim.particles
    n = ps.n_owned
    ps["v"][:n] = ps["v_half"][:n] = [1.0, 0.0]  # the leap-frog's state is v_half
    sim.refresh(("v",))
    x0 = ps["x"][:n].copy()
    p0 = float((ps["mass"][:n] * ps["v"][:n, 0]).sum())
    term = sim.plan.term(WallFunctionShear)
    rate = float(
        (ps["mass"][:n] * naive.wall_function_acc(x0, ps["v"][:n], NU, term.planes, 0.013, 0.005)[:, 0]).sum()
    )
    end = sim.scene.scene.end_time
    while sim.t < end * (1 - 1e-12):
        sim.step(end - sim.t)
    sim.current_state()  # v at the end time
    p1 = float((ps["mass"][: ps.n_owned] * ps["v"][: ps.n_owned, 0]).sum())
    assert rate < 0
    assert (p1 - p0) / end == pytest.approx(rate, rel=5e-3)
