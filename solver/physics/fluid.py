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
rates, so they run in parallel without races.
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
def viscous_stress(targets, start, index, x, v, rho, mass, material, viscosity, h, norm, tau):
    """tau_i = mu eps_i, seed eqs. (10)-(11), with the SPH velocity gradient
    dv^b/dx^a = sum_j (m_j / rho_j) (v_j^b - v_i^b) dW_ij/dx_i^a  (Liu & Liu 2003, eq. 4.31)."""
    dim = x.shape[1]
    for t in prange(targets.shape[0]):
        i = targets[t]
        grad = np.zeros((dim, dim))
        for s in range(start[t], start[t + 1]):
            j = index[s]
            r2 = 0.0
            for a in range(dim):
                r2 += (x[i, a] - x[j, a]) ** 2
            r = np.sqrt(r2) + 1e-300
            f = cubic_spline_dwdr(r, h, norm) / r * mass[j] / rho[j]
            for a in range(dim):
                ga = f * (x[i, a] - x[j, a])
                for b in range(dim):
                    grad[a, b] += (v[j, b] - v[i, b]) * ga
        div = 0.0
        for a in range(dim):
            div += grad[a, a]
        mu = viscosity[material[i]]
        for a in range(dim):
            for b in range(dim):
                eps = grad[a, b] + grad[b, a] - (2.0 / 3.0 if a == b else 0.0) * div  # eq. (11)
                tau[i, a * dim + b] = mu * eps  # eq. (10)


@kernel(parallel=True)
def fluid_rates(
    targets, start, index, x, v, rho, p, mass, material, sound_speed, h, norm,
    drho, acc,
    tau=None,                 # viscous stress (dim*dim per row): eq. (7)-(8) with (10)
    av_alpha=None, av_beta=None,  # artificial viscosity per material: eq. (19)
    xsph=None, xsph_eps=0.0,  # XSPH velocity correction out: eq. (22)
):
    """Continuity (6) and momentum (7) for each target; adds into drho and acc."""
    dim = x.shape[1]
    for t in prange(targets.shape[0]):
        i = targets[t]
        rho_i = rho[i]
        pi_r2 = p[i] / (rho_i * rho_i)
        d_rho = 0.0
        a_i = np.zeros(dim)
        dx_xsph = np.zeros(dim)
        for s in range(start[t], start[t + 1]):
            j = index[s]
            r2 = 0.0
            vr = 0.0
            for a in range(dim):
                xij = x[i, a] - x[j, a]
                r2 += xij * xij
                vr += (v[i, a] - v[j, a]) * xij
            r = np.sqrt(r2) + 1e-300
            dwdr = cubic_spline_dwdr(r, h, norm)
            fr = dwdr / r                       # grad_i W_ij = fr * x_ij
            m_j = mass[j]
            rho_j = rho[j]
            d_rho += m_j * vr * fr              # eq. (6): m_j v_ij . grad_i W_ij
            coef = -m_j * (pi_r2 + p[j] / (rho_j * rho_j))   # eq. (7), pressure part of sigma
            if av_alpha is not None:
                if vr < 0.0:                    # eq. (19): only approaching pairs
                    mi = material[i]
                    mj = material[j]
                    phi = h * vr / (r2 + 0.01 * h * h)
                    c_bar = 0.5 * (sound_speed[mi] + sound_speed[mj])
                    alpha = 0.5 * (av_alpha[mi] + av_alpha[mj])
                    beta = 0.5 * (av_beta[mi] + av_beta[mj])
                    coef -= m_j * (-alpha * c_bar * phi + beta * phi * phi) / (0.5 * (rho_i + rho_j))
            for a in range(dim):
                a_i[a] += coef * fr * (x[i, a] - x[j, a])
            if tau is not None:                 # eq. (7), viscous part of sigma
                ri2 = 1.0 / (rho_i * rho_i)
                rj2 = 1.0 / (rho_j * rho_j)
                for a in range(dim):
                    sa = 0.0
                    for b in range(dim):
                        sa += (tau[i, a * dim + b] * ri2 + tau[j, a * dim + b] * rj2) * fr * (x[i, b] - x[j, b])
                    a_i[a] += m_j * sa
            if xsph is not None:                # eq. (22): -eps sum_j (m_j/rho_j) v_ij W_ij
                w = cubic_spline_w(r, h, norm) * m_j / rho_j
                for a in range(dim):
                    dx_xsph[a] -= xsph_eps * w * (v[i, a] - v[j, a])
        drho[i] += d_rho
        for a in range(dim):
            acc[i, a] += a_i[a]
        if xsph is not None:
            for a in range(dim):
                xsph[i, a] = dx_xsph[a]
