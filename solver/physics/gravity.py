"""Gravity, the body force g of the momentum equations (seed eqs. 7, 20, 21)."""

from __future__ import annotations

import numpy as np
from numba import prange

from ..config import kernel
from ..term import Equation, Stage, Term


@kernel(parallel=True)
def add_gravity(n, g, acc):
    """acc_i += g for the first n rows: a threaded pass (as NumPy's broadcast add it was a serial
    1.7 % of the soil step, which caps the two-thread speed-up by Amdahl's law)."""
    for i in prange(n):
        for a in range(acc.shape[1]):
            acc[i, a] += g[a]


class Gravity(Term):
    """Adds g to every owned particle's acceleration; absent when the scene's g = 0."""

    name = "gravity"
    stage = Stage.RATES

    @classmethod
    def build(cls, scene, materials):
        g = np.asarray(scene.scene.gravity, float)
        return cls(g) if np.any(g != 0.0) else None

    def __init__(self, g):
        super().__init__()
        self.adds_to = ("acc",)
        self.equations = (Equation(f"body force g = {g.tolist()} m/s^2", "seed eqs. (7), (20), (21)"),)

    def run(self, ctx):
        # the scene's g, unless a driver changes it (a ramp)
        add_gravity(ctx.particles.n_owned, ctx.gravity, ctx.particles["acc"])
