"""Cell-linked list + Verlet list against brute force, in 1D, 2D and 3D."""

import naive
import numpy as np
import pytest
from conftest import disordered_lattice

from solver.neighbors import CellGrid, CellList


@pytest.mark.parametrize("dim,n_side", [(1, 200), (2, 30), (3, 9)])
def test_same_pairs_as_brute_force(dim, n_side, rng):
    dx = 0.01
    x = disordered_lattice(n_side, dim, dx, rng, jitter=0.45)
    radius = 2.6 * dx
    cells = CellList(CellGrid.covering(np.zeros(dim), np.full(dim, n_side * dx), radius, pad=radius))
    cells.bin(x, len(x))
    targets = np.arange(len(x), dtype=np.int64)
    nl = cells.neighbour_list(x, targets, radius)
    expected = naive.neighbours(x, targets, radius)
    for t in range(len(targets)):
        assert sorted(nl.index[nl.start[t] : nl.start[t + 1]].tolist()) == expected[t]


def test_phase_filter_and_targets_subset(rng):
    x = disordered_lattice(20, 2, 0.01, rng)
    phase = (rng.random(len(x)) < 0.5).astype(np.int32)
    cells = CellList(CellGrid.covering([0, 0], [0.2, 0.2], 0.026, pad=0.026))
    cells.bin(x, len(x))
    targets = np.flatnonzero(phase == 0).astype(np.int64)
    nl = cells.neighbour_list(x, targets, 0.026, phase, want_phase=1)
    for t, i in enumerate(targets):
        got = sorted(nl.index[nl.start[t] : nl.start[t + 1]].tolist())
        assert got == [j for j in naive.neighbours(x, [i], 0.026)[0] if phase[j] == 1]


def test_cost_is_linear_in_particle_count(rng):
    """O(N): candidates examined per particle do not grow with N (pairs per particle constant)."""
    per_particle = []
    for n_side in (20, 40, 80):
        x = disordered_lattice(n_side, 2, 0.01, rng)
        cells = CellList(CellGrid.covering([0, 0], [n_side * 0.01] * 2, 0.026, pad=0.026))
        cells.bin(x, len(x))
        nl = cells.neighbour_list(x, np.arange(len(x), dtype=np.int64), 0.026)
        per_particle.append(nl.pairs() / len(x))
    # grows only through the shrinking share of boundary particles (fewer neighbours)
    assert per_particle[0] <= per_particle[1] <= per_particle[2] < 1.1 * per_particle[0] + 1
