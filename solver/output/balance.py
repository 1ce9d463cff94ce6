"""The volume balance of a run with inlets and outlets, and the rigid bodies' leak counter
(issue 11 items 2, 3): figures for run.json and the HDF5 metadata.

Volumes are mass / rho0 of each particle's material (a particle's mass never changes, so the
balance is exact bookkeeping: a particle lost, duplicated or created outside an inlet shows up).
Per material:

    inflow (released by inlets since t = 0) - outflow (removed by outlets, and back-flow removed
    from inlet buffers) - (stored(t) - stored(0)) = 0

stored counts every particle of the material in the domain except inlet buffer particles (they
belong to the inlet until released); outlet buffer particles are stored until the outlet removes
them (outlet.py), so the outflow is counted once, when they leave the buffer zone. The run reports
the residual and whether it is within one particle volume dx^dim. Pore water is water: its volume
is its mass / rho0 = n V (the pores).
"""

from __future__ import annotations

import numpy as np

from ..physics.bodies import BodyGuard
from ..physics.inlet import Inlets
from ..physics.outlet import Outlets


def _stored(sim, comm):
    """Volume per material of the owned particles outside inlet buffers, summed over ranks."""
    ps, mats = sim.particles, sim.plan.materials
    n = ps.n_owned
    mask = np.ones(n, dtype=bool) if "inlet_buffer" not in ps else ps["inlet_buffer"][:n] < 0
    vol = np.bincount(ps["material"][:n][mask], weights=ps["mass"][:n][mask], minlength=len(mats.names))
    return np.array([comm.sum(float(v)) for v in vol]) / mats.rho0


class VolumeLedger:
    """Started before the first step (stored(0)); `report()` after the run."""

    def __init__(self, sim, comm, stored0=None):
        """stored0: the stored volumes at t = 0 of a run resumed from a checkpoint."""
        self.active = sim.plan.term(Inlets) is not None or sim.plan.term(Outlets) is not None
        self.bodies = sim.plan.term(BodyGuard)
        if not self.active:
            self.stored0 = None
        else:
            self.stored0 = np.asarray(stored0, float) if stored0 is not None else _stored(sim, comm)

    def report(self, sim, comm) -> dict:
        out = {}
        if self.bodies is not None:
            out["body_leaks"] = int(comm.sum(int(self.bodies.leaks)))
            out["body_deepest_leak_m"] = float(comm.max(float(self.bodies.deepest)))
        if not self.active:
            return out
        mats = sim.plan.materials
        inlets, outlets = sim.plan.term(Inlets), sim.plan.term(Outlets)
        inflow = np.zeros(len(mats.names))
        if inlets is not None:
            for z in inlets.zones:
                inflow[z.material] += z.released_mass / z.rho0  # replicated: not summed over ranks
        local = np.zeros(len(mats.names))
        if outlets is not None:
            local += outlets.removed_volume().sum(axis=0)
        if inlets is not None:
            for z in inlets.zones:
                local += z.backflow_mass / mats.rho0  # what flowed back into a buffer, per material
        outflow = np.array([comm.sum(float(v)) for v in local])
        stored = _stored(sim, comm)
        particle_volume = sim.scene.scene.spacing**sim.scene.dim
        balance = {}
        for k, name in enumerate(mats.names):
            residual = inflow[k] - outflow[k] - (stored[k] - self.stored0[k])
            balance[name] = {
                "inflow": float(inflow[k]),
                "outflow": float(outflow[k]),
                "stored_start": float(self.stored0[k]),
                "stored_end": float(stored[k]),
                "residual": float(residual),
                "within_one_particle": bool(abs(residual) <= particle_volume),
            }
        out["volume_balance"] = {
            "units": "m^3 (m^2 per unit depth in 2D)",
            "particle_volume": particle_volume,
            "materials": balance,
        }
        if inlets is not None:
            out["inlets"] = inlets.summary()
        return out
