"""Recursive coordinate bisection (RCB) of the domain among ranks, balanced on particle count.

Each node of the bisection tree holds a contiguous range of ranks [r0, r0 + nr) and a box.
It is cut across its longest side (so a long tank is cut into slabs first; with more ranks
the cuts alternate as the boxes become square) at the coordinate that leaves
floor(nr/2)/nr of the node's particles on the low side. The coordinate is found from
histograms of the particle positions summed over all ranks (one Allreduce of
nodes x BINS counts per pass, two passes: the second resolves the bin the first picked), so
no rank ever sees another rank's particles. Any rank count works (3 ranks: 1 | 2, ...).

Owner boxes are half open, [lo, hi), and the faces on the domain boundary are at -inf/+inf so
every finite position has exactly one owner (a particle that flew out of the box is caught by
the solver's state check, not lost here).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BINS = 1024


@dataclass
class Decomposition:
    lo: np.ndarray  # (size, dim) owner boxes, -inf on the domain's lower faces
    hi: np.ndarray  # (size, dim) +inf on the domain's upper faces
    region_lo: np.ndarray  # (size, dim) the same boxes clipped to the domain (for reports)
    region_hi: np.ndarray

    @property
    def size(self):
        return self.lo.shape[0]

    def owner(self, x: np.ndarray, default: int) -> np.ndarray:
        """Rank owning each row of x (vectorised over particles, a loop over ranks).
        Rows with NaN coordinates keep `default` (the state check reports them)."""
        out = np.full(len(x), default, dtype=np.int64)
        for r in range(self.size):
            inside = np.all((x >= self.lo[r]) & (x < self.hi[r]), axis=1)
            out[inside] = r
        return out

    def near(self, x: np.ndarray, rank: int, reach: float) -> np.ndarray:
        """Mask of rows of x closer than `reach` to box `rank` (Euclidean distance to the box)."""
        d = np.maximum(np.maximum(self.lo[rank] - x, x - self.hi[rank]), 0.0)
        return np.einsum("ij,ij->i", d, d) < reach * reach

    def cuts_summary(self):
        return [(self.region_lo[r].tolist(), self.region_hi[r].tolist()) for r in range(self.size)]


def bisect(x: np.ndarray, size: int, domain_lo, domain_hi, allreduce=None) -> Decomposition:
    """RCB of the particles at rows x (this rank's share) into `size` boxes.

    allreduce(counts) sums an int64 array over ranks; None means x already holds every
    particle (the replicated set-up, where every rank computes the same cuts alone)."""
    dim = x.shape[1]
    domain_lo = np.asarray(domain_lo, float)
    domain_hi = np.asarray(domain_hi, float)
    reduce = allreduce or (lambda a: a)
    lo = np.tile(-np.inf, (size, dim))
    hi = np.tile(np.inf, (size, dim))
    rlo = np.tile(domain_lo, (size, 1))
    rhi = np.tile(domain_hi, (size, 1))
    # nodes: (first rank, number of ranks); label: node of each particle
    nodes = [(0, size)]
    label = np.zeros(len(x), dtype=np.int64)
    while any(nr > 1 for _, nr in nodes):
        k = len(nodes)
        axes = np.array([int(np.argmax(rhi[r0] - rlo[r0])) for r0, _ in nodes])
        a_lo = np.array([rlo[r0, axes[i]] for i, (r0, _) in enumerate(nodes)])
        a_hi = np.array([rhi[r0, axes[i]] for i, (r0, _) in enumerate(nodes)])
        frac = np.array([(nr // 2) / nr for _, nr in nodes])
        coord = x[np.arange(len(x)), axes[label]] if len(x) else np.zeros(0)
        # pass 1: histogram over the node's extent; pass 2: over the chosen bin
        width = (a_hi - a_lo) / BINS
        counts = _node_histogram(coord, label, a_lo, width, k, reduce)
        total = counts.sum(axis=1)
        target = frac * total
        cum = np.cumsum(counts, axis=1)
        b = np.array([min(int(np.searchsorted(cum[i], target[i], side="left")), BINS - 1) for i in range(k)])
        below = np.array([cum[i, b[i] - 1] if b[i] > 0 else 0 for i in range(k)])
        sub_lo = a_lo + b * width
        sub_w = width / BINS
        in_bin = (coord >= sub_lo[label]) & (coord < sub_lo[label] + width[label])
        counts2 = _node_histogram(np.where(in_bin, coord, np.inf), label, sub_lo, sub_w, k, reduce)
        cum2 = below[:, None] + np.cumsum(counts2, axis=1)
        c = np.array([min(int(np.searchsorted(cum2[i], target[i], side="left")), BINS - 1) for i in range(k)])
        cut = sub_lo + (c + 1) * sub_w  # upper edge of the sub-bin where the target is reached
        cut = np.where(total > 0, cut, 0.5 * (a_lo + a_hi))
        new_nodes = []
        new_label = np.empty_like(label)
        for i, (r0, nr) in enumerate(nodes):
            mine = label == i
            if nr == 1:
                new_label[mine] = len(new_nodes)
                new_nodes.append((r0, nr))
                continue
            n_left = nr // 2
            ax = axes[i]
            left = slice(r0, r0 + n_left)
            right = slice(r0 + n_left, r0 + nr)
            hi[left, ax] = cut[i]
            rhi[left, ax] = cut[i]
            lo[right, ax] = cut[i]
            rlo[right, ax] = cut[i]
            go_right = mine & (coord >= cut[i])
            new_label[mine & ~go_right] = len(new_nodes)
            new_label[go_right] = len(new_nodes) + 1
            new_nodes += [(r0, n_left), (r0 + n_left, nr - n_left)]
        nodes, label = new_nodes, new_label
    return Decomposition(lo, hi, rlo, rhi)


def _node_histogram(coord, label, start, width, k, reduce):
    """Counts (k, BINS) of coord in [start, start + BINS width) per node label, summed over ranks;
    coordinates outside are clamped into the end bins (inf: dropped)."""
    finite = np.isfinite(coord)
    rel = (coord[finite] - start[label[finite]]) / width[label[finite]]
    bins = np.clip(np.floor(rel), 0, BINS - 1).astype(np.int64)
    local = np.bincount(label[finite] * BINS + bins, minlength=k * BINS).astype(np.int64)
    return np.asarray(reduce(local)).reshape(k, BINS)
