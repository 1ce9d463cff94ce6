"""Slow, obviously-correct NumPy twins of the soil kernels (solver/physics/soil.py), written
from the equations with full 3x3 matrices (tests/naive.py holds the water twins)."""

import numpy as np
from naive import cubic_spline, grad_w

IDX = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]


def to_matrix(v6):
    m = np.zeros((3, 3))
    for c, (a, b) in enumerate(IDX):
        m[a, b] = m[b, a] = v6[c]
    return m


def to_voigt(m):
    return np.array([m[a, b] for a, b in IDX])


def jaumann(s6, grad_v):
    """Seed eq. (13) corotational terms s^{ag} R^{bg} + s^{gb} R^{ag}, R from eq. (15);
    grad_v[a, b] = dv^a/dx^b (3x3)."""
    s = to_matrix(s6)
    R = 0.5 * (grad_v - grad_v.T)
    return to_voigt(np.einsum("ag,bg->ab", s, R) + np.einsum("gb,ag->ab", s, R))


def mu_of_i(inertial_number, mu_s, mu_2, i0):
    """The friction law of Jop, Forterre & Pouliquen (2006): mu(I) = mu_s + (mu_2 - mu_s) / (I_0 / I + 1)."""
    return mu_s + (mu_2 - mu_s) / (i0 / inertial_number + 1.0)


def rate_friction(p, gamma_dot, d_mu, i0, d50, rho_grain):
    """mu(I) - mu_s at I = gamma_dot d50 / sqrt(p / rho_grain) (GDR MiDi 2004), written from the
    definitions; 0 without confinement or shear."""
    if p <= 0 or gamma_dot <= 0 or d_mu <= 0:
        return 0.0
    inertial_number = gamma_dot * d50 / np.sqrt(p / rho_grain)
    return mu_of_i(inertial_number, 0.0, d_mu, i0)


def return_map(p, s6, model, K, G, phi_deg, c, psi_deg=0.0, mu_r=0.0):
    """Mohr-Coulomb scale-back (seed eq. 16) or Drucker-Prager return (Bui et al. 2008),
    from the definitions; returns (p, s6). mu_r = mu(I) - mu_s raises either surface by mu_r p
    (docs/rheology.md) where p > 0, held at the trial p during the return."""
    s = to_matrix(s6)
    j2 = 0.5 * np.sum(s * s)
    tphi, tpsi = np.tan(np.radians(phi_deg)), np.tan(np.radians(psi_deg))
    if model == "mohr_coulomb":
        if tphi > 0:
            p = max(p, -c / tphi)
        sf = max(c + p * tphi, 0.0) + mu_r * max(p, 0.0)
        return p, (to_voigt(s * sf / np.sqrt(j2)) if np.sqrt(j2) > sf else s6.copy())
    a_phi = tphi / np.sqrt(9 + 12 * tphi**2)
    k_c = 3 * c / np.sqrt(9 + 12 * tphi**2)
    a_psi = tpsi / np.sqrt(9 + 12 * tpsi**2)
    I1 = -3 * p
    if -a_phi * I1 + k_c < 0:  # beyond the apex: tension cracking
        return k_c / (3 * a_phi) * -1.0, np.zeros(6)
    mu_r = mu_r if p > 0 else 0.0
    f = a_phi * I1 + np.sqrt(j2) - k_c - mu_r * p
    if f <= 0:
        return p, s6.copy()
    # f after the return: sqrt(J2) - G dl - k_c - (3 a_phi + mu_r)(p + 3 K a_psi dl) = 0
    dl = f / (G + 3 * K * a_psi * (3 * a_phi + mu_r))
    # sigma_new = sigma_trial - D : dl (a_psi delta + s / (2 sqrt(J2)))
    sig = -p * np.eye(3) + s
    sig_new = sig - dl * (3 * K * a_psi * np.eye(3) + G * s / np.sqrt(j2))
    p_new = -np.trace(sig_new) / 3
    return p_new, to_voigt(sig_new + p_new * np.eye(3))


def soil_rates(x, v, rho, p, s, mass, c, G, h, alpha, beta, art=None, art_n=2.55, w_dx=1.0,
               suspended=None, suspended_av=(0.0, 0.0)):  # fmt: skip
    """All-pairs continuity (6), momentum (20) with AV (19) and artificial stress, and the
    Hooke-Jaumann rate (13)-(15), for every particle (one material). suspended: a pair with a
    suspended particle takes the AV constants suspended_av = (alpha, beta)."""
    n, dim = x.shape
    drho = np.zeros(n)
    acc = np.zeros((n, dim))
    ds = np.zeros((n, 6))
    for i in range(n):
        sig_i = (to_matrix(s[i]) - p[i] * np.eye(3))[:dim, :dim]
        L = np.zeros((3, 3))
        for j in range(n):
            if i == j or np.linalg.norm(x[i] - x[j]) >= 2 * h:
                continue
            gw = grad_w(x[i], x[j], h, dim)
            vij, xij = v[i] - v[j], x[i] - x[j]
            drho[i] += mass[j] * vij @ gw
            sig_j = (to_matrix(s[j]) - p[j] * np.eye(3))[:dim, :dim]
            T = sig_i / rho[i] ** 2 + sig_j / rho[j] ** 2
            vr = vij @ xij
            if vr < 0:
                a, b = alpha, beta
                if suspended is not None and (suspended[i] or suspended[j]):
                    a, b = suspended_av
                phi = h * vr / (xij @ xij + 0.01 * h * h)
                T = T - (-a * c * phi + b * phi**2) / (0.5 * (rho[i] + rho[j])) * np.eye(dim)
            if art is not None:
                f = cubic_spline(np.linalg.norm(xij), h, dim) / w_dx
                T = T + f**art_n * (to_matrix(art[i]) + to_matrix(art[j]))[:dim, :dim]
            acc[i] += mass[j] * T @ gw
            L[:dim, :dim] += mass[j] / rho[j] * np.outer(v[j] - v[i], gw)  # dv^a/dx^b
        eps = 0.5 * (L + L.T)
        dev = eps - np.trace(eps) / 3 * np.eye(3)
        ds[i] = to_voigt(2 * G * dev) + jaumann(s[i], L)
    return drho, acc, ds


def shear_rates(x, v, rho, mass, h):
    """All-pairs |gamma_dot| = sqrt(2 e':e'), e' the deviatoric part of the symmetric SPH velocity
    gradient (seed eq. 14; Liu & Liu 2003), for every particle: the shear rate of mu(I)."""
    n, dim = x.shape
    out = np.zeros(n)
    for i in range(n):
        L = np.zeros((3, 3))
        for j in range(n):
            if i != j and np.linalg.norm(x[i] - x[j]) < 2 * h:
                L[:dim, :dim] += mass[j] / rho[j] * np.outer(v[j] - v[i], grad_w(x[i], x[j], h, dim))
        eps = 0.5 * (L + L.T)
        dev = eps - np.trace(eps) / 3 * np.eye(3)
        out[i] = np.sqrt(2.0 * np.sum(dev * dev))
    return out


def artificial_stress(p, s6, rho, eps, dim=2):
    """Gray et al. (2001): R = -eps sum_a max(sigma_a, 0)/rho^2 n_a n_a over the principal
    directions (numpy's eigh): in 2D the in-plane ones plus zz (out-of-plane, principal)."""
    sig = to_matrix(s6) - p * np.eye(3)
    if dim == 3:
        w, vec = np.linalg.eigh(sig)
        return to_voigt(sum(-eps * max(w[a], 0) / rho**2 * np.outer(vec[:, a], vec[:, a]) for a in range(3)))
    w, vec = np.linalg.eigh(sig[:2, :2])
    R = np.zeros((3, 3))
    for a in range(2):
        R[:2, :2] += -eps * max(w[a], 0) / rho**2 * np.outer(vec[:, a], vec[:, a])
    R[2, 2] = -eps * max(sig[2, 2], 0) / rho**2
    return to_voigt(R)


def frictional_images(
    first, src, offset, fric_axis, fric_side, mu, p, s6, vsign, x, v, rho, gravity, v_stick
):
    """Coulomb wall by images (module doc of solver/physics/boundary.py), from the definitions,
    with full 3x3 stresses. For an image k across one frictional wall (normal axis a, side +1
    lower / -1 upper, plane at offset/2): the source's compressive normal stress on the wall
    plane, sigma_n = -(e_a . sigma . e_a) + rho |g_a| d (static equilibrium over the distance d
    to the plane), at least 0; its shear traction on the plane, tau_b = sigma_ab (b != a);
    its tangential velocity u. Stick (|u| <= v_stick and |tau| <= mu sigma_n): no-slip image
    (vsign -1 along the plane), stress unchanged. Slip: free-slip image (vsign +1) and image
    shear sigma'_ab = 2 w_b - sigma_ab, so that the pair's mean (the wall's traction) is w, of
    size mu sigma_n: against the sliding velocity, w = side mu sigma_n u / |u| (the traction
    sigma . n on the soil, n = -side e_a its outward normal, then opposes u), or along tau when
    slip starts from rest. Returns (new vsign, new stress rows, number slipping)."""
    dim = x.shape[1]
    vsign, s6 = vsign.copy(), s6.copy()
    slipping = 0
    for k, j in enumerate(src):
        a = fric_axis[k]
        if a < 0:
            continue
        i = first + k
        sigma = -p[j] * np.eye(3) + to_matrix(s6[j])
        plane = 0.5 * offset[k, a]
        sigma_n = max(-sigma[a, a] + rho[j] * abs(gravity[a]) * abs(x[j, a] - plane), 0.0)
        tangential = [b for b in range(3) if b != a]
        tau = np.array([sigma[a, b] for b in tangential])
        u = np.array([v[j, b] if b < dim else 0.0 for b in tangential])
        limit = mu * sigma_n
        sliding = np.linalg.norm(u) > v_stick
        slip = sliding or np.linalg.norm(tau) > limit
        for b in tangential:
            if b < dim:
                vsign[k, b] = 1.0 if slip else -1.0
        if slip:
            slipping += 1
            w = fric_side[k] * limit * u / np.linalg.norm(u) if sliding else limit * tau / np.linalg.norm(tau)
            image = to_matrix(s6[i])
            for wb, b in zip(w, tangential):
                if b < dim:
                    image[a, b] = image[b, a] = 2.0 * wb - sigma[a, b]
            s6[i] = to_voigt(image)
    return vsign, s6, slipping
