"""The step loop: predict, run the plan's terms stage by stage, time step, kick, drift.

It knows no material and no term: it runs what the plan lists, in the plan's order, and keeps
ghosts (through the communicator) and wall images current for the fields each term declares
it reads. It knows nothing of MPI either: the communicator does.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import BlowUpError
from .initial_state import create_particles
from .integrate import STATE_OK, as_rows, lf_drift, lf_kick, lf_predict, max_norm2, state_status
from .kernels import cubic_spline_normalisation
from .neighbors import CellGrid, CellList, verlet_radius
from .parallel.communicator import SerialCommunicator
from .particles import Mirror
from .physics.wall_images import WallImages, wall_planes
from .plan import RATE_STAGES, Plan, build_plan
from .scene import Scene
from .term import Stage, TermContext
from .timestep import TimeStepper


class Simulation:
    def __init__(self, scene: Scene, comm=None, plan: Plan | None = None, particles=None, resume=None):
        """`resume`: continue from a checkpoint (solver/output/checkpoint.py `Resume`; `particles`
        then holds this rank's particles from it): no set-up, no settling, see `_resume`."""
        self.scene = scene
        self.comm = comm or SerialCommunicator()
        self.plan = plan or build_plan(scene)
        self.particles = particles if particles is not None else create_particles(scene, self.plan)
        self.h = scene.h
        self.norm = cubic_spline_normalisation(scene.dim, self.h)
        self.skin = scene.numerics.neighbour_skin * self.h
        self.radius = verlet_radius(scene)
        self.lo = np.asarray(scene.domain.min, float)
        self.hi = np.asarray(scene.domain.max, float)
        self.walls = wall_planes(scene)  # (has_lo, lo, has_hi, hi): the drift's reflection safeguard
        self.cells = CellList(CellGrid.covering(self.lo, self.hi, self.radius, pad=self.radius))
        self.stepper = TimeStepper(list(self.plan.constraints), self.h, scene.numerics.cfl.force)
        self.ctx = TermContext(
            particles=self.particles,
            h=self.h,
            norm=self.norm,
            is3d=True if scene.dim == 3 else None,
            gravity=np.asarray(scene.scene.gravity, float),
            images=self.plan.term(WallImages),
            integrated=self.plan.integrated,
            position_correction=self.plan.position_correction,
        )
        self.ctx.owns = self.comm.owns
        self._phase_of_material = self.plan.materials.phase
        self.t = 0.0
        self.step_count = 0
        self.dt_prev = 0.0
        self.dt_first = None
        self.dt_limit = ""
        self.rebuilds = 0
        self._rho_state = "rho_half" if "rho_half" in self.particles else "rho"  # density checked for NaN
        self.wall_reflections = 0  # specular reflections at walls (diagnostic, see lf_drift)
        self.deepest_penetration = 0.0
        self.settling = None
        self._count_changes = any(t.changes_particles for t in self.plan.terms)
        if resume is not None:
            self.comm.setup(scene)
            self._resume(resume)
            return
        if particles is None:
            for term in self.plan.terms:
                term.start(self.ctx)  # initial particles of terms (inlet buffers), on the replicated set
        self._start_half_steps()
        self.comm.setup(scene)  # MPI: domain box and [parallel] settings (no-op serial)
        self.rebuild()
        if scene.numerics.settling_time > 0:
            self.settle(scene.numerics.settling_time)

    def settle(self, duration):
        """Settling phase (numerics.settling_time), the alternative to a geostatic start: step
        under gravity for `duration` s with kinetic damping (Cundall 1971; the dynamic-relaxation
        form of Barnes 1999): whenever the total kinetic energy falls after a step, the peak of
        an oscillation has passed and every velocity is set to zero, so the elastic energy of
        the initial load drains away mode by mode while plastic flow (if the state is not
        admissible) still happens. Then the clock restarts at t = 0 (release); the step count and
        diagnostics keep counting. Records {"steps", "resets", "ke_last"} in self.settling."""
        ps = self.particles
        ke_prev, resets, steps = 0.0, 0, 0
        while self.t < duration:
            self.step(duration - self.t)
            steps += 1
            n = ps.n_owned
            ke = self.comm.sum(0.5 * float(np.sum(ps["mass"][:n] * np.sum(ps["v_half"][:n] ** 2, axis=1))))
            if ke < ke_prev:
                ps["v_half"][:n] = 0.0
                if "v" in ps:
                    ps["v"][:n] = 0.0
                resets += 1
                ke = 0.0
            ke_prev = ke
        self.settling = {"steps": steps, "resets": resets, "ke_last": ke_prev, "duration": float(self.t)}
        self.t = 0.0

    def _start_half_steps(self):
        """q_{-1/2} = q_0 for every integrated field, so the first kick is the half-kick."""
        ps = self.particles
        n = ps.n_owned
        for f in self.plan.integrated:
            ps[f.half][:n] = ps[f.value][:n]

    @property
    def gravity(self):
        """The body force g in use (the scene's; a driver may ramp it: `sim.gravity = ...`)."""
        return self.ctx.gravity

    @gravity.setter
    def gravity(self, value):
        self.ctx.gravity[:] = value

    @property
    def lists(self):
        """Neighbour lists by (target phase, neighbour phase)."""
        return self.ctx.lists

    # -- neighbour structures -------------------------------------------------------
    def rebuild(self):
        """Migrate, sort into cell order, rebuild halo, images and Verlet lists."""
        ps, plan, ctx = self.particles, self.plan, self.ctx
        self.comm.migrate(ps)
        ps.drop_halo()
        self.cells.bin(ps["x"], ps.n_owned)
        ps.permute_owned(self.cells.owned_cell_order(ps.n_owned))
        self.comm.build_halo(ps, self.radius, plan.halo_fields)
        for term in plan.terms:
            term.on_rebuild(ctx)  # wall images are appended here
        if ctx.images is not None:
            ctx.images.refresh(ps, plan.rebuild_image_fields, plan.fields)
        n = ps.n_total
        self.cells.bin(ps["x"], n)
        phase = self._phase_of_material[ps["material"][:n]].astype(np.int32)
        owned_phase = phase[: ps.n_owned]
        ctx.rows = {p: np.flatnonzero(owned_phase == p).astype(np.int64) for p in plan.phases}
        ctx.lists = {
            (target, other): self.cells.neighbour_list(ps["x"], ctx.rows[target], self.radius, phase, other)
            for target, other in plan.pairs
        }
        if ctx.images is not None:  # no pair sees a body image from behind its mirror line
            ctx.lists = ctx.images.prune(ps, ctx.lists)
        ps["x_ref"][: ps.n_owned] = ps["x"][: ps.n_owned]
        self.rebuilds += 1

    def refresh(self, names):
        """Ghosts (halo exchange), then images, of the named fields."""
        if not names:
            return
        self.comm.refresh_halo(self.particles, names)
        if self.ctx.images is not None:
            self.ctx.images.refresh(self.particles, names, self.plan.fields)

    def _run(self, stage):
        for item in self.plan.schedule.get(stage, ()):
            self.refresh(item.refresh)
            item.term.run(self.ctx)

    # -- rates ------------------------------------------------------------------------
    def compute_rates(self):
        """Every rate at step n: zero the accumulated rates, then the rates stages of the plan."""
        ps = self.particles
        n = ps.n_owned
        for name in self.plan.accumulated:
            ps[name][:n] = 0.0
        for stage in RATE_STAGES:
            self._run(stage)

    # -- one step ---------------------------------------------------------------------
    def predict(self):
        """Values at the current time n from the half-step values (no-op before step 1)."""
        if self.step_count == 0:
            return
        ps = self.particles
        n = ps.n_owned
        for f in self.plan.integrated:
            lf_predict(
                n, 0.5 * self.dt_prev, as_rows(ps[f.value], n), as_rows(ps[f.half], n), as_rows(ps[f.rate], n)
            )

    def step(self, dt_max=math.inf):
        ps = self.particles
        self.predict()
        self.compute_rates()
        n = ps.n_owned
        max_acc = math.sqrt(self.comm.max(max_norm2(n, ps["acc"])))
        dynamic = [(t.dt_limit.name, self.comm.min(t.dt_now(self.ctx))) for t in self.plan.dynamic_limits]
        dt, self.dt_limit = self.stepper(max_acc, dynamic)
        dt = self.comm.min(dt)
        if self.dt_first is None:
            self.dt_first = dt
        elif dt < self.scene.numerics.cfl.collapse_fraction * self.dt_first:
            self._blow_up(
                f"time step collapsed to {dt:.3g} s ({self.dt_limit} constraint; "
                f"first step {self.dt_first:.3g} s)",
                self._worst_acceleration(),
            )
        dt = min(dt, dt_max)
        self.ctx.dt = dt
        weight = 0.5 * (self.dt_prev + dt)  # dt_prev = 0 on the first step: the half-kick
        for f in self.plan.integrated:
            lf_kick(n, weight, as_rows(ps[f.half], n), as_rows(ps[f.rate], n))
        self._run(Stage.AFTER_KICK)
        correction = self.plan.position_correction
        has_lo, lo, has_hi, hi = self.walls
        moved2, reflected, depth = lf_drift(
            n,
            dt,
            ps["x"],
            ps["v_half"],
            ps["x_ref"],
            has_lo,
            lo,
            has_hi,
            hi,
            ps[correction] if correction else None,
        )
        self.wall_reflections += reflected
        self.deepest_penetration = max(self.deepest_penetration, depth)
        self.t += dt
        self.step_count += 1
        self.dt_prev = self.ctx.dt_prev = dt
        # outlets remove what left through them before anything judges the new positions (a particle
        # leaving the domain through an open side inside an outlet zone, or crossing into a body there)
        self._run(Stage.LEAVING)
        n = ps.n_owned
        status = self.comm.max(state_status(n, ps["x"], ps["v_half"], ps[self._rho_state], self.lo, self.hi))
        if status != STATE_OK:
            self._report_bad_state(status)
        if self.comm.max(depth) > self.h:
            self._blow_up(
                f"a particle crossed a wall by {depth:.3g} m in one step (more than h = {self.h:.3g} m)",
                self._worst_acceleration(),
            )
        rebalance = self.comm.rebalance_due(self.step_count, n)  # MPI: new cuts when the load drifted
        # particles removed at LEAVING: the halo is gone and the lists are stale (one more collective
        # per step, only in scenes with outlets)
        removed = Stage.LEAVING in self.plan.schedule and self._rebuild_requested()
        if self.comm.max(moved2) > (0.5 * self.skin) ** 2 or rebalance or removed:
            self.rebuild()
        self._run(Stage.AFTER_DRIFT)
        self._rebuild_if_requested()
        return dt

    def _rebuild_requested(self):
        """Did a term on any rank add or remove particles since the last call? (Collective; clears
        the request.)"""
        requested, self.ctx.rebuild_requested = self.ctx.rebuild_requested, False
        return self._count_changes and self.comm.any(requested)

    def _rebuild_if_requested(self):
        """Terms that add or remove particles (inlets, outlets) ask for a rebuild: new rows get
        their owner, ghosts, images and neighbours before the next step (collective)."""
        if self._rebuild_requested():
            self.rebuild()

    def advance_to(self, t_target, on_step=None):
        """Step until t == t_target exactly. The last two steps share the remaining time
        equally when it is less than two full steps, so no sliver step is taken."""
        while self.t < t_target * (1 - 1e-12):
            remaining = t_target - self.t
            self.step(
                dt_max=remaining
                if remaining <= self._dt_estimate()
                else max(0.5 * remaining, remaining - self._dt_estimate())
            )
            if on_step is not None:
                on_step(self)
        self.t = max(self.t, t_target)

    def _dt_estimate(self):
        return self.dt_prev if self.dt_prev > 0 else math.inf

    def current_state(self):
        """Bring values to the current time (predict) and the fields derived from them, for output."""
        self.predict()
        for term in self.plan.terms:
            term.derive(self.ctx)
        return self.particles

    # -- checkpoint and restart (generic: the step loop's own state, no physics) -------------
    def saved_state(self) -> dict:
        """Everything the step loop carries from step to step outside the particle fields, for a
        checkpoint (solver/output/checkpoint.py): values alike on every rank ("shared"), this
        rank's diagnostics ("rank"), and each term's state (Term.state; None = nothing)."""
        return {
            "shared": {
                "t": self.t,
                "step_count": self.step_count,
                "dt_prev": self.dt_prev,
                "dt_first": self.dt_first,
                "dt_limit": self.dt_limit,
                "dt": self.ctx.dt,
                "rebuilds": self.rebuilds,
                "settling": self.settling,
                "gravity": self.ctx.gravity.tolist(),
            },
            "rank": {
                "wall_reflections": int(self.wall_reflections),
                "deepest_penetration": float(self.deepest_penetration),
                "next_id": int(self.particles.next_id),
            },
            "terms": {t.name: s for t in self.plan.terms if (s := t.state()) is not None},
        }

    def _resume(self, resume):
        """Continue from a checkpoint. The particle fields (this rank's rows, in the order they
        had) are back; what the last neighbour rebuild built from them (ghosts, wall images,
        neighbour lists, cell order, the MPI cuts) is rebuilt by replaying that rebuild: at the
        positions it saw, the Verlet references x_ref, with the cuts it used (same rank count).
        So the lists, and the order of every pair sum, are those of the uninterrupted run, and
        the run continues bit for bit; a fresh rebuild at the current positions would sum in
        another order and rebuild on another schedule (round-off differences). On another rank
        count the cuts are made afresh from x_ref; the lists are valid, as every particle is
        within skin/2 of x_ref. Then the current positions go back, ghosts and images are
        refreshed, and the scalars and term states are restored."""
        ps = self.particles
        n = ps.n_owned
        ids = ps.owned("id").copy()
        order = np.argsort(ids, kind="stable")
        ids_sorted, x_now = ids[order], ps.owned("x")[order].copy()
        ps["x"][:n] = ps["x_ref"][:n]
        self.comm.restore_decomposition(resume.decomposition)
        self.rebuild()
        n = ps.n_owned
        at = np.searchsorted(ids_sorted, ps.owned("id"))
        if n and (at.max() >= len(ids_sorted) or np.any(ids_sorted[at] != ps.owned("id"))):
            raise RuntimeError("restart: a particle reached this rank that it did not load")
        ps["x"][:n] = x_now[at]
        shared = resume.shared
        self.t = float(shared["t"])
        self.step_count = int(shared["step_count"])
        self.dt_prev = self.ctx.dt_prev = float(shared["dt_prev"])
        self.dt_first = None if shared["dt_first"] is None else float(shared["dt_first"])
        self.dt_limit = shared["dt_limit"]
        self.ctx.dt = float(shared["dt"])
        self.rebuilds = int(shared["rebuilds"])
        self.settling = shared["settling"]
        self.ctx.gravity[:] = shared["gravity"]
        mine = resume.rank_state
        self.wall_reflections = int(mine["wall_reflections"])
        self.deepest_penetration = float(mine["deepest_penetration"])
        ps.next_id = max(ps.next_id, int(mine["next_id"]))
        for term in self.plan.terms:
            if term.name in resume.terms:
                term.restore(resume.terms[term.name])
        # ghosts and images of every changing field from the owners' current values (the step
        # refreshes each before it is read anyway; this leaves no row at x_ref)
        self.refresh(
            tuple(k for k, f in self.plan.fields.items() if f.mirror is not Mirror.NONE and not f.constant)
        )

    # -- failure reports ----------------------------------------------------------------
    def _worst_acceleration(self):
        ps = self.particles
        a2 = np.sum(ps.owned("acc") ** 2, axis=1)
        i = int(np.nanargmax(a2)) if len(a2) else 0
        return (
            f"largest acceleration {math.sqrt(a2[i]):.3g} m/s^2 at particle id {ps['id'][i]}, "
            f"x = {ps['x'][i].tolist()}"
        )

    def _report_bad_state(self, status):
        ps = self.particles
        n = ps.n_owned
        x, v, rho = ps["x"][:n], ps["v_half"][:n], ps[self._rho_state][:n]
        bad_finite = ~(np.isfinite(x).all(axis=1) & np.isfinite(v).all(axis=1) & np.isfinite(rho))
        if bad_finite.any():  # whatever the status code: NaN positions also compare as outside
            i = int(np.flatnonzero(bad_finite)[0])
            self._blow_up(
                f"non-finite state (NaN/inf) in {int(bad_finite.sum())} particle(s)",
                f"first: particle id {ps['id'][i]} of material "
                f"{self.plan.materials.names[ps['material'][i]]}",
            )
        outside = np.any((x < self.lo) | (x > self.hi), axis=1)
        if outside.any():
            i = int(np.flatnonzero(outside)[0])
            axis = int(np.flatnonzero((x[i] < self.lo) | (x[i] > self.hi))[0])
            side = "xyz"[axis] + ("_min" if x[i, axis] < self.lo[axis] else "_max")
            kind = "wall" if getattr(self.scene.walls, side) else "open side"
            self._blow_up(
                f"{int(outside.sum())} particle(s) left the domain through the {side} {kind}",
                f"first: particle id {ps['id'][i]} at x = {x[i].tolist()}, v = {v[i].tolist()}",
            )
        self._blow_up("bad state reported by another rank", "see that rank's message", here=False)

    def _blow_up(self, what, where, here=True):
        # every call is reached by all ranks (after a reduction);
        # MPI: all report the failing rank's message
        what, where = self.comm.agree(what, where, here)
        raise BlowUpError(what, where, self.t, self.step_count)
