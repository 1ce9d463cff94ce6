"""Cell-linked list and Verlet neighbour lists: the only neighbour search.

Particles are binned into cells of side >= the list radius (2h + skin), counting-sorted
by cell (O(N)), and each target particle scans the 3^dim surrounding cells. Lists are
compressed rows (start, index); they stay valid until some particle has moved more than
half the skin (Verlet 1967; LAMMPS' "neighbor ... check yes").
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from numba import prange

from .config import kernel
from .kernels import SUPPORT_RADIUS


@dataclass
class CellGrid:
    origin: np.ndarray  # lower corner (float64[dim])
    cell_size: float
    shape: np.ndarray  # cells per axis (int64[dim])
    offsets: np.ndarray  # neighbour-cell offsets, int64[3^dim, dim]

    @classmethod
    def covering(cls, lo, hi, radius, pad):
        lo = np.asarray(lo, float) - pad
        hi = np.asarray(hi, float) + pad
        shape = np.maximum(np.ceil((hi - lo) / radius).astype(np.int64), 1)
        dim = len(lo)
        offsets = np.array(list(itertools.product((-1, 0, 1), repeat=dim)), dtype=np.int64)
        return cls(lo, float(radius), shape, offsets)

    @property
    def n_cells(self):
        return int(np.prod(self.shape))


@kernel(parallel=True)
def cell_of(x, n, origin, cell_size, shape, out):
    """Linear cell index of each of the first n particles (clamped into the grid)."""
    dim = x.shape[1]
    for i in prange(n):
        c = 0
        stride = 1
        for d in range(dim):
            k = int(np.floor((x[i, d] - origin[d]) / cell_size))
            k = min(max(k, 0), shape[d] - 1)
            c += k * stride
            stride *= shape[d]
        out[i] = c


@kernel
def counting_sort(cells, n, n_cells, cell_start, order):
    """cell_start[c]..cell_start[c+1] are the positions in `order` of the particles in cell c."""
    cell_start[:] = 0
    for i in range(n):
        cell_start[cells[i] + 1] += 1
    for c in range(n_cells):
        cell_start[c + 1] += cell_start[c]
    fill = cell_start[:-1].copy()
    for i in range(n):
        c = cells[i]
        order[fill[c]] = i
        fill[c] += 1


@kernel(parallel=True)
def _scan(
    targets, x, cells, cell_start, order, shape, offsets, radius2, phase, want, counts_or_start, index=None
):
    """One scan of the 3^dim cells around each target. With index=None it counts the
    neighbours into counts_or_start[t]; with an index array it writes them from
    counts_or_start[t] up to counts_or_start[t + 1] (the counts' prefix sum; Numba compiles the
    two variants separately). Cells are visited in the order of `offsets` and each cell's rows in
    binned order, so the lists, and every pair sum, keep one order (tests/test_neighbors.py).
    Branch-free: every candidate is written at the next free slot and the slot is kept only when
    it lies within the radius (a third of the candidates do, at random: the branch on r2 cost
    about 40 % of the scan's time); the fill stops when the target's
    count is reached, so no write reaches another target's slots. The target's cell coordinates
    are taken apart once, not once per neighbour cell (13 % of the scan in integer divisions)."""
    dim = x.shape[1]
    n0 = shape[0]
    n1 = shape[1] if dim > 1 else 1
    n2 = shape[2] if dim > 2 else 1
    for t in prange(targets.shape[0]):
        i = targets[t]
        m = 0 if index is None else counts_or_start[t]
        end = 0 if index is None else counts_or_start[t + 1]
        c = cells[i]
        k0 = c % n0
        k1 = (c // n0) % n1
        k2 = c // (n0 * n1)
        for o in range(offsets.shape[0]):
            if index is not None and m == end:
                break
            a0 = k0 + offsets[o, 0]
            a1 = k1 + offsets[o, 1] if dim > 1 else 0
            a2 = k2 + offsets[o, 2] if dim > 2 else 0
            if a0 < 0 or a0 >= n0 or a1 < 0 or a1 >= n1 or a2 < 0 or a2 >= n2:
                continue
            nc = a0 + n0 * (a1 + n1 * a2)
            for s in range(cell_start[nc], cell_start[nc + 1]):
                j = order[s]
                if j == i or (want >= 0 and phase[j] != want):
                    continue
                r2 = 0.0
                for d in range(dim):
                    dx = x[i, d] - x[j, d]
                    r2 += dx * dx
                if index is not None:
                    if m == end:
                        break
                    index[m] = j
                m += 1 if r2 < radius2 else 0
        if index is None:
            counts_or_start[t] = m


@dataclass
class NeighbourList:
    """Compressed rows: neighbours of targets[t] are index[start[t]:start[t+1]]."""

    targets: np.ndarray  # int64 particle rows whose rates this list serves
    start: np.ndarray  # int64[len(targets) + 1]
    index: np.ndarray  # int32 neighbour rows (half the memory traffic of int64)

    def pairs(self):
        return len(self.index)

    def unsigned(self):
        """(start, index) viewed as uint64 and uint32, no copy. A Numba pair loop indexed with
        these loads a row's neighbours as a plain vector and gathers with them without the
        negative-index wrap-around that a signed index brings (a sign test and fix-up per lane and
        a gather for the index itself): the soil rates pass took 27 % less time (one thread)."""
        return self.start.view(np.uint64), self.index.view(np.uint32)


class CellList:
    """Binning of all local rows (owned, ghosts, images) into a CellGrid."""

    def __init__(self, grid: CellGrid):
        self.grid = grid
        self.cell_start = np.zeros(grid.n_cells + 1, dtype=np.int64)
        self.cells = np.zeros(0, dtype=np.int64)
        self.order = np.zeros(0, dtype=np.int64)
        self.n = 0

    def bin(self, x, n):
        if len(self.cells) < n:
            self.cells = np.zeros(int(n * 1.5) + 16, dtype=np.int64)
            self.order = np.zeros_like(self.cells)
        g = self.grid
        cell_of(x, n, g.origin, g.cell_size, g.shape, self.cells)
        counting_sort(self.cells, n, g.n_cells, self.cell_start, self.order)
        self.n = n

    def neighbour_list(self, x, targets, radius, phase=None, want_phase=-1) -> NeighbourList:
        """Rows j != i within `radius` of each target i (optionally only of phase want_phase)."""
        g = self.grid
        if phase is None:
            phase = np.zeros(1, dtype=np.int32)
            want_phase = -1
        counts = np.empty(len(targets), dtype=np.int64)
        args = (
            x,
            self.cells,
            self.cell_start,
            self.order,
            g.shape,
            g.offsets,
            radius * radius,
            phase,
            want_phase,
        )
        _scan(targets, *args, counts)
        start = np.zeros(len(targets) + 1, dtype=np.int64)
        np.cumsum(counts, out=start[1:])
        index = np.empty(start[-1], dtype=np.int32)
        _scan(targets, *args, start, index)
        return NeighbourList(targets, start, index)

    def owned_cell_order(self, n_owned):
        """Permutation putting the first n_owned rows in cell order (stable)."""
        return np.argsort(self.cells[:n_owned], kind="stable")


def verlet_radius(scene):
    """Radius of the Verlet lists: the kernel support 2h plus the skin (numerics.neighbour_skin)."""
    return SUPPORT_RADIUS * scene.h + scene.numerics.neighbour_skin * scene.h
