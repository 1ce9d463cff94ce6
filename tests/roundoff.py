"""Round-off bounds for comparing two runs that differ only in summation order (test_mpi.py,
test_soil_3d.py)."""

import numpy as np


def roundoff_tolerances(state, stats, spacing, rho0, c, p_max, alpha):
    """Tolerances on |x|, |v| and |rho| differences between two runs that sum the same pair
    terms in different orders (serial vs MPI; mirror-symmetric particles of one run).

    The MPI run sums the same pair terms as the serial run, but in another order (ghosts sit
    after the owned rows within a cell, rows are re-sorted after migration). The sum of k
    terms t_j in floating point is within gamma_k sum|t_j| of the exact sum for any order
    (Higham 2002, eq. 3.5; gamma_k = k u / (1 - k u), u = 2^-53), so two orders differ by at
    most 2 gamma_k sum|t_j|, with k the largest number of terms (neighbour count, below).

      momentum (eq. 7):   sum|t| <= (2 p_max / rho0 + 2 alpha c v_max) G
                          (soil, eq. 20: p_max the largest stress magnitude, c the P-wave speed)
      continuity (eq. 6): sum|t| <= rho0 (2 v_max) G
    with G = sum_j (m_j / rho_j) |dW/dr(r_ij)| (bounded below), p_max the largest pressure
    (hydrostatic at the bottom of the column) and v_max the fastest particle.
    (The viscous term, nu = 1e-6 m^2/s, is 1e-4 of these and left out.)

    These per-step rate errors da, dD enter the leap-frog like a forcing; after N steps of dt,
    at worst (all errors aligned) and with an acoustic perturbation keeping its energy
    |dv|^2 + (c/rho0)^2 |drho|^2 up to the scheme's growth per step g (which also moves error
    between velocity and density at the ratio c/rho0):
      |dv|   <= A N dt (da + (c/rho0) dD)
      |drho| <= A N dt (dD + (rho0/c) da)
      |dx|   <= N dt |dv| + 4 ulp(x_max)       (drift of the velocity error; rounding of x)
    For soil the stress plays the pressure's part in the same wave energy, |dsigma| <= rho0 c |dv|.

    Every constant is a bound computed here, none a safety factor (issue 13 replaced the
    former S = 10, which stood for "neighbour counts and densities not uniform, leap-frog
    constant ~ 1"):
      k  = 2^dim x the largest neighbour count within the list radius in `state` (brute force;
           2^dim: a particle near a corner also sums the images of up to 2^dim - 1 mirrors);
      G <= k max|dW/dr| max(m/rho)   (every term of the sum at its largest; m/rho from `state`
           when it has mass and rho, else dx^dim / (1 - 0.02), 2 % compression);
      A  = max(1, g^N), g the spectral radius of the seed's leap-frog step for the fastest
           acoustic mode the SPH operator carries (omega_max = c max_k |sum_j V_j sin(k x_j)
           dW/dx(x_j)|, the Fourier symbol of the SPH gradient on the lattice), at the largest
           dt the sound limit allows (seed eq. 28, C_s = 0.25), without artificial viscosity
           (verification/leapfrog_stability.py). It is 1.55 for 300 steps in 2D, whatever the
           resolution.
    Measured errors are about 1e4 below these bounds; a real bug (a missing ghost or image)
    gives errors near dt g N ~ 1e-1 m/s, ten orders above.
    """
    from solver.kernels import cubic_spline_dwdr, cubic_spline_normalisation
    from verification.leapfrog_stability import amplification, spectral_radius

    u = 2.0**-53
    dx = spacing
    h = 1.3 * dx
    radius = 2.25 * h  # 2h + skin (0.25 h)
    x = np.asarray(state["x"], dtype=float)
    dim = x.shape[1]
    k = 2**dim * _max_neighbours(x, radius)
    gamma = k * u / (1 - k * u)
    norm = cubic_spline_normalisation(dim, h)
    r = np.linspace(0.0, 2.0 * h, 2001)
    dw_max = max(abs(float(cubic_spline_dwdr(float(rr), h, norm))) for rr in r)
    if "mass" in state and "rho" in state:
        volume = float(np.max(np.asarray(state["mass"]) / np.asarray(state["rho"])))
    else:
        volume = dx**dim / (1 - 0.02)
    G = k * dw_max * volume
    v_max = float(np.max(np.linalg.norm(state["v"], axis=1))) + 1e-3
    da = 2 * gamma * (2 * p_max / rho0 + 2 * alpha * c * v_max) * G
    dD = 2 * gamma * rho0 * 2 * v_max * G
    n_dt = stats["t"]  # N dt
    steps = int(stats.get("steps", state.get("steps", 0)))
    omega_dt = _fastest_sph_mode(dim, h, dx, norm) * c * (0.25 * h / c)
    A = max(1.0, spectral_radius(amplification(omega_dt, 0.0)) ** steps)
    tol_v = A * n_dt * (da + c / rho0 * dD)
    tol_rho = A * n_dt * (dD + rho0 / c * da)
    tol_x = n_dt * tol_v + 4 * np.spacing(float(np.max(np.abs(x))))
    return tol_x, tol_v, tol_rho


def _max_neighbours(x, radius):
    """Largest number of other particles within radius of one particle (brute force, chunked)."""
    best = 0
    for a in range(0, len(x), 512):
        d2 = np.sum((x[a : a + 512, None, :] - x[None, :, :]) ** 2, axis=2)
        best = max(best, int(np.max(np.sum(d2 < radius * radius, axis=1))) - 1)
    return best


def _fastest_sph_mode(dim, h, dx, norm):
    """max over k of |sum_j V sin(k x_j) dW/dx(x_j)| on the lattice (V = dx^dim): the largest
    frequency / c of a plane acoustic wave under the SPH gradient (it peaks near k dx = 1.3,
    well below the lattice's pi, and is about 1.06 / h in 2D)."""
    from solver.kernels import cubic_spline_dwdr

    offsets = np.arange(-3, 4) * dx  # the support 2h = 2.6 dx lies within three spacings
    pts = np.stack(np.meshgrid(*[offsets] * dim, indexing="ij"), axis=-1).reshape(-1, dim)
    r = np.linalg.norm(pts, axis=1)
    gx = np.array(
        [
            float(cubic_spline_dwdr(float(rr), h, norm)) * p[0] / rr if 0 < rr < 2 * h else 0.0
            for rr, p in zip(r, pts)
        ]
    )
    ks = np.linspace(0.0, np.pi / dx, 4001)
    return float(np.max(np.abs(np.sin(np.outer(ks, pts[:, 0])) @ gx)) * dx**dim)
