"""The decomposition and packing pieces of solver/parallel, in one process (no mpirun):
recursive bisection against obvious NumPy twins."""

from __future__ import annotations

import numpy as np
import pytest

from solver.parallel.decomposition import bisect
from solver.parallel.packing import pack, row_layout, unpack, unpack_dict

LO, HI = np.array([0.0, 0.0]), np.array([0.4572, 0.17145])


def _column(n_side=60, seed=1):
    """A disordered dam-break-like column: all particles in the left eighth of the tank."""
    rng = np.random.default_rng(seed)
    dx = 0.05715 / n_side
    g = np.stack(
        np.meshgrid((np.arange(n_side) + 0.5) * dx, (np.arange(2 * n_side) + 0.5) * dx, indexing="ij"), -1
    )
    return g.reshape(-1, 2) + rng.uniform(-0.2, 0.2, (2 * n_side * n_side, 2)) * dx


@pytest.mark.parametrize("size", [1, 2, 3, 4, 5, 8])
def test_bisection_balances_and_covers(size):
    x = _column()
    d = bisect(x, size, LO, HI)
    owner = d.owner(x, -1)
    assert (owner >= 0).all()
    counts = np.bincount(owner, minlength=size)
    # balanced to within the particles of one fine histogram bin per cut level (~ a few)
    assert counts.max() - counts.min() <= 2 * int(np.ceil(np.log2(size))) + 2, counts
    # every point of space has exactly one owner (half-open boxes, infinite outer faces)
    probe = np.random.default_rng(2).uniform(LO - 0.1, HI + 0.1, (20000, 2))
    inside = np.stack([np.all((probe >= d.lo[r]) & (probe < d.hi[r]), axis=1) for r in range(size)])
    assert (inside.sum(axis=0) == 1).all()


def test_two_ranks_cut_the_long_axis_and_follow_the_flow():
    x = _column()
    d0 = bisect(x, 2, LO, HI)
    assert d0.hi[0, 0] == d0.lo[1, 0] and np.isinf(d0.hi[0, 1])  # a slab cut across x
    moved = x.copy()
    moved[:, 0] *= 4.0  # the water has spread along the tank
    d1 = bisect(moved, 2, LO, HI)
    assert d1.hi[0, 0] > 3.5 * d0.hi[0, 0]


def test_replicated_and_distributed_cuts_agree():
    """Cuts from the whole set on one rank (the start-up path) equal the cuts that three
    'ranks' holding shares find with summed histograms (threads stand in for MPI ranks)."""
    import threading

    x = _column()
    whole = bisect(x, 4, LO, HI)
    shares = np.array_split(np.random.default_rng(3).permutation(len(x)), 3)
    barrier = threading.Barrier(3)
    slots, results = [None] * 3, [None] * 3

    def rank(k):
        def allreduce(local):
            slots[k] = local
            barrier.wait()
            total = sum(slots)
            barrier.wait()
            return total

        results[k] = bisect(x[shares[k]], 4, LO, HI, allreduce=allreduce)

    threads = [threading.Thread(target=rank, args=(k,)) for k in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for res in results:
        np.testing.assert_array_equal(res.lo, whole.lo)
        np.testing.assert_array_equal(res.hi, whole.hi)


def test_near_matches_brute_force():
    x = _column()
    d = bisect(x, 3, LO, HI)
    reach = 0.004
    for r in range(3):
        mask = d.near(x, r, reach)
        clipped = np.clip(x, d.lo[r], d.hi[r])  # nearest point of box r
        brute = np.linalg.norm(x - clipped, axis=1) < reach
        np.testing.assert_array_equal(mask, brute)


def test_pack_unpack_round_trip_mixed_dtypes():
    rng = np.random.default_rng(4)
    n = 50
    arrays = {
        "x": rng.normal(size=(n, 2)),
        "rho": rng.normal(size=n),
        "id": np.arange(n, dtype=np.int64) * 7,
        "material": rng.integers(0, 3, n).astype(np.int32),
        "fixed": rng.random(n) < 0.5,
        "tau": rng.normal(size=(n, 6)),
    }
    names = list(arrays)
    layout = row_layout(arrays, names)
    rows = np.array([3, 7, 7, 0, 49])
    buf = pack(arrays, layout, rows)
    assert buf.dtype == np.uint8 and buf.flags.c_contiguous
    out = {k: np.zeros_like(v) for k, v in arrays.items()}
    unpack(buf, out, layout, 10)
    for k in names:
        np.testing.assert_array_equal(out[k][10:15], arrays[k][rows])
    d = unpack_dict(
        buf, {k: v.dtype for k, v in arrays.items()}, {k: v.shape[1:] for k, v in arrays.items()}, layout
    )
    for k in names:
        np.testing.assert_array_equal(d[k], arrays[k][rows])
    empty = pack(arrays, layout, np.zeros(0, dtype=np.int64))
    assert empty.shape == (0, buf.shape[1])
