"""Leap-frog time integration, seed eqs. (24)-(27), in the form of Liu & Liu (2003, sec. 4.4.3).

Velocity, density (and, for soil, deviatoric stress) live at half steps; positions at
whole steps. One rate evaluation per step:
    predict   q_n      = q_{n-1/2} + (dt_{n-1}/2) (dq/dt)_{n-1}     (rates evaluated here)
    kick      q_{n+1/2} = q_{n-1/2} + (dt_{n-1} + dt_n)/2 (dq/dt)_n
    drift     x_{n+1}   = x_n + dt_n (v_{n+1/2} + xsph_n)           (XSPH, eq. 22)
The kick weight (dt_{n-1} + dt_n)/2 is the time between the half steps n-1/2 and n+1/2; it
equals dt for a constant step (Liu & Liu's form) and stays second-order when dt varies.
With dt_{-1} = 0 (q_{-1/2} = q_0) it is also the first half-kick q_{1/2} = q_0 + dt_0/2 (dq/dt)_0.
Each integrated field is a (value, half-step value, rate) triple of 2D arrays, so soil
stress joins without new code.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from .config import kernel

STATE_OK, STATE_NOT_FINITE, STATE_OUTSIDE = 0, 1, 2


@kernel(parallel=True)
def lf_predict(n, half_dt, value, half, rate):
    for i in prange(n):
        for k in range(value.shape[1]):
            value[i, k] = half[i, k] + half_dt * rate[i, k]


@kernel(parallel=True)
def lf_kick(n, weight, half, rate):
    """half += weight * rate, weight = (dt_{n-1} + dt_n) / 2."""
    for i in prange(n):
        for k in range(half.shape[1]):
            half[i, k] += weight * rate[i, k]


@kernel(parallel=True)
def lf_drift(n, dt, x, v_half, x_ref, has_lo, lo, has_hi, hi, xsph=None):
    """x += dt (v_{n+1/2} + xsph), then specular reflection at free-slip walls.

    Image particles repel only while the pressure is positive; a particle with tensile
    (negative) Tait pressure at a thin free-surface toe can drift through the wall plane.
    Reflecting the position and the normal velocity keeps the wall impenetrable; how
    often it happens and how deep is returned so the run can report (and a penetration
    deeper than h in one step, which no stable step produces, stops the run).
    Returns (largest squared displacement since x_ref, reflections, deepest penetration).
    """
    dim = x.shape[1]
    moved2 = 0.0
    reflected = 0
    depth = 0.0
    for i in prange(n):
        d2 = 0.0
        for a in range(dim):
            step = v_half[i, a]
            if xsph is not None:
                step += xsph[i, a]
            xa = x[i, a] + dt * step
            if has_lo[a] and xa < lo[a]:
                depth = max(depth, lo[a] - xa)
                xa = 2.0 * lo[a] - xa
                v_half[i, a] = -v_half[i, a]
                reflected += 1
            elif has_hi[a] and xa > hi[a]:
                depth = max(depth, xa - hi[a])
                xa = 2.0 * hi[a] - xa
                v_half[i, a] = -v_half[i, a]
                reflected += 1
            x[i, a] = xa
            d = xa - x_ref[i, a]
            d2 += d * d
        moved2 = max(moved2, d2)
    return moved2, reflected, depth


@kernel(parallel=True, exact=True)  # exact: under fastmath np.isfinite folds to True and a NaN goes unseen
def state_status(n, x, v_half, rho_half, lo, hi):
    """Worst status of the owned particles: 0 ok, 1 non-finite, 2 outside the domain box."""
    dim = x.shape[1]
    worst = 0
    for i in prange(n):
        code = 0
        if not np.isfinite(rho_half[i]):
            code = STATE_NOT_FINITE
        for a in range(dim):
            if not (np.isfinite(x[i, a]) and np.isfinite(v_half[i, a])):
                code = STATE_NOT_FINITE
            elif code == 0 and (x[i, a] < lo[a] or x[i, a] > hi[a]):
                code = STATE_OUTSIDE
        worst = max(worst, code)
    return worst


@kernel(parallel=True)
def max_norm2(n, vec):
    worst = 0.0
    for i in prange(n):
        s = 0.0
        for a in range(vec.shape[1]):
            s += vec[i, a] * vec[i, a]
        worst = max(worst, s)
    return worst


def as_rows(array, n):
    """A (n, k) view of the first n rows of a 1D or 2D field (no copy); k explicit, so a rank that
    owns no particle (n = 0) gets a (0, k) view too."""
    return array[:n].reshape(n, int(np.prod(array.shape[1:])))
