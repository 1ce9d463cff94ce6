"""Slow, obviously-correct NumPy twins of the fast Numba kernels (stumpy's tests/naive.py).

Written from the equations, not from the kernels: all-pairs loops, piecewise kernels as
printed in the seed paper (with the erratum), no neighbour lists.
"""

import numpy as np


def cubic_spline(r, h, dim):
    """Seed eq. (5) piecewise, erratum applied."""
    alpha = {1: 1.0 / h, 2: 15.0 / (7.0 * np.pi * h**2), 3: 3.0 / (2.0 * np.pi * h**3)}[dim]
    R = np.asarray(r, float) / h
    return alpha * np.where(R < 1, 2 / 3 - R**2 + 0.5 * R**3, np.where(R < 2, (2 - R) ** 3 / 6, 0.0))


def cubic_spline_dwdr(r, h, dim):
    alpha = {1: 1.0 / h, 2: 15.0 / (7.0 * np.pi * h**2), 3: 3.0 / (2.0 * np.pi * h**3)}[dim]
    R = np.asarray(r, float) / h
    return alpha / h * np.where(R < 1, -2 * R + 1.5 * R**2, np.where(R < 2, -0.5 * (2 - R) ** 2, 0.0))


def grad_w(xi, xj, h, dim):
    d = xi - xj
    r = np.linalg.norm(d)
    return np.zeros_like(d) if r == 0 else cubic_spline_dwdr(r, h, dim) / r * d


def neighbours(x, targets, radius):
    """All j != i with |x_i - x_j| < radius, as sorted lists."""
    out = []
    for i in targets:
        r = np.linalg.norm(x - x[i], axis=1)
        out.append(sorted(int(j) for j in np.flatnonzero(r < radius) if j != i))
    return out


def tait(rho, rho0, b, gamma):
    return b * ((rho / rho0) ** gamma - 1.0)


def velocity_gradient(i, x, v, rho, mass, h, dim, nbrs):
    g = np.zeros((dim, dim))
    for j in nbrs:
        g += mass[j] / rho[j] * np.outer(grad_w(x[i], x[j], h, dim), v[j] - v[i])  # g[a, b] = dv^b/dx^a
    return g


def viscous_stress(targets, x, v, rho, mass, mu, h, dim, nbr_lists):
    """Seed eqs. (10)-(11) as full tensors, returned in 6 symmetric components."""
    out = np.zeros((len(x), 6))
    for t, i in enumerate(targets):
        g = velocity_gradient(i, x, v, rho, mass, h, dim, nbr_lists[t])
        full = np.zeros((3, 3))
        full[:dim, :dim] = g
        eps = full + full.T - 2.0 / 3.0 * np.trace(full) * np.eye(3)
        tau = mu * eps
        out[i] = [tau[0, 0], tau[1, 1], tau[2, 2], tau[0, 1], tau[1, 2], tau[0, 2]]
    return out


def sym_to_full(c, dim):
    full = np.array([[c[0], c[3], c[5]], [c[3], c[1], c[4]], [c[5], c[4], c[2]]])
    return full[:dim, :dim]


def fluid_rates(
    targets, x, v, rho, p, mass, c, h, dim, nbr_lists, tau=None, alpha=0.0, beta=0.0, xsph_eps=0.0, pore=None
):
    """Seed eqs. (6), (7) with sigma = -p I + tau, (19) with beta phi^2, (22). With pore, targets with
    pore < 1 take the pressure part from corrected_pressure_gradient instead."""
    drho = np.zeros(len(x))
    acc = np.zeros((len(x), dim))
    xsph = np.zeros((len(x), dim))
    for t, i in enumerate(targets):
        corrected = pore is not None and pore[i] < 1.0
        if corrected:
            acc[i] += corrected_pressure_acceleration(i, x, rho, p, mass, h, dim, nbr_lists[t])
        for j in nbr_lists[t]:
            gw = grad_w(x[i], x[j], h, dim)
            vij, xij = v[i] - v[j], x[i] - x[j]
            drho[i] += mass[j] * vij @ gw
            p_i, p_j = (0.0, 0.0) if corrected else (p[i], p[j])  # the pressure part apart (above)
            sig_i = -p_i * np.eye(dim) + (sym_to_full(tau[i], dim) if tau is not None else 0)
            sig_j = -p_j * np.eye(dim) + (sym_to_full(tau[j], dim) if tau is not None else 0)
            acc[i] += mass[j] * (sig_i / rho[i] ** 2 + sig_j / rho[j] ** 2) @ gw
            vr = vij @ xij
            if vr < 0:
                phi = h * vr / (xij @ xij + 0.01 * h * h)
                acc[i] -= mass[j] * (-alpha * c * phi + beta * phi**2) / (0.5 * (rho[i] + rho[j])) * gw
            xsph[i] -= xsph_eps * mass[j] / rho[j] * vij * cubic_spline(np.linalg.norm(xij), h, dim)
    return drho, acc, xsph


def corrected_pressure_acceleration(i, x, rho, p, mass, h, dim, nbrs):
    """Pore water's pressure acceleration (solver/physics/pore_pressure_gradient.py): s a_c + (1 - s) a_sym,
    a_c = -(1/rho_i) M^-1 sum_j V_j (p_j - p_i) grad_i W_ij, M = sum_j V_j grad_i W_ij (x) (x_j - x_i),
    a_sym = -sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij, s = 0 below CUT_SUPPORT[0] of
    sum_j V_j W_ij, 1 above CUT_SUPPORT[1], linear between, 0 when det M <= 1/4."""
    from solver.physics.pore_pressure_gradient import CUT_SUPPORT

    grad, big_m, den = np.zeros(dim), np.zeros((dim, dim)), mass[i] / rho[i] * cubic_spline(0.0, h, dim)
    a_sym = np.zeros(dim)
    for j in nbrs:
        gw = grad_w(x[i], x[j], h, dim)
        vol = mass[j] / rho[j]
        grad += vol * (p[j] - p[i]) * gw
        big_m += vol * np.outer(gw, x[j] - x[i])
        den += vol * cubic_spline(np.linalg.norm(x[i] - x[j]), h, dim)
        a_sym -= mass[j] * (p[i] / rho[i] ** 2 + p[j] / rho[j] ** 2) * gw
    det = np.linalg.det(big_m)
    lo, hi = CUT_SUPPORT
    s = float(np.clip((den - lo) / (hi - lo), 0.0, 1.0)) if det > 0.25 else 0.0
    a_c = -np.linalg.solve(big_m, grad) / rho[i] if det > 0.0 else np.zeros(dim)
    return s * a_c + (1.0 - s) * a_sym


def continuity(targets, x, v, mass, h, dim, nbr_lists):
    """Seed eq. (6) alone: drho_i = sum_j m_j (v_i - v_j) . grad_i W_ij."""
    drho = np.zeros(len(x))
    for t, i in enumerate(targets):
        for j in nbr_lists[t]:
            drho[i] += mass[j] * (v[i] - v[j]) @ grad_w(x[i], x[j], h, dim)
    return drho


def fluid_rates_mixed(targets, x, v, rho, p, mass, material, c, alpha, beta, h, dim, nbr_lists):
    """Eqs. (6), (7) and (19) when a phase holds several materials: the artificial viscosity of
    a pair uses the pair means of c, alpha and beta (Monaghan 1992: c_bar = (c_i + c_j) / 2; the
    same mean for alpha, beta, which makes the pair term symmetric); c, alpha, beta per material."""
    drho = np.zeros(len(x))
    acc = np.zeros((len(x), dim))
    for t, i in enumerate(targets):
        for j in nbr_lists[t]:
            mi, mj = material[i], material[j]
            gw = grad_w(x[i], x[j], h, dim)
            vij, xij = v[i] - v[j], x[i] - x[j]
            drho[i] += mass[j] * vij @ gw
            acc[i] -= mass[j] * (p[i] / rho[i] ** 2 + p[j] / rho[j] ** 2) * gw
            vr = vij @ xij
            if vr < 0:
                c_bar, a_bar, b_bar = (
                    (c[mi] + c[mj]) / 2,
                    (alpha[mi] + alpha[mj]) / 2,
                    (beta[mi] + beta[mj]) / 2,
                )
                phi = h * vr / (xij @ xij + 0.01 * h * h)
                acc[i] -= mass[j] * (-a_bar * c_bar * phi + b_bar * phi**2) / (0.5 * (rho[i] + rho[j])) * gw
    return drho, acc


def hydrostatic_image_pressure(first, src, x, rho, gravity, p):
    """numerics.image_pressure = "hydrostatic": an image's pressure is its source's plus the
    hydrostatic difference between them, p' = p_src + rho_src g . (x' - x_src); sources unchanged."""
    out = np.array(p, dtype=float, copy=True)
    for k, j in enumerate(src):
        out[first + k] = p[first + k] + rho[j] * np.dot(gravity, x[first + k] - x[j])
    return out
