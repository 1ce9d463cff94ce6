"""Gravity, the body force g of the momentum equations (seed eqs. 7, 20, 21)."""

from __future__ import annotations

import numpy as np

from ..term import Equation, Stage, Term


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
        n = ctx.particles.n_owned
        ctx.particles["acc"][:n] += ctx.gravity  # the scene's g, unless a driver changes it (a ramp)
