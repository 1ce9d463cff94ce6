"""Inflow through a section at a prescribed unit discharge (issue 11 item 1).

The model is the buffer zone of DualSPHysics' inlet/outlet zones (Tafuni et al. 2018, CMAME 342)
and SPHinXsys' emitters: behind the section lie `layers` layers of water particles moving at the
prescribed velocity u d (their kernel support is complete for the water that has just left);
each time the front layer has crossed the section it is released (it becomes ordinary water,
with exactly the state it had) and a new layer is created at the back. Only the facts carry over
from those codes; this is our own implementation.

Geometry (2D): the section is the segment origin + a s, 0 <= s <= W, a the unit vector `across`;
n is its unit normal on the downstream side, d the unit direction of the velocity. Layers are
lines parallel to the section, a distance dx apart along n, so a spacing ds = dx / (d . n) along
d; each holds m = round(W / dx) particles at a spacing W / m across. A particle stands for the
area V0 = dx W / m (its cell, ds long along d) and carries mass rho0 V0 (volume = mass / rho0
exactly). With speed u along d the volume flux is u (d . n) W = q. The front layer straddles the
section; it is released when its cell has crossed it entirely (its centre ds/2 downstream), so
the inserted volume, released cells plus the crossed fraction of the front layer's cells, is
q t at every instant, and the released volume alone lags it by less than one layer (m V0).
Buffer particles carry rho0, p = 0: the pressure at the brink of a free overfall is atmospheric
(Rouse 1936).

Without `width` the section is a free overfall's critical section, y_c = (q^2/g)^(1/3) (Chow
1959, eq. 3-9), rounded to whole spacings so q stays exact; without `speed`, u = q / ((d . n) W).

State. Everything that decides where particles are and which exist is in plain attributes that
every MPI rank advances identically (the same dt): the front position A (distance along d moved
since the set-up), the number of released layers, the released mass. Layer l, particle j sits at
origin + (j + 1/2)(W/m) a + (A - (l + 1/2) ds) d; it is released when A >= (l + 1) ds. Its id is
(inlet index + 1) 2^40 + l m + j: a reserved range per inlet, unique and global with no
communication. A new particle is appended only by the rank that owns its position; `state()` and
`restore()` give the checkpointable state.

prefill_time T > 0 starts the run as if the inlet had run for T already, each released particle
in ballistic free flight since it crossed the section (position origin-point + u tau d + g tau^2/2,
velocity u d + g tau); docs/scour_setup.md (time zero) recommends it for the overflow nappe.
"""

from __future__ import annotations

import math

import numpy as np

from ..particles import FieldSpec
from ..scene_open import inlet_width, unit
from ..term import Equation, Stage, Term

ID_STRIDE = 2**40
"""Ids of inlet k are (k + 1) ID_STRIDE + serial: far above any scene's initial particles."""

INLET_BUFFER = FieldSpec(
    0, np.int32, "inlet index of a buffer particle, -1 for free particles", constant=False, default=-1
)


class InletZone:
    """One inlet: its geometry (fixed) and its state (replicated on every rank)."""

    def __init__(self, index, spec, scene, materials):
        dx = scene.scene.spacing
        self.index = index
        self.name = spec.name
        self.material = materials.index(spec.material)
        self.rho0 = float(materials.rho0[self.material])
        self.d = unit(spec.direction)
        self.a = np.array([-self.d[1], self.d[0]]) if spec.across is None else unit(spec.across)
        n = np.array([self.a[1], -self.a[0]])
        self.n = n if n @ self.d > 0 else -n  # normal on the downstream side
        self.cos = float(self.n @ self.d)
        self.q = float(spec.discharge)
        g = float(np.linalg.norm(scene.scene.gravity))
        self.critical_depth = (self.q**2 / g) ** (1.0 / 3.0) if spec.width is None else None  # Chow (1959)
        self.width = inlet_width(spec, dx, g)
        self.m = max(1, round(self.width / dx))
        self.speed = float(spec.speed) if spec.speed is not None else self.q / (self.cos * self.width)
        self.dx = dx
        self.ds = dx / self.cos  # layer spacing along d
        self.volume = dx * self.width / self.m  # V0 per particle (area in 2D)
        self.mass = self.rho0 * self.volume
        self.layers = int(spec.layers)
        self.origin = np.asarray(spec.origin, float)
        self.id_base = (index + 1) * ID_STRIDE
        self.prefill_time = float(spec.prefill_time)
        self.gravity = np.asarray(scene.scene.gravity, float)
        self.domain = (np.asarray(scene.domain.min, float), np.asarray(scene.domain.max, float))
        # state (plain attributes: state() / restore())
        self.advance = self.speed * self.prefill_time  # A
        self.released = self.layers_crossed()  # layers released so far
        self.prefilled = self.released  # of which were placed by the prefill at t = 0
        self.released_mass = 0.0  # since t = 0 (the prefill is initial state, not inflow)
        self.elapsed = 0.0  # time integrated by this inlet since t = 0
        # mass per material of free particles that flowed back into the buffer, removed (this rank's
        # share): mostly water, but a grain thrown up into the buffer is removed too (and counted as soil)
        self.backflow_mass = np.zeros(len(materials.names))
        self.rho0_all = np.asarray(materials.rho0, float)

    # -- state -----------------------------------------------------------------------
    def state(self) -> dict:
        return {
            "advance": self.advance,
            "released": self.released,
            "prefilled": self.prefilled,
            "released_mass": self.released_mass,
            "elapsed": self.elapsed,
            "backflow_mass": self.backflow_mass.tolist(),
        }

    def restore(self, state: dict):
        self.advance = float(state["advance"])
        self.released = int(state["released"])
        self.prefilled = int(state["prefilled"])
        self.released_mass = float(state["released_mass"])
        self.elapsed = float(state["elapsed"])
        back = state.get("backflow_mass", 0.0)
        if np.ndim(back) == 0:  # an older state: water only
            self.backflow_mass = np.zeros(len(self.rho0_all))
            self.backflow_mass[self.material] = float(back)
        else:
            self.backflow_mass = np.array(back, float)

    # -- kinematics ------------------------------------------------------------------
    def layers_crossed(self) -> int:
        """Layers whose cells have crossed the section entirely: A >= (l + 1) ds."""
        return max(0, math.floor(self.advance / self.ds + 1e-12))

    def crossed_volume(self) -> float:
        """The volume that has crossed the section since t = 0 by the kinematics (q t exactly)."""
        return (self.advance - self.speed * self.prefill_time) * self.cos * self.width

    def in_buffer_zone(self, x):
        """Mask of positions the buffer will overrun: behind, or within half a spacing of, the front
        buffer layer's centre line (along d), across the section's width plus half a spacing each side."""
        r = x - self.origin
        xi = (r @ self.n) / self.cos
        s = r @ self.a - xi * (self.d @ self.a)
        half = 0.5 * self.dx
        front = self.advance - (self.released + 0.5) * self.ds
        inside = (xi < front + 0.5 * self.ds) & (xi > -(self.layers + 0.5) * self.ds)
        return inside & (s > -half) & (s < self.width + half)

    def lateral(self):
        return (np.arange(self.m) + 0.5) * (self.width / self.m)

    def layer_positions(self, layer):
        """Positions (m, 2) of the particles of buffer layer `layer` at the current A."""
        xi = self.advance - (layer + 0.5) * self.ds
        return self.origin + self.lateral()[:, None] * self.a + xi * self.d

    def serials_to_layer_slot(self, ids):
        serial = ids - self.id_base
        return serial // self.m, serial % self.m

    def new_layer(self, layer):
        """Fields of the buffer particles of `layer` (all of them; the caller filters by owner)."""
        x = self.layer_positions(layer)
        v = np.tile(self.speed * self.d, (self.m, 1))
        ids = self.id_base + layer * self.m + np.arange(self.m, dtype=np.int64)
        return x, v, ids

    def prefill(self):
        """Positions, velocities, ids of the layers released before t = 0 (ballistic flight)."""
        out_x, out_v, out_id = [], [], []
        lo, hi = self.domain
        for layer in range(self.prefilled):
            tau = (self.advance - (layer + 0.5) * self.ds) / self.speed  # time since it crossed
            x0 = self.origin + self.lateral()[:, None] * self.a + tau * self.speed * self.d
            x = x0 + 0.5 * self.gravity * tau * tau
            v = np.tile(self.speed * self.d + self.gravity * tau, (self.m, 1))
            keep = np.all((x > lo) & (x < hi), axis=1)
            out_x.append(x[keep])
            out_v.append(v[keep])
            out_id.append((self.id_base + layer * self.m + np.arange(self.m, dtype=np.int64))[keep])
        if not out_x:
            return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64)
        return np.concatenate(out_x), np.concatenate(out_v), np.concatenate(out_id)


class Inlets(Term):
    """Every inlet of the scene: buffer kinematics, release of layers, creation of new ones."""

    name = "inlets"
    stage = Stage.AFTER_DRIFT
    changes_particles = True

    @classmethod
    def build(cls, scene, materials):
        return cls(scene, materials) if scene.inlets else None

    def __init__(self, scene, materials):
        super().__init__()
        self.zones = [InletZone(k, spec, scene, materials) for k, spec in enumerate(scene.inlets)]
        self.fields = {"inlet_buffer": INLET_BUFFER}
        self.writes = ("x", "v", "v_half", "rho", "acc", "drho")
        self.equations = (
            Equation(
                "buffer layers at u d; the front layer released each time it crosses the section",
                "DualSPHysics inlet zones (Tafuni et al. 2018); SPHinXsys emitters",
            ),
            Equation("critical depth y_c = (q^2/g)^(1/3), u = q / y_c when not given", "Chow (1959) eq. 3-9"),
        )

    def explain(self):
        lines = []
        for z in self.zones:
            lines.append(
                f"inlet '{z.name}': q = {z.q:g} m^2/s, width {z.width:.4g} m ({z.m} particles"
                + (f", critical depth {z.critical_depth:.4g} m" if z.critical_depth is not None else "")
                + f"), u = {z.speed:.4g} m/s along {z.d.round(4).tolist()}, {z.layers} buffer layers, "
                f"a layer every {z.ds / z.speed:.4g} s, prefill {z.prefill_time:g} s"
            )
        return lines

    # -- state -------------------------------------------------------------------------
    def state(self):
        return [z.state() for z in self.zones]

    def restore(self, state):
        for z, s in zip(self.zones, state):
            z.restore(s)

    def regroup_state(self, states, size):
        """A restart on another rank count: the inlet's progress is replicated (rank 0's); the
        back-flow each rank removed is a per-rank share, summed onto rank 0."""
        first, rest = [], []
        for k in range(len(self.zones)):
            back = np.sum([np.atleast_1d(np.asarray(s[k]["backflow_mass"], float)) for s in states], axis=0)
            first.append(dict(states[0][k], backflow_mass=back.tolist()))
            rest.append(dict(states[0][k], backflow_mass=np.zeros_like(back).tolist()))
        return [first] + [rest] * (size - 1)

    # -- set-up: the initial buffer (and prefill) on the replicated particle set ------------
    def start(self, ctx):
        ps = ctx.particles
        for z in self.zones:
            x, v, ids = z.prefill()
            if len(x):
                self._append(ps, z, x, v, ids, buffer=False)
            for layer in range(z.released, z.released + z.layers):
                x, v, ids = z.new_layer(layer)
                self._append(ps, z, x, v, ids, buffer=True)

    def _append(self, ps, z, x, v, ids, buffer):
        n = len(x)
        fields = dict(
            x=x,
            v=v,
            v_half=v,
            rho=np.full(n, z.rho0),
            mass=np.full(n, z.mass),
            material=np.full(n, z.material, dtype=np.int32),
            id=ids,
            inlet_buffer=np.full(n, z.index if buffer else -1, dtype=np.int32),
        )
        if "rho_half" in ps:
            fields["rho_half"] = fields["rho"]
        ps.append_owned(**fields)

    # -- each step, after the drift ---------------------------------------------------------
    def run(self, ctx):
        ps = ctx.particles
        added = False
        for z in self.zones:
            z.advance += z.speed * ctx.dt
            z.elapsed += ctx.dt
            added |= self._remove_backflow(ps, z)
            self._place_buffer(ps, z)
            crossed = z.layers_crossed()
            while z.released < crossed:
                self._release(ps, z, z.released)
                z.released += 1
                z.released_mass += z.m * z.mass
                x, v, ids = z.new_layer(z.released + z.layers - 1)
                mine = ctx.owned_here(x)
                if mine.any():
                    self._append(ps, z, x[mine], v[mine], ids[mine], buffer=True)
                added = True
        if added:
            ctx.request_rebuild()

    def _remove_backflow(self, ps, z):
        """Free particles that flowed back into the buffer zone, or that the front layer is about to
        overrun (within half a spacing of it), are removed and counted, as DualSPHysics does with
        fluid entering an inlet zone: the buffer moves kinematically, a velocity inlet ignores the
        pressure ahead of it, and a free particle in its way would be crushed."""
        n = ps.n_owned
        back = (ps["inlet_buffer"][:n] < 0) & z.in_buffer_zone(ps["x"][:n])
        if not back.any():
            return False
        z.backflow_mass += np.bincount(
            ps["material"][:n][back], weights=ps["mass"][:n][back], minlength=len(z.backflow_mass)
        )
        ps.remove_owned(~back)
        return True

    def _place_buffer(self, ps, z):
        """Buffer particles at their exact kinematic state (the kick and drift moved them with the
        rates of the water around them, and XSPH)."""
        n = ps.n_owned
        rows = np.flatnonzero(ps["inlet_buffer"][:n] == z.index)
        if not len(rows):
            return
        layer, slot = z.serials_to_layer_slot(ps["id"][rows])
        xi = z.advance - (layer + 0.5) * z.ds
        ps["x"][rows] = z.origin + ((slot + 0.5) * (z.width / z.m))[:, None] * z.a + xi[:, None] * z.d
        ps["v"][rows] = z.speed * z.d
        ps["v_half"][rows] = z.speed * z.d
        ps["acc"][rows] = 0.0
        ps["rho"][rows] = z.rho0
        ps["drho"][rows] = 0.0
        if "rho_half" in ps:
            ps["rho_half"][rows] = z.rho0

    def _release(self, ps, z, layer):
        n = ps.n_owned
        rows = np.flatnonzero(ps["inlet_buffer"][:n] == z.index)
        if len(rows):
            lay, _ = z.serials_to_layer_slot(ps["id"][rows])
            ps["inlet_buffer"][rows[lay == layer]] = -1

    def summary(self):
        """Replicated figures for run.json (identical on every rank)."""
        out = {}
        for z in self.zones:
            out[z.name] = {
                "discharge_m2_s": z.q,
                "width_m": z.width,
                "particles_across": z.m,
                "speed_m_s": z.speed,
                "released_layers": z.released - z.prefilled,
                "released_volume": z.released_mass / z.rho0,
                "crossed_volume_q_t": z.crossed_volume(),
                "prefill_volume": z.prefilled * z.m * z.volume,
                "backflow_volume_this_rank": (z.backflow_mass / z.rho0_all).tolist(),
                "state": z.state(),
            }
        return out
