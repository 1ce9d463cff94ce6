"""Slow NumPy twins of the seepage kernels (solver/physics/seepage.py), written from the equations
of docs/seepage.md: all-pairs loops over the other phase, no neighbour lists.

  p~_b         = sum_a V_a p_a W_ab / sum_a V_a W_ab                     (Shepard, 0 if no water)
  p^_a         = sum_b V_b p~_b W_ab / sum_b V_b W_ab                    (Shepard, p_a if no soil)
                 or (linear) the value at x_a of the V_b W_ab-weighted linear fit of p~_b
  F_ab (on b)  = V_a V_b C W_ab (v_a - v_b) - phi V_a V_b (p^_a - p~_b) grad_b W_ab
                 (C = drag of b's material, phi = 1 - n in the mixture form, 0 in the seed's)
  soil b       acc += sum_a F_ab / m_b
  water a      acc -= sum_b F_ab / m_a
  storage a    drho += -rho_a phi_a / (1 - phi_a) div v_s,  phi_a = min(sum_b m_b / rho_grain W_ab, 0.95),
               div v_s = sum_b V_b (v_b - v~) . grad_a W_ab, v~ = sum_b V_b v_b W_ab / sum_b V_b W_ab
"""

import numpy as np
from naive import cubic_spline, grad_w


def _within(xa, xb, radius):
    return np.linalg.norm(xa - xb) < radius


def pore_pressure_at_soil(soil, water, x, rho, mass, p, h, dim, radius):
    out = np.zeros(len(x))
    for b in soil:
        w = np.array([mass[a] / rho[a] * cubic_spline(np.linalg.norm(x[b] - x[a]), h, dim) for a in water])
        inside = np.array([_within(x[a], x[b], radius) for a in water])
        w = np.where(inside, w, 0.0)
        out[b] = (w @ p[water]) / w.sum() if w.sum() > 0 else 0.0
    return out


def pore_pressure_at_water(water, soil, x, rho, mass, p, pore, h, dim, radius, linear=False, ridge=1e-2):
    """pore with p^_a written on the water rows (soil rows kept). linear: p^_a = alpha of the weighted
    least-squares fit pore_b ~ alpha + beta . (x_b - x_a), weights w_b = V_b W_ab, with `ridge` times the
    mean variance of the offsets (about their weighted mean) added to the slope's normal matrix."""
    out = pore.copy()
    for a in water:
        w = np.array([mass[b] / rho[b] * cubic_spline(np.linalg.norm(x[a] - x[b]), h, dim) for b in soil])
        inside = np.array([_within(x[a], x[b], radius) for b in soil])
        w = np.where(inside, w, 0.0)
        if w.sum() <= 0:
            out[a] = p[a]
            continue
        out[a] = (w @ pore[soil]) / w.sum()
        if linear:
            d = x[soil] - x[a]
            d_mean = w @ d / w.sum()
            p_mean = out[a]
            cov = (w[:, None] * (d - d_mean)).T @ (d - d_mean)
            cov += ridge * np.trace(cov) / dim * np.eye(dim)
            beta = np.linalg.solve(cov, (w * (pore[soil] - p_mean)) @ (d - d_mean))
            out[a] = p_mean - d_mean @ beta
    return out


def pair_force(a, b, x, v, rho, mass, p, pore, drag, solid, h, dim):
    """The force on soil b from water a; p holds p^ on the water rows, pore p~ on the soil rows."""
    va, vb = mass[a] / rho[a], mass[b] / rho[b]
    w = cubic_spline(np.linalg.norm(x[b] - x[a]), h, dim)
    f = va * vb * drag * w * (v[a] - v[b])
    if solid:
        f -= solid * va * vb * (p[a] - pore[b]) * grad_w(x[b], x[a], h, dim)
    return f


def seepage_accelerations(soil, water, x, v, rho, mass, material, p, pore, drag, solid, h, dim, radius):
    """acc of both phases from the coupling alone, and the largest relaxation rates of each side."""
    acc = np.zeros((len(x), dim))
    lam = np.zeros(len(x))
    for b in soil:
        for a in water:
            if not _within(x[a], x[b], radius):
                continue
            m = material[b]
            f = pair_force(a, b, x, v, rho, mass, p, pore, drag[m], solid[m], h, dim)
            acc[b] += f / mass[b]
            acc[a] -= f / mass[a]
            w = cubic_spline(np.linalg.norm(x[b] - x[a]), h, dim)
            k = mass[a] / rho[a] * mass[b] / rho[b] * drag[m] * w
            lam[b] += k / mass[b]
            lam[a] += k / mass[a]
    return acc, lam[soil].max(), lam[water].max()


def storage(water, soil, x, v, rho, mass, material, grain_density, h, dim, radius):
    """Biot's storage rate of every water particle (mixture form)."""
    drho = np.zeros(len(x))
    for a in water:
        nb = [b for b in soil if _within(x[a], x[b], radius)]
        if not nb:
            continue
        w = np.array([cubic_spline(np.linalg.norm(x[a] - x[b]), h, dim) for b in nb])
        vol = np.array([mass[b] / rho[b] for b in nb])
        phi = min(sum(mass[b] / grain_density[material[b]] * wb for b, wb in zip(nb, w)), 0.95)
        v_mean = (vol * w) @ v[nb] / (vol @ w)
        div = sum(vol[k] * (v[b] - v_mean) @ grad_w(x[a], x[b], h, dim) for k, b in enumerate(nb))
        drho[a] = -rho[a] * phi / (1.0 - phi) * div
    return drho


def pair_correction(water, soil, x, rho, mass, h, dim, radius, kappa, full=(0.98, 0.995)):
    """L_a of the corrected mixture's buoyancy pair for every water row a (a dict of dim x dim):
    L = (1 - s) I + s kappa M^-1, M = sum_b V_b grad_b W_ab (x) (x_a - x_b) over the soil within
    reach (Bonet & Lok 1999), s = clip((sum_b V_b W_ab - full[0]) / (full[1] - full[0]), 0, 1), and
    s = 0 where det M <= kappa^dim / 4."""
    out = {}
    for a in water:
        m, den = np.zeros((dim, dim)), 0.0
        for b in soil:
            if not _within(x[a], x[b], radius):
                continue
            vol = mass[b] / rho[b]
            m += vol * np.outer(grad_w(x[b], x[a], h, dim), x[a] - x[b])
            den += vol * cubic_spline(np.linalg.norm(x[a] - x[b]), h, dim)
        s = min(max((den - full[0]) / (full[1] - full[0]), 0.0), 1.0)
        if not np.linalg.det(m) > 0.25 * kappa**dim:
            s = 0.0
        out[a] = (1.0 - s) * np.eye(dim) + (s * kappa * np.linalg.inv(m) if s > 0 else 0.0)
    return out


def corrected_accelerations(soil, water, x, v, rho, mass, material, pore, drag, solid, h, dim, radius, corr):
    """seepage_accelerations with the buoyancy pair's grad_b W_ab replaced by L_a grad_b W_ab."""
    acc = np.zeros((len(x), dim))
    for b in soil:
        for a in water:
            if not _within(x[a], x[b], radius):
                continue
            m = material[b]
            va, vb = mass[a] / rho[a], mass[b] / rho[b]
            w = cubic_spline(np.linalg.norm(x[b] - x[a]), h, dim)
            f = va * vb * drag[m] * w * (v[a] - v[b])
            f -= solid[m] * va * vb * (pore[a] - pore[b]) * corr[a] @ grad_w(x[b], x[a], h, dim)
            acc[b] += f / mass[b]
            acc[a] -= f / mass[a]
    return acc
