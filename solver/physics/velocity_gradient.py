"""The SPH velocity gradient, one neighbour pair at a time:

    g_ab = dv^b/dx^a = sum_j (m_j / rho_j) (v_j^b - v_i^b) dW_ij/dx_i^a    (Liu & Liu 2003, eq. 4.31)

shared by the water's viscous stress (seed eqs. 10-11) and the soil's Hooke-Jaumann rate
(seed eqs. 13-15). The nine components travel as a tuple so that the accumulators stay in
registers of the calling pair loop.
"""

from ..config import kernel

ZERO = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
"""(g00, g01, g02, g10, g11, g12, g20, g21, g22) before the first pair."""


@kernel
def add_pair(g, u0, u1, u2, f, d0, d1, d2, three):
    """g_ab += w_b d_a for one pair, w = -u f: u = v_i - v_j, f = (m_j / rho_j) (dW/dr) / r,
    d = x_i - x_j (grad_i W_ij = d (dW/dr) / r). In 2D (three False) the z terms are skipped."""
    g00, g01, g02, g10, g11, g12, g20, g21, g22 = g
    w0 = -u0 * f
    w1 = -u1 * f
    g00 += w0 * d0
    g01 += w1 * d0
    g10 += w0 * d1
    g11 += w1 * d1
    if three:
        w2 = -u2 * f
        g02 += w2 * d0
        g12 += w2 * d1
        g20 += w0 * d2
        g21 += w1 * d2
        g22 += w2 * d2
    return g00, g01, g02, g10, g11, g12, g20, g21, g22
