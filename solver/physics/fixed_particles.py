"""Wall particles of fixed blocks (`fixed = true`): they take part in their neighbours' sums
but are never moved (their rates are dropped, so v stays 0)."""

from __future__ import annotations

import numpy as np

from ..particles import FieldSpec, Mirror
from ..term import Equation, Stage, Term

FIXED = FieldSpec(
    0, np.bool_, "wall particles of fixed blocks: never moved", Mirror.SCALAR, constant=True
)  # mirrored: the seepage coupling reads it from neighbours (a wall's image is a wall)


class FixedParticles(Term):
    name = "fixed particles"
    stage = Stage.AFTER_RATES

    @classmethod
    def build(cls, scene, materials):
        return cls() if any(b.fixed for b in scene.blocks) else None

    def __init__(self):
        super().__init__()
        self.fields = {"fixed": FIXED}
        self.writes = ("acc",)
        self.equations = (
            Equation("acceleration of fixed wall particles set to zero", "seed sec. 2.5 (walls)"),
        )

    def run(self, ctx):
        ps = ctx.particles
        n = ps.n_owned
        ps["acc"][:n][ps["fixed"][:n]] = 0.0
