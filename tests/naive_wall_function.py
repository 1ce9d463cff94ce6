"""Slow NumPy twin of solver/physics/wall_function.py (the log-law wall shear), written from the
module's equations: a bisection for u* instead of Newton, the plane integral w(d) by direct
quadrature of the kernel on a fine grid instead of the table."""

import math

import numpy as np

from solver.kernels import kernel_values

KAPPA, E, Y_LAM = 0.41, 9.8, 11.06


def friction_velocity(u, y, nu):
    """u* from |u_t| = u at distance y: u / u* = y+ below Y_LAM, ln(E y+) / kappa above (bisection)."""
    if u <= 0.0:
        return 0.0

    def law(us):
        yp = us * y / nu
        return us * (yp if yp < Y_LAM else math.log(E * yp) / KAPPA) - u  # increasing in u*

    lo, hi = 0.0, math.sqrt(u * nu / y) + u  # law(hi) > 0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if law(mid) < 0 else (lo, mid)
    return 0.5 * (lo + hi)


def plane_weight(d, h, dim, grid=False):
    """Integral of W over a plane at distance d from the point (2D: a line): a Riemann sum along the
    line in 2D; in 3D over the in-plane radius rho (area 2 pi rho d rho) or, with grid=True, on a
    square grid of the plane (slow: for spot checks)."""
    s = np.linspace(-2.0 * h, 2.0 * h, 4001)
    ds = s[1] - s[0]
    if dim == 2:
        return float(kernel_values(np.sqrt(d * d + s * s), h, 2).sum() * ds)
    if grid:
        a, b = np.meshgrid(s[::8], s[::8])
        return float(kernel_values(np.sqrt(d * d + a * a + b * b), h, 3).sum() * (8 * ds) ** 2)
    rho = s[2000:]
    f = kernel_values(np.sqrt(d * d + rho * rho), h, 3) * 2.0 * np.pi * rho
    return float(np.sum(0.5 * (f[1:] + f[:-1])) * ds)


def wall_function_acc(x, v, nu, planes, h, y_min):
    """acc per particle: -2 u*^2 w(d) u_t / |u_t| summed over the planes (axis, position, side) within 2h."""
    acc = np.zeros_like(v)
    for i in range(len(x)):
        for a, pos, side in planes:
            a = int(a)
            d = side * (x[i, a] - pos)
            if d >= 2.0 * h:
                continue
            d = max(d, 0.0)
            ut = v[i].copy()
            ut[a] = 0.0
            speed = np.linalg.norm(ut)
            if speed == 0.0:
                continue
            us = friction_velocity(speed, max(d, y_min), nu)
            acc[i] += -2.0 * us * us * plane_weight(d, h, x.shape[1]) * ut / speed
    return acc
