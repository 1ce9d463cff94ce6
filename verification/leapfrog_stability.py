"""Linear stability of the seed's leap-frog (eqs. 24-27) for one acoustic mode.

An acoustic mode of the weakly compressible equations is, per Fourier component,
    d(rho)/dt = -w v,   dv/dt = w rho - alpha w v        (w = omega, alpha: AV-like damping)
The seed integrates rho and v both at half steps, with rates at step n from values
predicted with the previous rates (Liu & Liu 2003, sec. 4.4.3). One step maps the state
(rho_{n-1/2}, v_{n-1/2}, r_{n-1}, a_{n-1}) linearly; its spectral radius is the growth per
step. `python -m verification.leapfrog_stability` prints the table in the README.
"""

import numpy as np


def amplification(omega_dt, alpha=0.0, predict_rho=True, predict_v=True):
    """Step matrix of the half-step scheme (dt = 1, w = omega dt)."""
    w = omega_dt
    rho_n = np.array([1.0, 0.0, 0.5 * predict_rho, 0.0])
    v_n = np.array([0.0, 1.0, 0.0, 0.5 * predict_v])
    r_n = -w * v_n
    a_n = w * rho_n - alpha * w * v_n
    return np.array([np.eye(4)[0] + r_n, np.eye(4)[1] + a_n, r_n, a_n])


def staggered_amplification(omega_dt):
    """rho at whole steps (like x), v at half steps: rho_{n+1} = rho_n - w v_{n+1/2},
    v_{n+3/2} = v_{n+1/2} + w rho_{n+1}: the symplectic leap-frog."""
    w = omega_dt
    return np.array([[1.0, -w], [w, 1.0 - w * w]])


def spectral_radius(matrix):
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))


if __name__ == "__main__":
    ws = (0.1, 0.3, 0.5, 1.0)
    print("| scheme | " + " | ".join(f"omega dt = {w}" for w in ws) + " |")
    print("|---|" + "---|" * len(ws))
    for alpha in (0.0, 0.01, 0.1):
        print(
            f"| seed (rho, v at half steps, predicted), alpha = {alpha} | "
            + " | ".join(f"{spectral_radius(amplification(w, alpha)):.5f}" for w in ws)
            + " |"
        )
    print(
        "| rho at whole steps (symplectic), alpha = 0 | "
        + " | ".join(f"{spectral_radius(staggered_amplification(w)):.5f}" for w in ws)
        + " |"
    )
