"""Outflow: particles that enter an outlet zone are removed and counted (issue 11 item 2).

An outlet is a box (`[[outlets]]`, min and max); after each drift every owned particle whose
centre lies in it (of the outlet's materials, default all; never an inlet's buffer) is deleted,
as DualSPHysics' outlet zones and SPHinXsys' disposers do. The removed mass is counted per
material; its volume is mass / rho0 of the material (what the volume balance reports, docs/
open_boundaries.md). The counters are this process's share: the run's report sums them over ranks.
"""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..term import Equation, Stage, Term


@kernel
def in_boxes(x, n, lo, hi, material, wanted, out):
    """out[i] = index of the first box (lo[k], hi[k]) holding x[i] among materials wanted[k, m], else -1."""
    dim = x.shape[1]
    hits = 0
    for i in range(n):
        out[i] = -1
        for k in range(lo.shape[0]):
            if not wanted[k, material[i]]:
                continue
            inside = True
            for a in range(dim):
                if x[i, a] < lo[k, a] or x[i, a] > hi[k, a]:
                    inside = False
            if inside:
                out[i] = k
                hits += 1
                break
    return hits


class Outlets(Term):
    """Every outlet zone of the scene."""

    name = "outlets"
    stage = Stage.AFTER_DRIFT
    changes_particles = True

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if scene.outlets else None

    def __init__(self, scene, materials):
        super().__init__()
        self.names = [o.name for o in scene.outlets]
        self.lo = np.array([o.min for o in scene.outlets], float)
        self.hi = np.array([o.max for o in scene.outlets], float)
        n_mat = len(materials.names)
        self.wanted = np.zeros((len(self.names), n_mat), dtype=np.bool_)
        for k, o in enumerate(scene.outlets):
            for m in o.materials if o.materials is not None else materials.names:
                self.wanted[k, materials.index(m)] = True
        self.rho0 = np.asarray(materials.rho0, float)
        self.material_names = materials.names
        self.removed_mass = np.zeros((len(self.names), n_mat))  # this rank's share
        self.removed_count = np.zeros(len(self.names), dtype=np.int64)
        self.equations = (
            Equation(
                "particles entering an outlet zone are removed; mass counted", "DualSPHysics outlet zones"
            ),
        )

    def explain(self):
        return [
            f"outlet '{n}': {lo.tolist()} to {hi.tolist()}" for n, lo, hi in zip(self.names, self.lo, self.hi)
        ]

    def state(self):
        return {"removed_mass": self.removed_mass.tolist(), "removed_count": self.removed_count.tolist()}

    def restore(self, state):
        self.removed_mass = np.array(state["removed_mass"], float)
        self.removed_count = np.array(state["removed_count"], dtype=np.int64)

    def regroup_state(self, states, size):
        """Per-rank shares (a restart on another rank count): their sum on rank 0, zero elsewhere."""
        mass = np.sum([s["removed_mass"] for s in states], axis=0)
        count = np.sum([s["removed_count"] for s in states], axis=0)
        zero = {"removed_mass": np.zeros_like(mass).tolist(), "removed_count": np.zeros_like(count).tolist()}
        return [{"removed_mass": mass.tolist(), "removed_count": count.tolist()}] + [zero] * (size - 1)

    def run(self, ctx):
        ps = ctx.particles
        n = ps.n_owned
        zone = np.empty(n, dtype=np.int64)
        if not in_boxes(ps["x"], n, self.lo, self.hi, ps["material"], self.wanted, zone):
            return
        if "inlet_buffer" in ps:
            zone[ps["inlet_buffer"][:n] >= 0] = -1
        gone = np.flatnonzero(zone >= 0)
        if not len(gone):
            return
        np.add.at(self.removed_mass, (zone[gone], ps["material"][gone]), ps["mass"][gone])
        np.add.at(self.removed_count, zone[gone], 1)
        keep = np.ones(n, dtype=bool)
        keep[gone] = False
        ps.remove_owned(keep)
        ctx.request_rebuild()

    def removed_volume(self):
        """This rank's removed volume per outlet and material (mass / rho0), (outlets, materials)."""
        return self.removed_mass / self.rho0[None, :]
