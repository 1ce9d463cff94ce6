"""Slow NumPy twins of the erosion kernels (solver/sediment.py, solver/physics/bed_surface.py,
solver/physics/shields_pickup.py), written from the equations of their module docs: all-pairs loops,
the log law inverted by bisection instead of the fixed point.

  phi_b    = sum_c V_c W_bc over bed (non-suspended) soil c, b included when bed
  n_b      = -grad phi_b / |grad phi_b|
  u*       solves u_t = (u* / kappa) max(ln(y / z0(u*)), 1),
           z0 = k_s/30 (1 - exp(-u* k_s / 27 nu)) + nu / 9u*
  theta_b  = rho_w <u*^2> / ((rho_s - rho_w) g d50),  <.> weighted by V_a W_ab over water a with y >= y_min
  share_b += E dt V_b^((d-1)/d) / m_b,
           E = 0.00033 rho_s sqrt((s-1) g d) D*^0.3 ((theta - theta_cr)/theta_cr)^1.5
"""

import numpy as np
from naive import cubic_spline, cubic_spline_dwdr

KAPPA = 0.40


def roughness_length(u_star, k_s, nu):
    return k_s / 30.0 * (1.0 - np.exp(-u_star * k_s / (27.0 * nu))) + nu / (9.0 * u_star)


def friction_velocity(u, y, k_s, nu):
    """u* of the log law by bisection on [0, kappa u] (the law's clamp ln >= 1 bounds u* by kappa u)."""
    if u <= 0.0 or y <= 0.0:
        return 0.0
    speed = lambda us: us / KAPPA * max(np.log(y / roughness_length(us, k_s, nu)), 1.0)  # noqa: E731
    lo, hi = 1e-12, KAPPA * u
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if speed(mid) < u else (lo, mid)
    return 0.5 * (lo + hi)


def van_rijn(theta, theta_cr, d, rho_s, rho_w, nu, g):
    if theta <= theta_cr:
        return 0.0
    s = rho_s / rho_w
    dstar = d * ((s - 1.0) * g / nu**2) ** (1.0 / 3.0)
    return 0.00033 * rho_s * np.sqrt((s - 1.0) * g * d) * dstar**0.3 * ((theta - theta_cr) / theta_cr) ** 1.5


def bed_surface(soil, x, mass, rho, suspended, h, dim):
    fraction, normal = np.zeros(len(x)), np.zeros((len(x), dim))
    bed = [c for c in soil if not suspended[c]]
    for b in soil:
        phi, grad = 0.0, np.zeros(dim)
        for c in bed:
            d = x[b] - x[c]
            r = np.linalg.norm(d)
            vol = mass[c] / rho[c]
            phi += vol * cubic_spline(r, h, dim)
            if r > 0:
                grad += vol * cubic_spline_dwdr(r, h, dim) / r * d
        fraction[b] = phi
        size = np.linalg.norm(grad)
        normal[b] = -grad / size if size > 0 else 0.0
    return fraction, normal


def shields_pickup(soil, water, x, v, mass, rho, material, fixed, suspended, share, stress_dev, fraction,
                   normal, mat, rho_w, nu, g, dx, h, dim, dt, surface_limit, deposit_limit,
                   min_height):  # fmt: skip
    """(shields, share, suspended, stress_dev) after one pass; mat[m] = dict(d50, theta_cr, rho_s) or None."""
    shields, share, suspended, stress_dev = (
        np.zeros(len(x)),
        share.copy(),
        suspended.copy(),
        stress_dev.copy(),
    )
    w0 = float(cubic_spline(0.0, h, dim))
    for b in soil:
        props = mat[material[b]]
        if props is None:
            continue
        vol_b = mass[b] / rho[b]
        lifted = bool(suspended[b])
        near_bed = fraction[b] + w0 * vol_b >= deposit_limit if lifted else fraction[b] < surface_limit
        if not near_bed or not normal[b].any():
            continue
        weights, us2 = [], []
        for a in water:
            if fixed is not None and fixed[a]:
                continue
            d = x[a] - x[b]
            y = d @ normal[b] - 0.5 * dx
            w = mass[a] / rho[a] * cubic_spline(np.linalg.norm(d), h, dim)
            if y < min_height * dx or w <= 0:
                continue
            rel = v[a] - v[b]
            tangential = rel - (rel @ normal[b]) * normal[b]
            weights.append(w)
            us2.append(friction_velocity(np.linalg.norm(tangential), y, 2.5 * props["d50"], nu) ** 2)
        if not weights:
            continue
        theta = rho_w * np.average(us2, weights=weights) / ((props["rho_s"] - rho_w) * g * props["d50"])
        shields[b] = theta
        if lifted:
            if theta <= props["theta_cr"]:
                suspended[b], share[b] = 0, 0.0
            continue
        share[b] += (
            van_rijn(theta, props["theta_cr"], props["d50"], props["rho_s"], rho_w, nu, g)
            * dt
            * (vol_b ** ((dim - 1) / dim) / mass[b])
        )
        if share[b] >= 1.0:
            suspended[b], share[b] = 1, 0.0
            stress_dev[b] = 0.0
    return shields, share, suspended, stress_dev


def free_water(water, soil, x, mass, rho, suspended, h, dim, limit):
    """1 where the bed fraction over non-suspended soil is below limit (bed_shear.FreeWater)."""
    out = np.zeros(len(x), dtype=np.uint8)
    bed = [b for b in soil if not suspended[b]]
    for a in water:
        phi = sum(mass[b] / rho[b] * cubic_spline(np.linalg.norm(x[a] - x[b]), h, dim) for b in bed)
        out[a] = phi < limit
    return out


def wall_shear(soil, water, x, v, mass, rho, material, fixed, suspended, fraction, normal, free, mat, rho_w,
               nu, dx, h, dim, surface_limit, min_height):  # fmt: skip
    """(bed_shear, shear_weight): tau_b t_b and sum W over the free pairs above b (shields_pickup doc)."""
    shear, weight = np.zeros((len(x), dim)), np.zeros(len(x))
    for b in soil:
        props = mat[material[b]]
        if props is None or suspended[b] or fraction[b] >= surface_limit or not normal[b].any():
            continue
        us2, ws, tangents, free_w = [], [], [], 0.0
        for a in water:
            if fixed is not None and fixed[a]:
                continue
            d = x[a] - x[b]
            y = d @ normal[b] - 0.5 * dx
            kernel_w = float(cubic_spline(np.linalg.norm(d), h, dim))
            if y <= 0:
                continue
            free_w += kernel_w if free[a] else 0.0
            w = mass[a] / rho[a] * kernel_w
            if y < min_height * dx or w <= 0:
                continue
            rel = v[a] - v[b]
            tangential = rel - (rel @ normal[b]) * normal[b]
            us2.append(friction_velocity(np.linalg.norm(tangential), y, 2.5 * props["d50"], nu) ** 2)
            ws.append(w)
            tangents.append(tangential)
        if not ws:
            continue
        t = np.average(tangents, axis=0, weights=ws)
        if np.linalg.norm(t) > 0:
            shear[b] = rho_w * np.average(us2, weights=ws) * t / np.linalg.norm(t)
            weight[b] = free_w
    return shear, weight


def wall_shear_accelerations(soil, water, x, mass, rho, fixed, free, shear, weight, normal, dx, h, dim):
    """acc from the wall shear (bed_shear.py): -A_b tau_b t_b W_ab / weight_b / m_a on free water above
    b, +A_b tau_b t_b / m_b on b."""
    acc = np.zeros((len(x), dim))
    for b in soil:
        if weight[b] <= 0:
            continue
        area = (mass[b] / rho[b]) ** ((dim - 1) / dim)
        acc[b] += area * shear[b] / mass[b]
        for a in water:
            if free[a] and not fixed[a] and (x[a] - x[b]) @ normal[b] > 0.5 * dx:
                w = float(cubic_spline(np.linalg.norm(x[a] - x[b]), h, dim))
                acc[a] -= area * shear[b] * w / weight[b] / mass[a]
    return acc


def release_pore_water(free, fraction, rho, rho_half, tait_b, rho0, exponent=7.0):
    """Pore water outside the bed becomes free water (solver/physics/pore_water_release.py): where
    fraction < 1 and free, fraction -> 1 and the densities are divided by the old fraction. Returns the
    new (fraction, rho, rho_half) and the Tait pressures before and after, each with its own reference
    fraction * rho0 (seed eq. 9)."""
    fraction, rho, rho_half = (np.array(a, float) for a in (fraction, rho, rho_half))
    p_before = tait_b * ((rho / (fraction * rho0)) ** exponent - 1.0)
    move = (fraction < 1.0) & (np.asarray(free) != 0)
    rho[move] = rho[move] / fraction[move]
    rho_half[move] = rho_half[move] / fraction[move]
    fraction[move] = 1.0
    p_after = tait_b * ((rho / (fraction * rho0)) ** exponent - 1.0)
    return fraction, rho, rho_half, p_before, p_after
