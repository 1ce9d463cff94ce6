"""Particle shifting of the pore water (Lind et al. 2012, J. Comput. Phys. 231:1499, sec. 3.2: Fickian
shifting): after the drift each pore-water particle a moves by

    dr_a = -D grad C_a,   D = A h |v_a| dt,   C_a = sum_b V_b W_ab,   grad C_a = sum_b V_b grad_a W_ab

over its water neighbours b (pore water, free water and wall particles alike), A = 2 (Lind et al.
use 2; they found 1-6 to work). Why (docs/seepage.md, case 5): the Lagrangian pore water flows
through a fixed (or slowly moving) skeleton and is sheared by the flow net around an obstacle, so
it loses its lattice order; the pressure and drag sums over the disordered neighbours let less water
through and a steady discharge drifts (the sheet pile: -0.017 / -0.027 of Q/(k dH) per second at
10 / 5 mm; with the pore water held on its lattice, steady). Shifting towards uniform concentration
keeps the order; the shift is proportional to the distance travelled (|v| dt), so still pore water
is never moved and a bed at rest is unchanged.

Where the water support is cut (the water table, a free surface) grad C points into the water and
would pull the surface apart: the shift is blended to zero there by C (FULL_WATER: Lind et al.
switch it off at free surfaces). Only pore water is shifted (the mixture's water_fraction < 1, the
seed form's pore_label < 1), never wall particles. The fields are not Taylor-corrected to the new
position (Lind et al. do): the shift per step is a fraction of |v| dt, O(h |v| dt |grad C|), and the
pore water's pressure field is smooth on that scale. Linear momentum is not changed (positions only);
mass moves with its particle.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..fields import PORE_LABEL, WATER_FRACTION
from ..kernels import cubic_spline_dwdr, cubic_spline_w
from ..materials import Phase
from ..term import Equation, Stage, Term
from .density_diffusion import pore_field
from .fixed_particles import FIXED
from .seepage import SeepageSettings

A_SHIFT = 2.0  # Lind et al. (2012): A = 2
FULL_WATER = (0.85, 0.95)  # C_a below which the shift is blended out (free surface rows: C ~ 0.5-0.8)
ENABLED = True  # False only for before/after diagnostics (docs/seepage.md)


@kernel(parallel=True)
def pore_water_shift(targets, start, index, x, v, rho, mass, label, h, norm, coeff, shift, fixed=None,
                     is3d=None):  # fmt: skip
    """shift[t] = -s coeff h |v_a| grad C_a for target a = targets[t] with label[a] < 1 (pore water)
    and not fixed; 0 otherwise. coeff = A dt; s = clip((C_a - FULL_WATER[0]) / (FULL_WATER[1] -
    FULL_WATER[0]), 0, 1)."""
    lo, hi = FULL_WATER
    for t in prange(targets.shape[0]):
        a = targets[t]
        shift[t, 0] = shift[t, 1] = 0.0
        if is3d is not None:
            shift[t, 2] = 0.0
        if label[a] >= 1.0 or (fixed is not None and fixed[a]):
            continue
        speed = v[a, 0] * v[a, 0] + v[a, 1] * v[a, 1]
        if is3d is not None:
            speed += v[a, 2] * v[a, 2]
        if speed == 0.0:
            continue
        c = g0 = g1 = g2 = 0.0
        for s in range(start[t], start[t + 1]):
            b = index[s]
            d0 = x[a, 0] - x[b, 0]
            d1 = x[a, 1] - x[b, 1]
            d2 = x[a, 2] - x[b, 2] if is3d is not None else 0.0
            r = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + 1e-300
            vol = mass[b] / rho[b]
            c += vol * cubic_spline_w(r, h, norm)
            f = vol * cubic_spline_dwdr(r, h, norm) / r  # grad_a W_ab = f d / V_b
            g0 += f * d0
            g1 += f * d1
            g2 += f * d2
        c += mass[a] / rho[a] * cubic_spline_w(0.0, h, norm)  # the particle's own share of C
        blend = min(max((c - lo) / (hi - lo), 0.0), 1.0)
        k = -blend * coeff * h * np.sqrt(speed)
        shift[t, 0] = k * g0
        shift[t, 1] = k * g1
        if is3d is not None:
            shift[t, 2] = k * g2


@kernel(parallel=True)
def apply_shift(targets, x, shift, is3d=None):
    for t in prange(targets.shape[0]):
        a = targets[t]
        x[a, 0] += shift[t, 0]
        x[a, 1] += shift[t, 1]
        if is3d is not None:
            x[a, 2] += shift[t, 2]


class PoreWaterShifting(Term):
    """The pore water's Fickian shifting after the drift (module docstring)."""

    name = "pore water shifting"
    stage = Stage.AFTER_DRIFT
    targets = Phase.WATER
    neighbours = Phase.WATER

    @classmethod
    def build(cls, scene, materials):
        if not ENABLED or SeepageSettings.of(scene, materials) is None:
            return None
        label = pore_field(scene)
        if label is None:  # no saturated block: no pore water
            return None
        walls = any(b.fixed and scene.materials[b.material].model == "water" for b in scene.blocks)
        return cls(label, walls)

    def __init__(self, label, walls):
        super().__init__()
        self.label, self.walls = label, walls
        self.fields = {label: WATER_FRACTION if label == "water_fraction" else PORE_LABEL}
        if walls:
            self.fields["fixed"] = FIXED
        self.reads = ("x", "rho", "mass")
        self.equations = (
            Equation(
                f"pore water: x += -A h |v| dt grad C, C = sum_b V_b W_ab, A = {A_SHIFT:g}",
                "Lind et al. (2012) sec. 3.2 (Fickian shifting)",
            ),
        )
        self._shift = np.zeros((0, 3))

    def run(self, ctx):
        ps, nl = ctx.particles, ctx.neighbours(self)
        if self._shift.shape[0] < nl.targets.shape[0]:
            self._shift = np.zeros((int(1.5 * nl.targets.shape[0]) + 16, 3))
        pore_water_shift(
            nl.targets, nl.start, nl.index, ps["x"], ps["v_half"], ps["rho"], ps["mass"], ps[self.label],
            ctx.h, ctx.norm, A_SHIFT * ctx.dt, self._shift, ps["fixed"] if self.walls else None, ctx.is3d,
        )  # fmt: skip
        apply_shift(nl.targets, ps["x"], self._shift, ctx.is3d)
