"""The calibration kernel of the benchmark gate (benchmarks/gate.py).

This host's speed varies by 2x within an hour (other jobs share its 2 cores), so a benchmark's
time alone says little. Each gate benchmark is timed interleaved with this kernel, and the gate
compares the ratio benchmark time / calibration time, which the host's speed largely cancels.

The kernel has the profile of an SPH pass: for each of n jittered 2D particles, a gather
over a fixed Verlet list (about 21 neighbours at h = 1.3 dx, support 2h) reading position,
velocity and density of the neighbour, a cubic-spline weight and gradient, and three
accumulations (density rate, acceleration with a pressure and an artificial-viscosity-like
term). It must never change: it is built from its own code and a fixed seed, and imports
nothing from the solver, so that a change in the solver moves the benchmarks and not the yardstick.
"""

from __future__ import annotations

import time

import numba
import numpy as np

N_SIDE = 158  # 158 x 158 = 24,964 particles (the gate makes one per benchmark size, `calibration(n)`)
H_OVER_DX = 1.3
SEED = 20261124


@numba.njit(cache=True)
def _cell_list_pairs(x, radius, n_cells_x, n_cells_y):
    """CSR neighbour list (start, index) of every particle within `radius`, by a cell grid."""
    n = x.shape[0]
    cx = np.minimum((x[:, 0] / radius).astype(np.int64), n_cells_x - 1)
    cy = np.minimum((x[:, 1] / radius).astype(np.int64), n_cells_y - 1)
    cell = cx * n_cells_y + cy
    order = np.argsort(cell)
    first = np.full(n_cells_x * n_cells_y + 1, n, np.int64)
    for k in range(n - 1, -1, -1):
        first[cell[order[k]]] = k
    for c in range(n_cells_x * n_cells_y - 1, -1, -1):
        if first[c] > first[c + 1]:
            first[c] = first[c + 1]
    counts = np.zeros(n, np.int64)
    r2 = radius * radius
    for i in range(n):
        for a in range(max(cx[i] - 1, 0), min(cx[i] + 2, n_cells_x)):
            for b in range(max(cy[i] - 1, 0), min(cy[i] + 2, n_cells_y)):
                c = a * n_cells_y + b
                for k in range(first[c], first[c + 1]):
                    j = order[k]
                    d0, d1 = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1]
                    if j != i and d0 * d0 + d1 * d1 < r2:
                        counts[i] += 1
    start = np.zeros(n + 1, np.int64)
    start[1:] = np.cumsum(counts)
    index = np.empty(start[-1], np.int64)
    fill = start[:-1].copy()
    for i in range(n):
        for a in range(max(cx[i] - 1, 0), min(cx[i] + 2, n_cells_x)):
            for b in range(max(cy[i] - 1, 0), min(cy[i] + 2, n_cells_y)):
                c = a * n_cells_y + b
                for k in range(first[c], first[c + 1]):
                    j = order[k]
                    d0, d1 = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1]
                    if j != i and d0 * d0 + d1 * d1 < r2:
                        index[fill[i]] = j
                        fill[i] += 1
    return start, index


@numba.njit(cache=True, fastmath=True)
def pair_sum(start, index, x, v, rho, mass, h, drho, acc):
    """One SPH-like gather pass (the calibration workload)."""
    n = start.shape[0] - 1
    inv_h = 1.0 / h
    norm = 10.0 / (7.0 * np.pi * h * h)
    for i in range(n):
        d_rho = 0.0
        a0 = 0.0
        a1 = 0.0
        pi_ = 1.0 + rho[i] * 0.01
        for k in range(start[i], start[i + 1]):
            j = index[k]
            d0 = x[i, 0] - x[j, 0]
            d1 = x[i, 1] - x[j, 1]
            r = np.sqrt(d0 * d0 + d1 * d1) + 1e-12
            q = r * inv_h
            if q < 1.0:
                dw = norm * inv_h * (-3.0 * q + 2.25 * q * q)
            else:
                dw = -norm * inv_h * 0.75 * (2.0 - q) * (2.0 - q)
            u0 = v[i, 0] - v[j, 0]
            u1 = v[i, 1] - v[j, 1]
            vr = u0 * d0 + u1 * d1
            visc = 0.0
            if vr < 0.0:
                mu = h * vr / (r * r + 0.01 * h * h)
                visc = -mu / (0.5 * (rho[i] + rho[j]))
            f = (
                mass[j]
                * (pi_ / (rho[i] * rho[i]) + (1.0 + rho[j] * 0.01) / (rho[j] * rho[j]) + visc)
                * dw
                / r
            )
            d_rho += mass[j] * vr * dw / r
            a0 -= f * d0
            a1 -= f * d1
        drho[i] = d_rho
        acc[i, 0] = a0
        acc[i, 1] = a1


class Calibration:
    """The fixed workload on n_side^2 particles, built once; `measure()` runs it and returns
    (wall s, CPU s)."""

    def __init__(self, n_side=N_SIDE):
        rng = np.random.default_rng(SEED)
        dx = 1.0 / n_side
        g = (np.arange(n_side) + 0.5) * dx
        x = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
        x += rng.uniform(-0.15, 0.15, x.shape) * dx
        self.x = np.clip(x, 0.0, 1.0 - 1e-9)
        self.h = H_OVER_DX * dx
        n_cells = int(1.0 / (2.0 * self.h))
        self.start, self.index = _cell_list_pairs(self.x, 2.0 * self.h, n_cells, n_cells)
        self.v = rng.normal(0.0, 0.05, self.x.shape)
        self.rho = 1000.0 + rng.normal(0.0, 1.0, len(self.x))
        self.mass = np.full(len(self.x), 1000.0 * dx * dx)
        self.drho = np.zeros(len(self.x))
        self.acc = np.zeros_like(self.x)
        self.time_once()  # compile / load from cache outside any timing

    def pairs(self):
        return int(self.start[-1])

    def time_once(self):
        """Wall seconds of one pass."""
        return self.measure()[0]

    def measure(self):
        """(wall s, CPU s) of one pass."""
        t0, c0 = time.perf_counter(), time.process_time()
        pair_sum(self.start, self.index, self.x, self.v, self.rho, self.mass, self.h, self.drho, self.acc)
        return time.perf_counter() - t0, time.process_time() - c0


_shared = {}


def calibration(n_particles=N_SIDE * N_SIDE):
    """The process's Calibration of about n_particles particles (built on first use), so that a
    benchmark is compared with a yardstick of its own working-set size."""
    n_side = int(round(np.sqrt(n_particles)))
    if n_side not in _shared:
        _shared[n_side] = Calibration(n_side)
    return _shared[n_side]


if __name__ == "__main__":
    c = calibration()
    times = sorted(c.time_once() for _ in range(50))
    print(
        f"{len(c.x)} particles, {c.pairs()} pairs ({c.pairs() / len(c.x):.1f} per particle): median "
        f"{times[25] * 1e3:.3f} ms, min {times[0] * 1e3:.3f} ms, "
        f"{times[25] / c.pairs() * 1e9:.2f} ns per pair"
    )
