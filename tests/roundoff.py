"""Round-off bounds for comparing two runs that differ only in summation order (test_mpi.py,
test_soil_3d.py)."""

import math

import numpy as np


def roundoff_tolerances(state, stats, spacing, rho0, c, p_max, alpha):
    """Tolerances on |x|, |v| and |rho| differences between two runs that sum the same pair
    terms in different orders (serial vs MPI; mirror-symmetric particles of one run).

    The MPI run sums the same pair terms as the serial run, but in another order (ghosts sit
    after the owned rows within a cell, rows are re-sorted after migration). The sum of k
    terms t_j in floating point is within gamma_k sum|t_j| of the exact sum for any order
    (Higham 2002, eq. 3.5; gamma_k = k u / (1 - k u), u = 2^-53), so two orders differ by at
    most 2 gamma_k sum|t_j|, with k the largest neighbour count (pi (r_list/dx)^2).

      momentum (eq. 7):   sum|t| <= (2 p_max / rho0 + 2 alpha c v_max) G
                          (soil, eq. 20: p_max the largest stress magnitude, c the P-wave speed)
      continuity (eq. 6): sum|t| <= rho0 (2 v_max) G
    with G = sum_j (m_j / rho_j) |dW/dr(r_ij)| over the lattice (about 1.4 / h), p_max the
    hydrostatic pressure at the bottom of the column and v_max the fastest particle.
    (The viscous term, nu = 1e-6 m^2/s, is 1e-4 of these and left out.)

    These per-step rate errors da, dD enter the leap-frog like a forcing. The scheme is
    stable at this CFL, so the linearised error is not amplified: an acoustic perturbation
    keeps its energy |dv|^2 + (c/rho0)^2 |drho|^2, which also moves error between velocity
    and density at the ratio c/rho0. After N steps of dt, at worst (all errors aligned):
      |dv|   <= N dt (da + (c/rho0) dD)
      |drho| <= N dt (dD + (rho0/c) da)
      |dx|   <= N dt |dv| + 4 ulp(x_max)       (drift of the velocity error; rounding of x)
    For soil the stress plays the pressure's part in the same wave energy, |dsigma| <= rho0 c |dv|.
    A safety factor S = 10 covers the constants (neighbour counts and densities not uniform,
    leap-frog energy constant ~ 1). Measured errors are 300-2000x below these bounds; a real
    bug (a missing ghost or image) gives errors near dt g N ~ 1e-1 m/s, ten orders above.
    """
    from solver.kernels import cubic_spline_dwdr, cubic_spline_normalisation

    u = 2.0**-53
    dx = spacing
    h = 1.3 * dx
    radius = 2.25 * h  # 2h + skin (0.25 h)
    dim = state["x"].shape[1]
    k = math.ceil((math.pi if dim == 2 else 4.0 * math.pi / 3.0) * (radius / dx) ** dim)
    gamma = k * u / (1 - k * u)
    norm = cubic_spline_normalisation(dim, h)
    i = np.arange(-3, 4) * dx
    r = np.sqrt(sum(q**2 for q in np.meshgrid(*[i] * dim)))
    G = sum(dx**dim * abs(float(cubic_spline_dwdr(float(rr), h, norm))) for rr in r.ravel() if 0 < rr < 2 * h)
    v_max = float(np.max(np.linalg.norm(state["v"], axis=1))) + 1e-3
    da = 2 * gamma * (2 * p_max / rho0 + 2 * alpha * c * v_max) * G
    dD = 2 * gamma * rho0 * 2 * v_max * G
    n_dt = stats["t"]  # N dt
    S = 10.0
    tol_v = S * n_dt * (da + c / rho0 * dD)
    tol_rho = S * n_dt * (dD + rho0 / c * da)
    tol_x = n_dt * tol_v + 4 * np.spacing(float(np.max(np.abs(state["x"]))))
    return tol_x, tol_v, tol_rho
