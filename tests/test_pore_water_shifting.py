"""The pore water's Fickian shifting (solver/physics/pore_water_shifting.py; Lind et al. 2012) against
its NumPy twin (tests/naive_seepage.py), and where the plan has it."""

import naive_seepage
import numpy as np
import pytest
from conftest import disordered_lattice

from solver.kernels import cubic_spline_normalisation
from solver.neighbors import CellGrid, CellList
from solver.physics.pore_water_shifting import apply_shift, pore_water_shift
from solver.plan import build_plan


def _water(rng, dim, n_side, dx=0.01, jitter=0.15):
    h = 1.3 * dx
    x = disordered_lattice(n_side, dim, dx, rng, jitter)
    n = len(x)
    rho = 1000.0 * (1 + rng.normal(0, 0.01, n))
    mass = np.full(n, 1000.0 * dx**dim)
    v = rng.normal(0, 0.01, (n, dim))
    label = np.where(rng.random(n) < 0.7, 0.4, 1.0)
    fixed = rng.random(n) < 0.1
    radius = 2 * h * 1.01
    cells = CellList(CellGrid.covering(np.zeros(dim), np.full(dim, n_side * dx), radius, pad=radius))
    cells.bin(x, n)
    nl = cells.neighbour_list(x, np.arange(n, dtype=np.int64), radius)
    return x, v, rho, mass, label, fixed, h, radius, nl


@pytest.mark.parametrize("dim", [2, 3])
def test_shift_matches_twin(rng, dim):
    """Pore water (label < 1) moves by -s A dt h |v| grad C; free water and wall particles do not;
    the blend s cuts it at the block's edges (C < 0.95)."""
    x, v, rho, mass, label, fixed, h, radius, nl = _water(rng, dim, 10 if dim == 2 else 6)
    coeff = 2.0 * 1e-4
    shift = np.zeros((len(x), 3))
    pore_water_shift(
        nl.targets, nl.start, nl.index, x, v, rho, mass, label, h, cubic_spline_normalisation(dim, h), coeff,
        shift, fixed, True if dim == 3 else None,
    )  # fmt: skip
    expected = naive_seepage.pore_water_shift(
        nl.targets, x, v, rho, mass, label, fixed, h, dim, radius, coeff
    )
    scale = np.abs(expected).max()
    assert scale > 0.0
    np.testing.assert_allclose(shift[:, :dim], expected, rtol=1e-10, atol=1e-12 * scale)
    assert not shift[label >= 1.0].any() and not shift[fixed].any()
    moved = x.copy()
    apply_shift(nl.targets, moved, shift, True if dim == 3 else None)
    np.testing.assert_array_equal(moved, x + shift[:, :dim])


def test_no_shift_on_a_lattice_or_at_rest(rng):
    """A uniform lattice has grad C = 0 inside (so a pore water that keeps its order is never moved),
    and still water is never moved: a bed at rest is unchanged."""
    x, v, rho, mass, label, fixed, h, radius, nl = _water(rng, 2, 12, jitter=0.0)
    rho[:] = 1000.0
    shift = np.zeros((len(x), 3))
    norm = cubic_spline_normalisation(2, h)
    pore_water_shift(nl.targets, nl.start, nl.index, x, v, rho, mass, label, h, norm, 2e-4, shift, fixed)
    inside = np.all((x > 3 * h) & (x < 0.12 - 3 * h), axis=1)
    assert np.abs(shift[inside]).max() < 1e-12 * np.abs(shift).max()
    pore_water_shift(
        nl.targets, nl.start, nl.index, x, np.zeros_like(v), rho, mass, label, h, norm, 2e-4, shift, fixed
    )
    assert not shift.any()


def test_shifting_only_in_scenes_with_pore_water():
    """Water-only and soil-only plans, and a scene with water and soil but no saturated block, have no
    shifting term (their plans are unchanged); a saturated bed has it in both formulations."""
    import tomllib

    from test_seepage import BOX

    from solver.scene import parse_scene
    from verification.column_collapse import scene_at
    from verification.common import scene_from_file

    for scene in (scene_from_file("hydrostatic_tank_2d.toml"), scene_at(0.01, end_time=0.01)):
        assert "pore water shifting" in build_plan(scene).absent
    for form in ("mixture", "seed"):
        text = BOX.replace("{form}", form)
        wet = parse_scene(tomllib.loads(text), "b")
        assert "pore water shifting" in {t.name for t in build_plan(wet).terms}
        dry = parse_scene(tomllib.loads(text.replace("saturated = true\n", "")), "b")
        assert "pore water shifting" not in {t.name for t in build_plan(dry).terms}
