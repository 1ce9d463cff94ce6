"""Grain-scale sediment formulas of the erosion law (solver/physics/shields_pickup.py; docs/erosion.md).

All in SI units; d is the median grain size d50, s = rho_grain / rho_water, nu the water's kinematic
viscosity. Scalar functions are Numba-compiled so the pick-up kernel calls them per particle; they
run unchanged from Python.

  D*        = d ((s - 1) g / nu^2)^(1/3)                            Soulsby (1997) ch. 6
  theta_cr  = 0.30 / (1 + 1.2 D*) + 0.055 (1 - exp(-0.020 D*))      Soulsby & Whitehouse (1997),
                                                                    as in Soulsby (1997) ch. 6
  theta     = tau_b / ((rho_grain - rho_water) g d)                 Shields (1936)
  E         = 0.00033 rho_grain ((s - 1) g d)^0.5 D*^0.3 T^1.5,     van Rijn (1984), J. Hydraul. Eng.
              T = (theta - theta_cr) / theta_cr  (kg/m^2/s)         110(10):1494, "Sediment pick-up functions"
  u(y)      = (u* / kappa) ln(y / z0),                              Christoffersen & Jonsson (1985);
  z0        = (k_s / 30)(1 - exp(-u* k_s / (27 nu))) + nu / (9 u*)  Soulsby (1997) ch. 3
  k_s       = 2.5 d                                                 Soulsby (1997): z0 = d / 12 rough

The log law's z0 blends the smooth (nu / 9u*) and the rough (k_s / 30) walls, so the friction
velocity of a sand bed is right whether its grain Reynolds number u* k_s / nu is 1 or 1000.
"""

from __future__ import annotations

import math

from .config import kernel

KAPPA = 0.40  # von Karman constant as Soulsby (1997) uses it with z0
ROUGHNESS_PER_GRAIN = 2.5  # k_s = 2.5 d50 (Nikuradse roughness of a flat grain bed; Soulsby 1997)
VAN_RIJN_PICKUP = 0.00033  # van Rijn (1984) pick-up coefficient


@kernel
def dimensionless_grain_size(d, s, nu, g):
    """D*, the dimensionless grain size (Soulsby 1997)."""
    return d * ((s - 1.0) * g / (nu * nu)) ** (1.0 / 3.0)


@kernel
def critical_shields(dstar):
    """theta_cr of Soulsby & Whitehouse (1997) (as given by Soulsby 1997): the threshold of motion of a
    flat bed, fitted to the Shields data over D* = 0.1 - 1000."""
    return 0.30 / (1.0 + 1.2 * dstar) + 0.055 * (1.0 - math.exp(-0.020 * dstar))


@kernel
def pickup_rate(theta, theta_cr, d, s, dstar, rho_grain, g):
    """Mass of sediment lifted per unit bed area and time (kg/m^2/s), van Rijn (1984); 0 below the
    threshold."""
    if theta <= theta_cr:
        return 0.0
    excess = (theta - theta_cr) / theta_cr
    return VAN_RIJN_PICKUP * rho_grain * math.sqrt((s - 1.0) * g * d) * dstar**0.3 * excess**1.5


@kernel
def roughness_length(u_star, k_s, nu):
    """z0 of the transitional law of the wall (module doc)."""
    if u_star <= 0.0:
        return math.inf
    return k_s / 30.0 * (1.0 - math.exp(-u_star * k_s / (27.0 * nu))) + nu / (9.0 * u_star)


@kernel
def bed_friction_velocity(u, y, k_s, nu):
    """u* with u = (u* / kappa) ln(y / z0(u*)) for a tangential speed u >= 0 at height y above the
    bed. Fixed-point iteration from the rough wall's u*; y / z0 is kept above e (the law's lower end,
    a speed measured inside the roughness layer reads as if at y = e z0)."""
    if u <= 0.0 or y <= 0.0:
        return 0.0
    us = KAPPA * u / max(math.log(30.0 * y / k_s), 1.0)
    for _ in range(60):
        z0 = roughness_length(us, k_s, nu)
        us_new = KAPPA * u / max(math.log(y / z0), 1.0)
        if abs(us_new - us) <= 1e-10 * us_new:
            return us_new
        us = 0.5 * (us + us_new)  # damped: z0's smooth branch makes the plain iteration oscillate
    return us


@kernel
def speed_at_height(u_star, y, k_s, nu):
    """The log law's u(y) for a given u* (the inverse of bed_friction_velocity, for flows imposed in
    tests and verification)."""
    z0 = roughness_length(u_star, k_s, nu)
    return u_star / KAPPA * max(math.log(y / z0), 1.0)
