"""Leap-frog exactness and particle bookkeeping (ids survive every reordering)."""

import numpy as np
import pytest

from solver.particles import FieldSpec, ParticleSet
from solver.simulation import Simulation
from verification.common import scene_from_file


def test_free_fall_is_exact_with_variable_steps():
    """Kick-drift leap-frog with kick weight (dt_prev + dt)/2 integrates constant acceleration
    exactly for any sequence of steps: x = x0 - g t^2 / 2 to round-off, at output times
    that force shortened steps."""
    scene = scene_from_file(
        "dam_break_2d.toml",
        **{
            "scene.spacing": 0.01,
            "domain.max": [0.2, 0.5],
            "blocks": [
                {
                    "name": "drop",
                    "material": "water",
                    "shape": "rectangle",
                    "min": [0.09, 0.4],
                    "max": [0.1, 0.411],
                }
            ],
            "walls": {},
        },
    )
    sim = Simulation(scene)
    assert sim.particles.n_owned == 1
    y0 = sim.particles["x"][0, 1]
    for t in (0.0123, 0.05, 0.0777, 0.1):
        sim.advance_to(t)
        assert sim.particles["x"][0, 1] == pytest.approx(y0 - 0.5 * 9.81 * t * t, abs=1e-12)


def specs():
    return {
        "x": FieldSpec(2, np.float64, ""),
        "id": FieldSpec(0, np.int64, ""),
        "mass": FieldSpec(0, np.float64, ""),
    }


def test_append_remove_permute_keep_ids():
    ps = ParticleSet(2, specs(), capacity=4)
    ps.append_owned(x=np.zeros((10, 2)), mass=np.arange(10.0))
    assert ps.capacity >= 10 and ps["id"][:10].tolist() == list(range(10))
    ps.remove_owned(ps.owned("mass") % 2 == 0)  # outflow of odd ones
    assert ps.owned("id").tolist() == [0, 2, 4, 6, 8]
    ps.append_owned(x=np.ones((3, 2)), mass=np.full(3, -1.0))  # inflow gets fresh ids
    assert ps.owned("id").tolist() == [0, 2, 4, 6, 8, 10, 11, 12]
    ps.permute_owned(np.array([7, 6, 5, 4, 3, 2, 1, 0]))
    assert ps.owned("id").tolist() == [12, 11, 10, 8, 6, 4, 2, 0]
    np.testing.assert_array_equal(ps.owned("mass")[:3], -1.0)


def test_rebuild_reorders_by_cell_without_losing_particles():
    sim = Simulation(scene_from_file("dam_break_2d.toml", **{"scene.spacing": 0.05715 / 10}))
    ids = np.sort(sim.particles.owned("id"))
    for _ in range(200):
        sim.step()
    assert sim.rebuilds > 1
    np.testing.assert_array_equal(np.sort(sim.particles.owned("id")), ids)


def test_polygon_block_fills_its_area():
    """A triangle of legs L on the dx lattice holds area / dx^2 particles to within one
    lattice row along the hypotenuse (L / dx particles)."""
    from solver.geometry import block_points

    L, dx = 0.1, 0.0025
    scene = scene_from_file(
        "dam_break_2d.toml",
        **{
            "scene.spacing": dx,
            "blocks": [
                {
                    "name": "wedge",
                    "material": "water",
                    "shape": "polygon",
                    "vertices": [[0.0, 0.0], [L, 0.0], [0.0, L]],
                }
            ],
        },
    )
    pts = block_points(scene.blocks[0], scene)
    assert abs(len(pts) - 0.5 * L * L / dx**2) <= L / dx
    assert np.all(pts[:, 0] + pts[:, 1] <= L)


def test_no_recompilation_inside_the_time_loop():
    """Every kernel is compiled by the first step; hundreds of steps with neighbour
    rebuilds, output-time landings and image changes add no new specialisation."""
    import importlib

    from numba.core.registry import CPUDispatcher

    import solver.integrate
    import solver.neighbors
    from solver.physics import TERMS

    def compiled():
        terms = [importlib.import_module(cls.__module__) for cls in TERMS]
        mods = (solver.integrate, solver.neighbors, *terms)
        return {
            (m.__name__, n): len(f.signatures)
            for m in mods
            for n, f in vars(m).items()
            if isinstance(f, CPUDispatcher)
        }

    sim = Simulation(scene_from_file("dam_break_2d.toml", **{"scene.spacing": 0.05715 / 10}))
    sim.step()
    sim.current_state()
    before = compiled()
    sim.advance_to(0.02)
    sim.current_state()
    rebuilds = sim.rebuilds
    sim.advance_to(0.05)
    assert sim.rebuilds > rebuilds
    assert compiled() == before


def test_state_status_sees_nan_and_inf_in_every_field():
    """The blow-up check against its NumPy twin. A regression guard: compiled with the project's
    fastmath flags, np.isfinite folded to True, so a NaN velocity or density went unseen and a
    NaN position was reported as "outside the domain"."""
    from solver.integrate import STATE_NOT_FINITE, STATE_OK, STATE_OUTSIDE, state_status

    def twin(x, v, rho, lo, hi):
        if not (np.isfinite(x).all() and np.isfinite(v).all() and np.isfinite(rho).all()):
            return (
                STATE_NOT_FINITE if not ((x < lo) | (x > hi)).any() else max(STATE_NOT_FINITE, STATE_OUTSIDE)
            )
        return STATE_OUTSIDE if ((x < lo) | (x > hi)).any() else STATE_OK

    lo, hi = np.zeros(2), np.ones(2)
    base = (np.full((4, 2), 0.5), np.zeros((4, 2)), np.ones(4))
    cases = {
        "ok": (),
        "nan v": (("v", (2, 0), np.nan),),
        "inf v": (("v", (1, 1), np.inf),),
        "nan x": (("x", (3, 1), np.nan),),
        "nan rho": (("rho", (0,), np.nan),),
        "outside": (("x", (0, 0), 1.5),),
    }
    for name, edits in cases.items():
        x, v, rho = (a.copy() for a in base)
        arrays = {"x": x, "v": v, "rho": rho}
        for field, index, value in edits:
            arrays[field][index] = value
        assert state_status(4, x, v, rho, lo, hi) == twin(x, v, rho, lo, hi), name
    assert (
        state_status(4, *[a.copy() for a in base[:2]], np.array([np.nan, 1, 1, 1]), lo, hi)
        == STATE_NOT_FINITE
    )


def test_nan_velocity_stops_a_serial_run_with_what_where_when():
    from solver.errors import BlowUpError

    sim = Simulation(scene_from_file("dam_break_2d.toml", **{"scene.spacing": 0.05715 / 10}))
    sim.step()
    sim.particles["v_half"][3, 0] = np.nan
    with pytest.raises(BlowUpError) as info:
        sim.step()
    text = str(info.value)
    assert "non-finite state" in text and "particle id" in text and "step 2" in text
