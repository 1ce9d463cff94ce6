"""Log-law wall shear on water at walls of kind "wall_function" (a wall model for an unresolved boundary
layer; the images of such a wall are free-slip, so this term is the wall's only tangential traction).

Each water particle within the kernel support 2h of such a wall gets its friction velocity u* from its
own tangential speed |u_t| and wall distance y (y at least dx/2, where a lattice's first layer sits) by
the smooth-wall law of the wall (Launder & Spalding 1974, Comput. Methods Appl. Mech. Eng. 3:269):
    |u_t| / u* = ln(E y+) / kappa   for y+ = u* y / nu >= Y_LAM (log layer),
    |u_t| / u* = y+                 below (viscous sublayer: tau_w = mu |u_t| / y),
kappa = 0.41, E = 9.8, Y_LAM = 11.06 (where the two meet). The wall traction tau_w = rho u*^2 enters the
momentum equation as the boundary integral of the kernel (the semi-analytical wall terms of Ferrand et
al. 2013, Int. J. Numer. Meth. Fluids 71:446, with a planar wall):
    a_i = -2 u*_i^2 w(d_i) u_t,i / |u_t,i|,    w(d) = integral of W over the wall plane at distance d,
so that over a half-space of particles sum_i V_i w(d_i) = 1/2 per unit wall area and the fluid feels
the traction tau_w once (sum_i m_i a_i = -tau_w per unit area when every particle's u* is the same,
i.e. when the velocity profile is the log law). Walls are the box sides (axis-aligned planes).

Why a wall function: at the particle sizes of a dam break (dx = 4-15 mm) the physical boundary layer
(a few mm) lies inside the first particle layer, and the viscous shear of no-slip images, mu 2 u / dx,
is 5-10 times smaller than a log layer's (verification/results/impact_pressure/README.md).
Time step: the relaxation rate of the traction, d a / d u <= 4 w(0) u / Y_LAM^2 < 0.1 u / h, is far
below the acoustic CFL limit, so no dt limit is declared.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..config import kernel
from ..kernels import kernel_values
from ..materials import Phase
from ..term import Equation, Stage, Term

KAPPA = 0.41  # von Karman constant (Launder & Spalding 1974)
E_SMOOTH = 9.8  # log-law constant of a hydraulically smooth wall (Launder & Spalding 1974)
Y_LAM = 11.06  # y+ where y+ = ln(E y+) / kappa: the sublayer-log layer switch
TABLE = 201  # points of the tabulated w(d), d in [0, 2h]


def wall_weight_table(h, dim, n=TABLE):
    """w(d) = integral of the cubic spline over a plane at distance d, tabulated at d = 2h k / (n - 1).
    2D: 2 int_0^s W(sqrt(d^2 + s^2)) ds; 3D: int_d^2h W(r) 2 pi r dr (rings on the plane)."""
    d = np.linspace(0.0, 2.0 * h, n)
    out = np.zeros(n)
    for k, dk in enumerate(d):
        if dim == 2:
            s = np.linspace(0.0, math.sqrt(max(4.0 * h * h - dk * dk, 0.0)), 2001)
            f = kernel_values(np.sqrt(dk * dk + s * s), h, 2)
            out[k] = 2.0 * np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(s))
        else:
            r = np.linspace(dk, 2.0 * h, 2001)
            f = kernel_values(r, h, 3) * 2.0 * math.pi * r
            out[k] = np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(r))
    return out


@kernel
def friction_velocity(u, y, nu):
    """u* of the smooth-wall law for tangential speed u >= 0 at distance y > 0 (module doc); Newton
    iterations on u* ln(E u* y / nu) / kappa = u from the sublayer's or a log-layer start."""
    if u <= 0.0:
        return 0.0
    u_lam = math.sqrt(u * nu / y)  # viscous sublayer: u / u* = y+
    if u_lam * y / nu < Y_LAM:
        return u_lam
    us = KAPPA * u / math.log(E_SMOOTH * max(u_lam * y / nu, Y_LAM))
    for _ in range(30):
        lg = math.log(E_SMOOTH * us * y / nu)
        f = us * lg / KAPPA - u
        us_new = us - f / ((lg + 1.0) / KAPPA)
        if us_new <= 0.0:
            us_new = 0.5 * us
        if abs(us_new - us) <= 1e-12 * us:
            return us_new
        us = us_new
    return us


@kernel(parallel=True)
def wall_function_acc(rows, x, v, material, nu, planes, h, y_min, table, acc):
    """a_i += -2 u*^2 w(d) u_t / |u_t| for each owned water row i and each wall plane within 2h
    (planes[k] = (axis, position, side): side +1 a lower wall, -1 an upper one)."""
    dim = x.shape[1]
    n_tab = table.shape[0]
    step = 2.0 * h / (n_tab - 1)
    for t in prange(rows.shape[0]):
        i = rows[t]
        for k in range(planes.shape[0]):
            a = int(planes[k, 0])
            d = planes[k, 2] * (x[i, a] - planes[k, 1])
            if d >= 2.0 * h:
                continue
            d = max(d, 0.0)
            ut2 = 0.0
            for b in range(dim):
                if b != a:
                    ut2 += v[i, b] * v[i, b]
            ut = math.sqrt(ut2)
            if ut <= 0.0:
                continue
            us = friction_velocity(ut, max(d, y_min), nu[material[i]])
            q = d / step
            j = min(int(q), n_tab - 2)
            w = table[j] + (q - j) * (table[j + 1] - table[j])
            scale = -2.0 * us * us * w / ut
            for b in range(dim):
                if b != a:
                    acc[i, b] += scale * v[i, b]


def wall_planes(scene):
    """(axis, position, side) of each box side of kind "wall_function"."""
    rows = []
    for a, ax in enumerate("xyz"[: scene.dim]):
        if getattr(scene.walls, f"{ax}_min") == "wall_function":
            rows.append((a, scene.domain.min[a], 1.0))
        if getattr(scene.walls, f"{ax}_max") == "wall_function":
            rows.append((a, scene.domain.max[a], -1.0))
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


class WallFunctionShear(Term):
    """The log-law wall traction on water next to "wall_function" walls."""

    name = "wall function"
    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        if "wall_function" not in scene.walls.kinds() or not materials.has_phase(Phase.WATER):
            return None
        return cls(scene, materials)

    def __init__(self, scene, materials):
        super().__init__()
        self.planes = wall_planes(scene)
        self.nu = np.array(
            [mu / rho if rho > 0 else 0.0 for mu, rho in zip(materials.viscosity, materials.rho0)], float
        )
        self.y_min = 0.5 * scene.scene.spacing
        self.table = wall_weight_table(scene.h, scene.dim)
        self.reads = ()  # owned rows only: no halo or image refresh needed
        self.adds_to = ("acc",)
        self.equations = (
            Equation(
                f"log-law wall shear tau_w = rho u*^2 (kappa = {KAPPA}, E = {E_SMOOTH}) on water within "
                f"2h of {len(self.planes)} wall(s), as a kernel boundary integral",
                "Launder & Spalding (1974); Ferrand et al. (2013)",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        wall_function_acc(
            ctx.rows[Phase.WATER], ps["x"], ps["v"], ps["material"], self.nu, self.planes, ctx.h, self.y_min,
            self.table, ps["acc"],
        )  # fmt: skip
