"""Point probes: SPH interpolation of a particle field at fixed points, as a gauge measures.

    f(x) = sum_j (m_j / rho_j) f_j W(x - x_j, h) / sum_j (m_j / rho_j) W(x - x_j, h)
(Shepard-normalised, so a probe near a free surface is not biased low by the missing
support). Brute force NumPy: verification sizes only.
"""

import numpy as np

from solver.kernels import kernel_values


def probe(points, x, field, mass, rho, h, dim):
    points = np.atleast_2d(points)
    r = np.linalg.norm(points[:, None, :] - x[None, :, :], axis=2)
    w = kernel_values(r, h, dim) * (mass / rho)[None, :]
    total = w.sum(axis=1)
    return np.where(total > 0, (w @ field) / np.where(total > 0, total, 1.0), np.nan)
