"""The pore water's pressure gradient in the corrected difference form (numerics.pore_pressure_gradient =
"corrected", opt-in; docs/seepage.md, case 5).

The water's own pass (fluid_rates.py, seed eq. 7) is the symmetric form
  a_i = -sum_j m_j (p_i / rho_i^2 + p_j / rho_j^2) grad_i W_ij,
which conserves momentum pair by pair but is not zeroth-order consistent: its expansion holds
-2 (p_i / rho_i) sum_j V_j grad_i W_ij, zero on a lattice and O(eps / dx) for particles displaced by
eps, times the full pressure. In pore water flowing through a fixed skeleton the pressure is mostly
hydrostatic (~2 kPa in the sheet pile) while the seepage is driven by head differences of a few
hundred Pa, so small distortions of the pore water's lattice give forces of the order of the drag
(measured: median 0 -> 141 N/m^3 within 1 s against a drag of ~1490 N/m^3 next to the pile).

For pore water (water of pore field < 1: the seed's pore_label or the mixture's water_fraction) the
option replaces it by the difference form with the kernel-gradient correction,
  a_i = -(1 / rho_i) L_i sum_j V_j (p_j - p_i) grad_i W_ij,   L_i = M_i^-1,
  M_i = sum_j V_j grad_i W_ij (x) (x_j - x_i) = -sum_j V_j (W'/r) x_ij (x) x_ij,
the normalised gradient of Randles & Libersky (1996, Comput. Methods Appl. Mech. Engrg. 139:375,
eqs. 2.10-2.12) and Bonet & Lok (1999, Comput. Methods Appl. Mech. Engrg. 180:97, sec. 2.3, eq. 27 with
the correction of their eq. 45): exact for a linear pressure on any particle arrangement with a full
support, so a uniform background pressure (and a hydrostatic one) gives no force however the pore
water is arranged, and it reads grad p without the lattice factor kappa (1.0105) of the symmetric form.

What it costs: the pair forces are no longer equal and opposite (V_i V_j (p_j - p_i) L_i grad W_ij is
not antisymmetric in i, j), so the pore water's linear momentum is not conserved pair by pair, nor its
angular momentum (Bonet & Lok 1999, sec. 3: only the corrected *symmetric* forms keep them, and those
keep the zeroth-order term). The pore water exchanges momentum with the skeleton through the drag,
which balances the pressure gradient to within the discretisation error; the momentum error is that
error, O(h^2) in the bulk. The symmetric form's zeroth-order term also acts as a restoring force that
keeps particles ordered (it is why WCSPH uses it); the difference form has none, which the drag of a
skeleton (relaxation rate n g / k, 4e3 /s at k = 1e-3 m/s) makes harmless in pores. Free water keeps
the symmetric form.

Where the water support is cut (the Shepard sum sum_j V_j W_ij below CUT_SUPPORT: pore water at a
free surface) or M is near singular, the acceleration is blended to the symmetric form, which holds
a free surface at p = 0. The blend weight and M^-1 come from `corrected_weight` and `solve_m` here;
the sums are gathered inside fluid_rates' loop (no extra pass).
"""

from __future__ import annotations

from ..config import kernel

# Where a pore-water particle's water support counts as full (the Shepard sum sum_j V_j W_ij): below
# CUT_SUPPORT[0] the symmetric form, above CUT_SUPPORT[1] the corrected one, linear between. Cubic
# spline at h = 1.3 dx: the first lattice row at a plane cut of the support reads 0.765, the second 0.990;
# a lattice jittered by up to 0.15 dx (tests/conftest.py) reads 0.90-1.13 in its bulk, 0.93-1.08 for 90 %.
CUT_SUPPORT = (0.80, 0.90)


@kernel
def corrected_weight(den, det):
    """Weight of the corrected form against the symmetric one: 0 below CUT_SUPPORT[0] of the Shepard
    sum den, 1 above CUT_SUPPORT[1], linear between; 0 where det M is below a quarter of its lattice
    value (~1: M ~ kappa I, kappa ~ 1), a support cut to half in some direction."""
    lo, hi = CUT_SUPPORT
    s = min(max((den - lo) / (hi - lo), 0.0), 1.0)
    if not det > 0.25:
        s = 0.0
    return s


@kernel
def solve_m(m0, m1, m2, m3, m4, m5, g0, g1, g2, is3d):
    """(det M, M^-1 g) for the symmetric M of 6 components (solver/tensors.py order: xx, yy, zz, xy,
    yz, xz); in 2D m2, m4, m5 and g2 are ignored."""
    if is3d is None:
        det = m0 * m1 - m3 * m3
        if not det > 0.0:
            return det, 0.0, 0.0, 0.0
        return det, (m1 * g0 - m3 * g1) / det, (m0 * g1 - m3 * g0) / det, 0.0
    i0 = m1 * m2 - m4 * m4
    i1 = m0 * m2 - m5 * m5
    i2 = m0 * m1 - m3 * m3
    i3 = m4 * m5 - m3 * m2
    i4 = m3 * m5 - m0 * m4
    i5 = m3 * m4 - m1 * m5
    det = m0 * i0 + m3 * i3 + m5 * i5
    if not det > 0.0:
        return det, 0.0, 0.0, 0.0
    return (
        det,
        (i0 * g0 + i3 * g1 + i5 * g2) / det,
        (i3 * g0 + i1 * g1 + i4 * g2) / det,
        (i5 * g0 + i4 * g1 + i2 * g2) / det,
    )
