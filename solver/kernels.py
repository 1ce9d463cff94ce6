"""Smoothing kernels W(r, h) and their radial derivative dW/dr.

Cubic spline of Monaghan & Lattanzio (1985), seed eq. (5) with the erratum of DESIGN.md
(first branch 2/3 - R^2 + R^3/2). Written branch-free as
    W = a_d [ (2-R)_+^3 - 4 (1-R)_+^3 ] / 6,
which equals eq. (5) on both branches and vectorises in the pair loops.
The dimension enters only through the normalisation a_d, so 1D/2D/3D share the code.
"""

import math

import numpy as np

from .config import kernel

SUPPORT_RADIUS = 2.0  # k in seed eq. (4): W = 0 for r > 2h


def cubic_spline_normalisation(dim, h):
    """a_d of eq. (5): 1/h, 15/(7 pi h^2), 3/(2 pi h^3)."""
    if dim == 1:
        return 1.0 / h
    if dim == 2:
        return 15.0 / (7.0 * math.pi * h * h)
    if dim == 3:
        return 3.0 / (2.0 * math.pi * h**3)
    raise ValueError(f"dimension must be 1, 2 or 3, not {dim}")


@kernel
def cubic_spline_w(r, h, norm):
    """W(r, h); `norm` is cubic_spline_normalisation(dim, h)."""
    R = r / h
    a = max(2.0 - R, 0.0)
    b = max(1.0 - R, 0.0)
    return norm * (a * a * a - 4.0 * b * b * b) / 6.0


@kernel
def cubic_spline_dwdr(r, h, norm):
    """dW/dr; negative inside the support, zero at r = 0 and r >= 2h."""
    R = r / h
    a = max(2.0 - R, 0.0)
    b = max(1.0 - R, 0.0)
    return norm * (-0.5 * a * a + 2.0 * b * b) / h


def kernel_values(r, h, dim):
    """Vectorised W for arrays of r (NumPy; used in set-up and tests)."""
    R = np.asarray(r, dtype=float) / h
    a = np.clip(2.0 - R, 0.0, None)
    b = np.clip(1.0 - R, 0.0, None)
    return cubic_spline_normalisation(dim, h) * (a**3 - 4.0 * b**3) / 6.0
