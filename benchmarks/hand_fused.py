"""A hand-fused water pair loop with every term written inline (no optional arguments):
the yardstick for the composed `fluid_rates` kernel (same terms, same order of work)."""

import numpy as np
from numba import prange

from solver.config import kernel


@kernel(parallel=True)
def hand_fused_2d(
    targets, start, index, x, v, rho, p, mass, tau, c, alpha, beta, eps, h, norm, drho, acc, xsph
):
    hh = 0.01 * h * h
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1, vi0, vi1 = x[i, 0], x[i, 1], v[i, 0], v[i, 1]
        ri2 = 1.0 / (rho[i] * rho[i])
        pi = p[i] * ri2
        t00, t11, t01 = tau[i, 0] * ri2, tau[i, 1] * ri2, tau[i, 3] * ri2
        d = a0 = a1 = s0 = s1 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0, d1 = xi0 - x[j, 0], xi1 - x[j, 1]
            u0, u1 = vi0 - v[j, 0], vi1 - v[j, 1]
            r2 = d0 * d0 + d1 * d1
            r = np.sqrt(r2) + 1e-300
            R = r / h
            qa, qb = max(2.0 - R, 0.0), max(1.0 - R, 0.0)
            fr = norm * (-0.5 * qa * qa + 2.0 * qb * qb) / h / r
            w = norm * (qa * qa * qa - 4.0 * qb * qb * qb) / 6.0
            vr = u0 * d0 + u1 * d1
            rj2 = 1.0 / (rho[j] * rho[j])
            mj = mass[j]
            d += mj * vr * fr
            phi = h * min(vr, 0.0) / (r2 + hh)
            coef = -(pi + p[j] * rj2) - (-alpha * c * phi + beta * phi * phi) * 2.0 / (rho[i] + rho[j])
            s00, s11, s01 = t00 + tau[j, 0] * rj2, t11 + tau[j, 1] * rj2, t01 + tau[j, 3] * rj2
            fm = mj * fr
            a0 += fm * (coef * d0 + s00 * d0 + s01 * d1)
            a1 += fm * (coef * d1 + s01 * d0 + s11 * d1)
            ww = eps * w * mj / rho[j]
            s0 -= ww * u0
            s1 -= ww * u1
        drho[i] += d
        acc[i, 0] += a0
        acc[i, 1] += a1
        xsph[i, 0] = s0
        xsph[i, 1] = s1
