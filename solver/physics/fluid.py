"""Water: weakly compressible Newtonian fluid, exactly the terms of the seed paper.

  continuity        seed eq. (6)
  momentum          seed eq. (7), sigma = -p delta + tau (8)
  Tait EOS          seed eq. (9)
  viscous stress    seed eqs. (10)-(11), tau from the SPH velocity gradient
  artificial visc.  seed eq. (19), Monaghan (1992) form with beta phi^2 (erratum)
  XSPH              seed eq. (22)
Optional terms are optional arguments: passing None removes the term at compile time
(Numba prunes `is None` branches before typing), so an absent term costs nothing.
All loops are gathers over a target's neighbour row: each target writes only its own
rates, so they run in parallel without races. Accumulators are scalars (no per-particle
allocation) and z components are guarded by `is3d is not None`, so 2D and 3D share one
kernel and the 2D specialisation contains no z code at all.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import cubic_spline_dwdr, cubic_spline_w


@kernel(parallel=True)
def tait_pressure(n, rho, material, rho0, eos_b, exponent, p):
    """Seed eq. (9): p = B [(rho/rho0)^lambda - 1] for rows [0, n)."""
    for i in prange(n):
        m = material[i]
        p[i] = eos_b[m] * ((rho[i] / rho0[m]) ** exponent[m] - 1.0)


@kernel(parallel=True)
def viscous_stress(targets, start, index, x, v, rho, mass, material, viscosity, h, norm, tau, is3d=None):
    """tau_i = mu eps_i, seed eqs. (10)-(11), with the SPH velocity gradient
    g_ab = dv^b/dx^a = sum_j (m_j / rho_j) (v_j^b - v_i^b) dW_ij/dx_i^a (Liu & Liu 2003, eq. 4.31).
    tau has 6 symmetric components (solver/tensors.py). is3d: None in 2D (z code pruned)."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        g00 = g01 = g02 = g10 = g11 = g12 = g20 = g21 = g22 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            f = cubic_spline_dwdr(r, h, norm) / r * mass[j] / rho[j]
            w0 = (v[j, 0] - vi0) * f
            w1 = (v[j, 1] - vi1) * f
            g00 += w0 * d0
            g01 += w1 * d0
            g10 += w0 * d1
            g11 += w1 * d1
            if is3d is not None:
                w2 = (v[j, 2] - vi2) * f
                g02 += w2 * d0
                g12 += w2 * d1
                g20 += w0 * d2
                g21 += w1 * d2
                g22 += w2 * d2
        mu = viscosity[material[i]]
        third_div = (g00 + g11 + g22) / 3.0
        tau[i, 0] = mu * (2.0 * g00 - 2.0 * third_div)  # eq. (11): g_ab + g_ba - 2/3 div delta_ab
        tau[i, 1] = mu * (2.0 * g11 - 2.0 * third_div)
        tau[i, 2] = mu * (2.0 * g22 - 2.0 * third_div)
        tau[i, 3] = mu * (g01 + g10)
        tau[i, 4] = mu * (g12 + g21)
        tau[i, 5] = mu * (g02 + g20)


@kernel(parallel=True)
def fluid_rates(
    targets,
    start,
    index,
    x,
    v,
    rho,
    p,
    mass,
    material,
    sound_speed,
    h,
    norm,
    drho,
    acc,
    tau=None,  # viscous stress: eq. (7)-(8) with (10)
    av_alpha=None,
    av_beta=None,  # artificial viscosity per material: eq. (19)
    xsph=None,
    xsph_eps=0.0,  # XSPH velocity correction out: eq. (22)
    is3d=None,  # None in 2D: every z term is pruned at compile time
    mixed=None,  # None when the phase has one material: no per-pair look-ups
):
    """Continuity (6) and momentum (7) for each target; adds into drho and acc."""
    hh = 0.01 * h * h
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        rho_i = rho[i]
        ri2 = 1.0 / (rho_i * rho_i)
        pi_r2 = p[i] * ri2
        mi = material[i]
        c_bar, alpha, beta = 0.0, 0.0, 0.0
        if av_alpha is not None:
            c_bar, alpha, beta = sound_speed[mi], av_alpha[mi], av_beta[mi]
        d_rho = 0.0
        a0 = a1 = a2 = 0.0
        x0 = x1 = x2 = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            u0 = vi0 - v[j, 0]
            u1 = vi1 - v[j, 1]
            d2 = u2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
                u2 = vi2 - v[j, 2]
            r2 = d0 * d0 + d1 * d1 + d2 * d2
            r = np.sqrt(r2) + 1e-300
            vr = u0 * d0 + u1 * d1 + u2 * d2
            fr = cubic_spline_dwdr(r, h, norm) / r  # grad_i W_ij = fr x_ij
            m_j = mass[j]
            rho_j = rho[j]
            rj2 = 1.0 / (rho_j * rho_j)
            if drho is not None:
                d_rho += m_j * vr * fr  # eq. (6)
            coef = -(pi_r2 + p[j] * rj2)  # eq. (7): sigma = -p delta
            if av_alpha is not None:  # eq. (19), branch-free: zero unless vr < 0
                if mixed is not None:  # pair means of c, alpha, beta
                    mj = material[j]
                    c_bar = 0.5 * (sound_speed[mi] + sound_speed[mj])
                    alpha = 0.5 * (av_alpha[mi] + av_alpha[mj])
                    beta = 0.5 * (av_beta[mi] + av_beta[mj])
                phi = h * min(vr, 0.0) / (r2 + hh)
                coef -= (-alpha * c_bar * phi + beta * phi * phi) * 2.0 / (rho_i + rho_j)
            coef *= m_j * fr
            a0 += coef * d0
            a1 += coef * d1
            a2 += coef * d2
            if tau is not None:  # eq. (7): + (tau_i/rho_i^2 + tau_j/rho_j^2) . grad W
                fm = m_j * fr
                s00 = tau[i, 0] * ri2 + tau[j, 0] * rj2
                s11 = tau[i, 1] * ri2 + tau[j, 1] * rj2
                s01 = tau[i, 3] * ri2 + tau[j, 3] * rj2
                if is3d is not None:
                    s22 = tau[i, 2] * ri2 + tau[j, 2] * rj2
                    s12 = tau[i, 4] * ri2 + tau[j, 4] * rj2
                    s02 = tau[i, 5] * ri2 + tau[j, 5] * rj2
                    a0 += fm * (s00 * d0 + s01 * d1 + s02 * d2)
                    a1 += fm * (s01 * d0 + s11 * d1 + s12 * d2)
                    a2 += fm * (s02 * d0 + s12 * d1 + s22 * d2)
                else:
                    a0 += fm * (s00 * d0 + s01 * d1)
                    a1 += fm * (s01 * d0 + s11 * d1)
            if xsph is not None:  # eq. (22): -eps sum_j (m_j/rho_j) v_ij W_ij
                w = xsph_eps * cubic_spline_w(r, h, norm) * m_j / rho_j
                x0 -= w * u0
                x1 -= w * u1
                x2 -= w * u2
        if drho is not None:
            drho[i] += d_rho
        acc[i, 0] += a0
        acc[i, 1] += a1
        if is3d is not None:
            acc[i, 2] += a2
        if xsph is not None:
            xsph[i, 0] = x0
            xsph[i, 1] = x1
            if is3d is not None:
                xsph[i, 2] = x2


@kernel(parallel=True)
def continuity(targets, start, index, x, v, mass, h, norm, drho, is3d=None):
    """Seed eq. (6) alone: drho_i = sum_j m_j (v_i - v_j) . grad_i W_ij (written, not added).
    With v = v_{n+1/2} and x = x_{n+1} it advances rho at whole steps (numerics.leapfrog =
    "symplectic_density")."""
    for t in prange(targets.shape[0]):
        i = targets[t]
        xi0, xi1 = x[i, 0], x[i, 1]
        vi0, vi1 = v[i, 0], v[i, 1]
        xi2 = vi2 = 0.0
        if is3d is not None:
            xi2, vi2 = x[i, 2], v[i, 2]
        d_rho = 0.0
        for s in range(start[t], start[t + 1]):
            j = index[s]
            d0 = xi0 - x[j, 0]
            d1 = xi1 - x[j, 1]
            vr = (vi0 - v[j, 0]) * d0 + (vi1 - v[j, 1]) * d1
            d2 = 0.0
            if is3d is not None:
                d2 = xi2 - x[j, 2]
                vr += (vi2 - v[j, 2]) * d2
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            d_rho += mass[j] * vr * cubic_spline_dwdr(r, h, norm) / r
        drho[i] = d_rho
