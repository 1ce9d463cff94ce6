"""Outflow through outlet zones (issue 11 item 2): a buffer zone by default, or plain deletion.

An outlet is a box (`[[outlets]]`, min and max) and a `kind` (solver/scene_open.py; the default in
solver/defaults.toml, `[outlet_defaults]`). Only particles of the outlet's materials (default all)
take part; an inlet's buffer particles never do.

kind = "buffer" (the default): the outflow buffer of open-boundary SPH (Federico et al. 2012,
Eur. J. Mech. B/Fluids 34:35-46: an outflow region at least one kernel support deep where
particles keep the velocity they had on entering it and move with it; Tafuni et al. 2018, CMAME
342:604-624: the same buffer with the state extrapolated from the fluid instead of frozen. We
could not read either paper here: the concept is as commonly summarised, the details below are
ours).
A particle whose centre enters the zone becomes a buffer particle of it (field `outlet_buffer`, the
zone's index; -1 for every other particle): from then on it receives no rates (velocity, density,
soil stress and every other integrated field keep the values they had on entry, so its pressure
too; no XSPH correction), moves ballistically at its frozen velocity (gravity is a rate: it is
dropped too), and still acts on its neighbours. So the fluid upstream of the zone sees a full
kernel of particles in the state of the oncoming stream, instead of the truncated kernel of a
deletion zone, which acts as a free surface at its upstream face and draws the flow down over the
last kernel support (the scour study's end-wall trough, docs/scour_study.md). The frozen state is
Federico et al.'s zero-order choice; Tafuni et al.'s extrapolation, which lets the buffer follow
a changing upstream state, is not implemented. A buffer particle is deleted, and its mass
counted, when its centre leaves the zone through any face (this includes a face on an open side
of the domain, and one lying on a body's edge: the end wall's top in the scour scenes). That is
done in Stage.LEAVING, right after the drift and before the state check (which would report a
particle outside the domain) and the bodies' leak guard (which would count a particle inside the
end wall). A face on a wall side of the domain is not an exit: the drift reflects a buffer
particle there like any other. What we take from the papers is the concept (an outflow zone one
support deep, frozen velocity, removal on leaving it). One code does the same, checked in its
source: PySPH's SimpleOutlet (pysph/sph/simple_inlet_outlet.py: a particle entering the outlet
region moves to an outlet array and is removed when it leaves the region), whose particles are
advanced by InletOutletStep (pysph/sph/integrator_step.py: x += u dt only, so u and rho stay as
they were). For DualSPHysics' outflow zones and SPHinXsys' disposers we
could not confirm from their documentation whether the buffer freezes or extrapolates the state;
this is our own implementation, not a copy of any of them.

kind = "delete": every particle whose centre is in the zone after a drift is removed at once (the
former outlet; a free overfall at the zone's upstream face).

The freezing is by rates: OutletBuffers zeroes every integrated rate and the drift correction of
buffer rows after the rates stages (as fixed wall particles drop their acceleration,
fixed_particles.py), and Outlets zeroes them on the step a particle enters, so the predictor gives
it its half-step values. The midpoint-density continuity (midpoint_continuity.py, which advances
rho after the drift) leaves buffer rows out through `frozen_rows`.

The removed mass is counted per outlet and material; its volume is mass / rho0 of the material
(the volume balance, solver/output/balance.py: buffer particles are still stored water or soil
until they are removed). The counters are this process's share: the run's report sums them over
ranks. The buffer flag is a particle field, so it migrates between MPI ranks and goes into
checkpoints with every other field (the inlet's `inlet_buffer` does the same).
"""

from __future__ import annotations

import numpy as np

from ..config import kernel
from ..particles import FieldSpec
from ..scene_open import OutletKind
from ..term import Equation, Stage, Term

OUTLET_BUFFER = FieldSpec(
    0, np.int32, "outlet index of a buffer particle, -1 for free particles", constant=False, default=-1
)  # as inlet.INLET_BUFFER: an owned-row flag, migrated and checkpointed, read by no neighbour


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


@kernel
def left_boxes(x, n, lo, hi, zone, out):
    """out[i] = zone[i] if particle i belongs to box zone[i] >= 0 and its centre is outside that box
    (closed: a centre on a face is inside, as in in_boxes), else -1. Returns how many left."""
    dim = x.shape[1]
    gone = 0
    for i in range(n):
        out[i] = -1
        k = zone[i]
        if k < 0:
            continue
        for a in range(dim):
            if x[i, a] < lo[k, a] or x[i, a] > hi[k, a]:
                out[i] = k
        if out[i] >= 0:
            gone += 1
    return gone


def frozen_rows(ps, n):
    """Owned rows of outlet buffer particles (none when the scene has no buffered outlet)."""
    if "outlet_buffer" not in ps:
        return np.zeros(0, dtype=np.int64)
    return np.flatnonzero(ps["outlet_buffer"][:n] >= 0)


def freeze(ps, rows, integrated, correction):
    """Drop the rates of `rows`: every integrated field keeps its value, x moves at v_half."""
    if not len(rows):
        return
    for f in integrated:
        ps[f.rate][rows] = 0.0
    if correction is not None:
        ps[correction][rows] = 0.0


class Outlets(Term):
    """Every outlet zone of the scene: buffer entry, removal on leaving (or on entry: delete)."""

    name = "outlets"
    stage = Stage.LEAVING
    changes_particles = True

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if scene.outlets else None

    def __init__(self, scene, materials):
        super().__init__()
        self.names = [o.name for o in scene.outlets]
        self.kinds = [OutletKind(o.kind) for o in scene.outlets]
        self.buffered = np.array([k is OutletKind.BUFFER for k in self.kinds], dtype=np.bool_)
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
        equations = []
        if self.buffered.any():
            self.fields = {"outlet_buffer": OUTLET_BUFFER}
            self.writes = ("outlet_buffer",)
            equations.append(
                Equation(
                    "buffer zone: a particle entering keeps its velocity and density (no rates), moves "
                    "ballistically, acts on its neighbours; removed and counted when it leaves the zone",
                    "Federico et al. (2012); Tafuni et al. (2018); PySPH SimpleOutlet",
                )
            )
        if not self.buffered.all():
            equations.append(
                Equation(
                    "particles entering a deletion zone are removed; mass counted",
                    "DualSPHysics outlet zones",
                )
            )
        self.equations = tuple(equations)

    def explain(self):
        return [
            f"outlet '{n}' ({k.value}): {lo.tolist()} to {hi.tolist()}"
            for n, k, lo, hi in zip(self.names, self.kinds, self.lo, self.hi)
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
        entered = in_boxes(ps["x"], n, self.lo, self.hi, ps["material"], self.wanted, zone)
        if "inlet_buffer" in ps:
            zone[ps["inlet_buffer"][:n] >= 0] = -1
        gone = np.full(n, -1, dtype=np.int64)
        if "outlet_buffer" in ps:
            flag = ps["outlet_buffer"][:n]
            left_boxes(ps["x"], n, self.lo, self.hi, flag, gone)  # gone[i]: the zone buffer particle i left
            zone[flag >= 0] = -1  # a buffer particle belongs to its own zone, not to one it drifts into
            if entered:
                new = np.flatnonzero(zone >= 0)
                new = new[self.buffered[zone[new]]]
                if len(new):
                    flag[new] = zone[new]
                    zone[new] = -1
                    freeze(ps, new, ctx.integrated, ctx.position_correction)
        out = np.flatnonzero(gone >= 0)
        if entered:  # deletion zones: removed on entry
            out = np.union1d(out, np.flatnonzero(zone >= 0))
            gone[zone >= 0] = zone[zone >= 0]
        if not len(out):
            return
        np.add.at(self.removed_mass, (gone[out], ps["material"][out]), ps["mass"][out])
        np.add.at(self.removed_count, gone[out], 1)
        keep = np.ones(n, dtype=bool)
        keep[out] = False
        ps.remove_owned(keep)
        ctx.request_rebuild()

    def removed_volume(self):
        """This rank's removed volume per outlet and material (mass / rho0), (outlets, materials)."""
        return self.removed_mass / self.rho0[None, :]


class OutletBuffers(Term):
    """After the rates: outlet buffer particles receive none (their state stays as on entry)."""

    name = "outlet buffers"
    stage = Stage.AFTER_RATES

    @classmethod
    def build(cls, scene, materials):
        buffered = any(OutletKind(o.kind) is OutletKind.BUFFER for o in scene.outlets)
        return cls() if buffered else None

    def __init__(self):
        super().__init__()
        self.fields = {"outlet_buffer": OUTLET_BUFFER}
        self.writes = ("acc",)  # and every other integrated rate, and the XSPH correction (owned rows)
        self.equations = (
            Equation(
                "every integrated rate and the XSPH correction of outlet buffer particles set to zero",
                "Federico et al. (2012): frozen velocity in the outflow buffer",
            ),
        )

    def run(self, ctx):
        ps = ctx.particles
        freeze(ps, frozen_rows(ps, ps.n_owned), ctx.integrated, ctx.position_correction)
