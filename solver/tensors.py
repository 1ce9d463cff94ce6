"""Symmetric tensors are stored as 6 components in every dimension:

    0: xx   1: yy   2: zz   3: xy   4: yz   5: xz

A 2D scene is plane strain: zz is kept (soil needs s_zz for the yield criterion) and the
out-of-plane shears stay zero. Mirroring a tensor across walls flips the sign of each
component by s_a s_b (seed eq. 23); SYM_AXES lists (a, b) per component for that.
"""

import numpy as np

from .config import kernel

XX, YY, ZZ, XY, YZ, XZ = range(6)
N_SYM = 6
SYM_AXES = np.array([[0, 0], [1, 1], [2, 2], [0, 1], [1, 2], [0, 2]], dtype=np.int64)


@kernel
def positive_part(a0, a1, a2, a3, a4, a5):
    """The positive part sum_a max(lambda_a, 0) n_a n_a of a symmetric 3x3 tensor (6 components,
    the order above), by cyclic Jacobi rotations (Golub & Van Loan 2013, sec. 8.5): no LAPACK is
    needed inside Numba, and repeated eigenvalues are handled, where closed forms divide by zero."""
    a = np.empty((3, 3))
    a[0, 0], a[1, 1], a[2, 2] = a0, a1, a2
    a[0, 1] = a[1, 0] = a3
    a[1, 2] = a[2, 1] = a4
    a[0, 2] = a[2, 0] = a5
    q = np.eye(3)
    scale = abs(a0) + abs(a1) + abs(a2) + abs(a3) + abs(a4) + abs(a5)
    for _sweep in range(12):  # quadratic convergence: 4-6 sweeps reach round-off
        off = abs(a[0, 1]) + abs(a[1, 2]) + abs(a[0, 2])
        if off <= 1e-15 * scale:
            break
        for p, r in ((0, 1), (1, 2), (0, 2)):
            if a[p, r] == 0.0:
                continue
            theta = 0.5 * (a[r, r] - a[p, p]) / a[p, r]
            t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
            c = 1.0 / np.sqrt(t * t + 1.0)
            s = t * c
            for k in range(3):  # a <- a J (columns p, r)
                akp, akr = a[k, p], a[k, r]
                a[k, p] = c * akp - s * akr
                a[k, r] = s * akp + c * akr
            for k in range(3):  # a <- J^T a (rows p, r)
                apk, ark = a[p, k], a[r, k]
                a[p, k] = c * apk - s * ark
                a[r, k] = s * apk + c * ark
            for k in range(3):  # q <- q J: columns are the eigenvectors
                qkp, qkr = q[k, p], q[k, r]
                q[k, p] = c * qkp - s * qkr
                q[k, r] = s * qkp + c * qkr
    out = np.zeros(6)
    for m in range(3):
        lam = a[m, m]
        if lam > 0.0:
            out[0] += lam * q[0, m] * q[0, m]
            out[1] += lam * q[1, m] * q[1, m]
            out[2] += lam * q[2, m] * q[2, m]
            out[3] += lam * q[0, m] * q[1, m]
            out[4] += lam * q[1, m] * q[2, m]
            out[5] += lam * q[0, m] * q[2, m]
    return out
