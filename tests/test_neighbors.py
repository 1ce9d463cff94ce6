"""Cell-linked list + Verlet list against brute force, in 1D, 2D and 3D."""

import naive
import numpy as np
import pytest
from conftest import disordered_lattice

from solver import neighbors
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


class CountingPositions:
    """Positions that count their reads: the search reads x[i, d] and x[j, d] once per axis for
    every candidate pair whose distance it evaluates, so reads / (2 dim) is the number of
    distance evaluations, a count independent of time and machine."""

    def __init__(self, x):
        self.x, self.shape, self.reads = x, x.shape, 0

    def __getitem__(self, key):
        self.reads += 1
        return self.x[key]


def test_cost_is_linear_in_particle_count(rng, monkeypatch):
    """O(N): the distance evaluations per particle of a neighbour search stay bounded as N
    grows 16x. The search runs as written (CellList.neighbour_list calling the Python source
    of its Numba scan, on positions that count their reads). An all-pairs search would evaluate
    N - 1 distances per particle, 1599 at N = 1600; the cell list evaluates those in the 3^2
    cells around a particle's own, about 9 x (2.6 dx)^2 / dx^2 = 61 here."""
    monkeypatch.setattr(neighbors, "_scan", neighbors._scan.py_func)
    per_particle = []
    for n_side in (10, 20, 40):
        x = disordered_lattice(n_side, 2, 0.01, rng)
        cells = CellList(CellGrid.covering([0, 0], [n_side * 0.01] * 2, 0.026, pad=0.026))
        cells.bin(x, len(x))
        counting = CountingPositions(x)
        nl = cells.neighbour_list(counting, np.arange(len(x), dtype=np.int64), 0.026)
        assert nl.pairs() == sum(len(n) for n in naive.neighbours(x, np.arange(len(x)), 0.026))
        evaluations = counting.reads / (2 * 2) / 2  # 2 reads per axis, 2 axes, 2 passes (count, fill)
        per_particle.append(evaluations / len(x))
    print("distance evaluations per particle", per_particle)
    # bounded by the 9-cell stencil (edge particles see fewer cells, so it rises towards the bound)
    assert max(per_particle) < 9 * 2.6**2 * 1.2, per_particle
    assert per_particle[2] < 1.2 * per_particle[1], per_particle


@pytest.mark.parametrize("dim,n_side", [(1, 60), (2, 20), (3, 7)])
def test_list_order_is_that_of_the_cell_offsets(dim, n_side, rng):
    """The scan visits the neighbour cells in the order of CellGrid.offsets and each cell's rows
    in binned order: a NumPy twin that takes every neighbour cell's coordinates apart gives the
    same lists element for element (the order fixes every pair sum's round-off)."""
    dx = 0.01
    x = disordered_lattice(n_side, dim, dx, rng, jitter=0.45)
    radius = 2.6 * dx
    grid = CellGrid.covering(np.zeros(dim), np.full(dim, n_side * dx), radius, pad=radius)
    cells = CellList(grid)
    cells.bin(x, len(x))
    targets = rng.permutation(len(x)).astype(np.int64)
    nl = cells.neighbour_list(x, targets, radius)
    strides = np.cumprod(np.concatenate([[1], grid.shape[:-1]]))
    for t, i in enumerate(targets):
        k = (cells.cells[i] // strides) % grid.shape
        expected = []
        for off in grid.offsets:
            a = k + off
            if np.any(a < 0) or np.any(a >= grid.shape):
                continue
            c = int(a @ strides)
            for j in cells.order[cells.cell_start[c] : cells.cell_start[c + 1]]:
                if j != i and np.sum((x[i] - x[j]) ** 2) < radius**2:
                    expected.append(j)
        assert nl.index[nl.start[t] : nl.start[t + 1]].tolist() == expected
