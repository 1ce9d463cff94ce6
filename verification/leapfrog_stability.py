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


def whole_step_density_amplification(omega_dt, alpha=0.0, diffusion=0.0, predicted_av=True):
    """rho at whole steps, v at half steps, one rate evaluation per step, with the damping terms:
    the scheme of numerics.leapfrog = "midpoint_density" (the default for water) and of the former
    "symplectic_density" (grad W at the end of the drift; linearly the same map: the two differ only
    in the nonlinear quadrature of grad W, solver/physics/midpoint_continuity.py).
        v_n       = v_{n-1/2} + a_{n-1} / 2          (predicted: the AV needs a whole-step velocity)
        a_n       = w rho_n - alpha w v_n
        v_{n+1/2} = v_{n-1/2} + a_n
        rho_{n+1} = rho_n - w v_{n+1/2} - diffusion w rho_n
    `diffusion` = delta k h for a mode of wavenumber k: the density diffusion delta h c0 lap(rho)
    (Molteni & Colagrossi 2009) is -delta h c0 k^2 rho = -(delta k h) w rho. State (rho, v, a_{n-1});
    predicted_av=False uses v_{n-1/2} in the AV instead."""
    w = omega_dt
    v_n = np.array([0.0, 1.0, 0.5 if predicted_av else 0.0])
    a_n = w * np.array([1.0, 0.0, 0.0]) - alpha * w * v_n
    v_new = np.array([0.0, 1.0, 0.0]) + a_n
    rho_new = np.array([1.0 - diffusion * w, 0.0, 0.0]) - w * v_new
    return np.array([rho_new, v_new, a_n])


def dualsphysics_symplectic_amplification(omega_dt, alpha=0.0, diffusion=0.0):
    """DualSPHysics' symplectic predictor-corrector (Monaghan 2005 form; Dominguez et al. 2022):
        predictor  rho_{n+1/2} = rho_n + r_n / 2,  v_{n+1/2} = v_n + a_n / 2   (rates at n)
        corrector  rates at n+1/2;  v_{n+1} = v_n + a_{n+1/2},
                   rho_{n+1} = rho_n (2 - eps) / (2 + eps), eps = -(r/rho)_{n+1/2} dt
    Linearised about rho0 the density update is rho_{n+1} = rho_n + r_{n+1/2}: for the acoustic pair
    this is the explicit midpoint rule (two rate evaluations per step), |G|^2 = 1 + w^4/4 undamped."""
    w = omega_dt

    def rates(rho, v):  # rows: coefficients on (rho_n, v_n)
        return -w * v - diffusion * w * rho, w * rho - alpha * w * v

    e = np.eye(2)
    r0, a0 = rates(e[0], e[1])
    rho_h, v_h = e[0] + 0.5 * r0, e[1] + 0.5 * a0
    r_h, a_h = rates(rho_h, v_h)
    return np.array([e[0] + r_h, e[1] + a_h])


def spectral_radius(matrix):
    return float(np.max(np.abs(np.linalg.eigvals(matrix))))


GROWTH_SCHEMES = {
    "seed (rho, v at half steps, predicted), alpha = 0": lambda w: amplification(w, 0.0),
    "seed, alpha = 0.01": lambda w: amplification(w, 0.01),
    "seed, alpha = 0.1": lambda w: amplification(w, 0.1),
    "rho at whole steps (symplectic), alpha = 0": staggered_amplification,
    "rho at whole steps, alpha = 0.01 (AV from predicted v_n)": lambda w: whole_step_density_amplification(
        w, 0.01
    ),
    "rho at whole steps, alpha = 0.01, delta k h = 0.1": lambda w: whole_step_density_amplification(
        w, 0.01, 0.1
    ),
    "rho at whole steps, alpha = 0, delta k h = 0.1": lambda w: whole_step_density_amplification(w, 0.0, 0.1),
    "DualSPHysics symplectic predictor-corrector, alpha = 0": dualsphysics_symplectic_amplification,
    "DualSPHysics symplectic, alpha = 0.01, delta k h = 0.1": lambda w: dualsphysics_symplectic_amplification(
        w, 0.01, 0.1
    ),
}


if __name__ == "__main__":
    import sys

    from .common import script_parser

    script_parser(sys.modules[__name__]).parse_args()
    ws = (0.1, 0.3, 0.5, 1.0, 1.5)
    print("| scheme (growth per step) | " + " | ".join(f"omega dt = {w}" for w in ws) + " |")
    print("|---|" + "---|" * len(ws))
    for name, step in GROWTH_SCHEMES.items():
        print(f"| {name} | " + " | ".join(f"{spectral_radius(step(w)):.5f}" for w in ws) + " |")
    print()
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
