"""Slow NumPy twin of solver/physics/density_diffusion.py, written from the equations:
all-pairs loops over explicit neighbour lists, full matrices, np.linalg.inv.

  D_i = delta h c0 sum_j psi_ij . grad_i W_ij V_j                       (Antuono et al. 2010, eq. 6)
  psi_ij = 2 [(rho_j - rho_i) - (rho^H_j - rho^H_i)] x_ji / |x_ji|^2
           - (<grad rho>_i^L + <grad rho>_j^L)                           (eq. 7; Fourtakas et al. 2019)
  <grad rho>_i^L = sum_j (rho_j - rho_i) L_i grad_i W_ij V_j,
  L_i = [sum_j x_ji (x) grad_i W_ij V_j]^-1                              (eq. 8)
"""

import numpy as np
from naive import grad_w


def renormalised_gradient(targets, x, rho, mass, h, dim, nbr_lists):
    out = np.zeros((len(x), dim))
    for t, i in enumerate(targets):
        m = np.zeros((dim, dim))
        u = np.zeros(dim)
        for j in nbr_lists[t]:
            gw = grad_w(x[i], x[j], h, dim)
            vj = mass[j] / rho[j]
            m += np.outer(x[j] - x[i], gw) * vj
            u += (rho[j] - rho[i]) * gw * vj
        out[i] = np.linalg.solve(m.T, u)  # L applied as in eq. 8: g = (M^T)^-1 u (M is symmetric here)
    return out


def density_diffusion(
    targets, x, rho, mass, c0, delta, h, dim, nbr_lists, rho_ref=None, grad_rho=None, fraction=None
):
    """With `fraction`: pore water (fraction < 1) neither gets nor gives any diffusion."""
    out = np.zeros(len(x))
    ref = np.zeros(len(x)) if rho_ref is None else rho_ref
    free = np.ones(len(x), bool) if fraction is None else fraction >= 1.0
    q = rho
    for t, i in enumerate(targets):
        total = 0.0
        if not free[i]:
            continue
        for j in nbr_lists[t]:
            if not free[j]:
                continue
            xji = x[j] - x[i]
            psi = 2.0 * ((q[j] - q[i]) - (ref[j] - ref[i])) * xji / np.dot(xji, xji)
            if grad_rho is not None:
                psi = psi - (grad_rho[i] + grad_rho[j])
            total += np.dot(psi, grad_w(x[i], x[j], h, dim)) * mass[j] / rho[j]
        out[i] = delta * h * c0 * total
    return out


def hydrostatic_density(z, level, rho0, b, gamma, g):
    """Inverse Tait law (seed eq. 9) of p = rho0 g (level - z)."""
    return rho0 * (1.0 + rho0 * g * (level - z) / b) ** (1.0 / gamma)


def midpoint_continuity(targets, x, x_old, v, rho, mass, h, dim, nbr_lists):
    """Seed eq. (6) with every position at the midpoint (x + x_old) / 2."""
    mid = 0.5 * (x + x_old)
    out = np.zeros(len(x))
    for t, i in enumerate(targets):
        for j in nbr_lists[t]:
            out[i] += mass[j] * np.dot(v[i] - v[j], grad_w(mid[i], mid[j], h, dim))
    return out


def pore_density_diffusion(targets, x, rho, mass, fraction, c0, delta, h, dim, nbr_lists, rho_ref=None,
                           fixed=None, scaled=True):  # fmt: skip
    """solver/physics/seepage_pore_diffusion.py from its equations: among pore water (fraction < 1, not
    fixed) only, Antuono et al.'s (2010) eqs. (6)-(8) on q = rho / f - rho^H, the rate times f_i; with
    scaled False (the seed's pore_label) f = 1. Returns (the rates, the renormalised gradients)."""
    ref = np.zeros(len(x)) if rho_ref is None else rho_ref
    fixed = np.zeros(len(x), bool) if fixed is None else fixed
    pore = (fraction < 1.0) & ~fixed
    f = fraction if scaled else np.ones(len(x))
    q = rho / f - ref
    lists = [[j for j in nbrs if pore[j]] for nbrs in nbr_lists]
    grad = np.zeros((len(x), dim))
    for t, i in enumerate(targets):
        if not pore[i]:
            continue
        m = np.zeros((dim, dim))
        u = np.zeros(dim)
        for j in lists[t]:
            gw = grad_w(x[i], x[j], h, dim)
            m += np.outer(x[j] - x[i], gw) * mass[j] / rho[j]
            u += (q[j] - q[i]) * gw * mass[j] / rho[j]
        if abs(np.linalg.det(m)) > 1e-300:
            grad[i] = np.linalg.solve(m.T, u)
    out = np.zeros(len(x))
    for t, i in enumerate(targets):
        if not pore[i]:
            continue
        total = 0.0
        for j in lists[t]:
            xji = x[j] - x[i]
            psi = 2.0 * (q[j] - q[i]) * xji / np.dot(xji, xji) - (grad[i] + grad[j])
            total += np.dot(psi, grad_w(x[i], x[j], h, dim)) * mass[j] / rho[j]
        out[i] = f[i] * delta * h * c0 * total
    return out, grad
