"""The step loop: predict, refresh halos and images, EOS, passes, time step, kick, drift.

It knows nothing of MPI (the communicator does) and nothing of specific physics beyond
calling the passes the plan lists.
"""

from __future__ import annotations

import math

import numpy as np

from .errors import BlowUpError
from .initial_state import create_particles
from .integrate import STATE_OK, as_rows, lf_drift, lf_kick, lf_predict, max_norm2, state_status
from .kernels import SUPPORT_RADIUS, cubic_spline_normalisation, cubic_spline_w
from .materials import PHASE_SOIL, PHASE_WATER
from .neighbors import CellGrid, CellList
from .parallel.communicator import SerialCommunicator
from .physics import fluid, soil
from .physics.boundary import (
    ImageWalls,
    add_equilibrium_image_stress,
    add_hydrostatic_image_pressure,
    frictional_images,
    refresh_image_scalar,
    refresh_image_tensor,
    refresh_image_vectors,
)
from .plan import Plan, build_plan
from .scene import Scene
from .tensors import SYM_AXES
from .timestep import TimeStepper


class Simulation:
    def __init__(self, scene: Scene, comm=None, plan: Plan | None = None, particles=None):
        self.scene = scene
        self.comm = comm or SerialCommunicator()
        self.plan = plan or build_plan(scene)
        self.particles = particles if particles is not None else create_particles(scene, self.plan)
        dim = scene.dim
        self.h = scene.h
        self.is3d = True if dim == 3 else None  # compile-time dimension switch for the kernels
        self.norm = cubic_spline_normalisation(dim, self.h)
        # artificial stress f_ij = W_ij / W(dx); evaluated only when the plan has the term (nothing compiled
        # otherwise)
        self.inv_w_dx = (
            1.0 / float(cubic_spline_w(scene.scene.spacing, self.h, self.norm))
            if self.plan.options.get("artificial_stress")
            else 0.0
        )
        self.skin = scene.numerics.neighbour_skin * self.h
        self.radius = SUPPORT_RADIUS * self.h + self.skin  # Verlet list radius
        self.lo = np.asarray(scene.domain.min, float)
        self.hi = np.asarray(scene.domain.max, float)
        self.gravity = np.asarray(scene.scene.gravity, float)
        self.walls = ImageWalls(scene, reach=self.radius)
        self.cells = CellList(CellGrid.covering(self.lo, self.hi, self.radius, pad=self.radius))
        self.stepper = TimeStepper(self.plan.constraints, self.h, scene.numerics.cfl.force)
        mats = self.plan.materials
        self._phase_of_material = mats.phase
        self.t = 0.0
        self.step_count = 0
        self.dt_prev = 0.0
        self.dt_first = None
        self.dt_limit = ""
        self.rebuilds = 0
        self._rho_state = "rho_half" if "rho_half" in self.particles else "rho"  # density checked for NaN
        self.wall_reflections = 0  # specular reflections at walls (diagnostic, see lf_drift)
        self.deepest_penetration = 0.0
        self.lists = {}
        self._start_half_steps()
        self.comm.setup(scene)  # MPI: domain box and [parallel] settings (no-op serial)
        self.rebuild()
        self.settling = None
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
        for value, half, _ in self.plan.integrated:
            ps[half][:n] = ps[value][:n]

    # -- neighbour structures -------------------------------------------------------
    def rebuild(self):
        """Migrate, sort into cell order, rebuild halo, images and Verlet lists."""
        ps = self.particles
        self.comm.migrate(ps)
        ps.drop_halo()
        self.cells.bin(ps["x"], ps.n_owned)
        ps.permute_owned(self.cells.owned_cell_order(ps.n_owned))
        self.comm.build_halo(ps, self.radius, self.plan.halo_fields)
        self.walls.rebuild(ps)
        src, sign, offset = self.walls.tables()
        first = ps.n_local
        refresh_image_vectors(first, src, sign, offset, ps["x"], ps["v"], self.walls.velocity_signs())
        for name in ("mass", "material", "rho"):
            refresh_image_scalar(first, src, ps[name])
        n = ps.n_total
        self.cells.bin(ps["x"], n)
        phase = self._phase_of_material[ps["material"][:n]].astype(np.int32)
        owned_phase = phase[: ps.n_owned]
        self.lists = {}
        for p in self.plan.passes:
            key = (p.targets, p.neighbours)
            if key not in self.lists:
                want = {"water": PHASE_WATER, "soil": PHASE_SOIL}
                targets = np.flatnonzero(owned_phase == want[p.targets]).astype(np.int64)
                self.lists[key] = self.cells.neighbour_list(
                    ps["x"], targets, self.radius, phase, want[p.neighbours]
                )
        ps["x_ref"][: ps.n_owned] = ps["x"][: ps.n_owned]
        self.rebuilds += 1

    def refresh_images(self, vectors=(), scalars=(), tensors=()):
        ps = self.particles
        src, sign, offset = self.walls.tables()
        if len(src) == 0:
            return
        first = ps.n_local
        if vectors:
            refresh_image_vectors(first, src, sign, offset, ps["x"], ps["v"], self.walls.velocity_signs())
        for name in scalars:
            refresh_image_scalar(first, src, ps[name])
        tsign = self.walls.tensor_signs() if tensors else None  # eq. (23); no-slip walls: T' = T
        for name in tensors:
            refresh_image_tensor(first, src, tsign, SYM_AXES, ps[name])

    # -- rates ------------------------------------------------------------------------
    def compute_rates(self):
        ps, plan, mats = self.particles, self.plan, self.plan.materials
        n = ps.n_owned
        ps["acc"][:n] = self.gravity  # body force g in eq. (7)
        ps["drho"][:n] = 0.0
        self.comm.refresh_halo(ps, ("x", "v", "rho"))
        self.refresh_images(vectors=plan.image_vectors, scalars=plan.image_scalars)
        if "p" in ps:
            fluid.tait_pressure(
                ps.n_total, ps["rho"], ps["material"], mats.rho0, mats.eos_b, mats.eos_exponent, ps["p"]
            )
            if plan.options.get("hydrostatic_images") and ps.n_image:
                add_hydrostatic_image_pressure(
                    ps.n_local, self.walls.tables()[0], ps["x"], ps["rho"], self.gravity, ps["p"]
                )
        for p in plan.passes:
            nl = self.lists[(p.targets, p.neighbours)]
            getattr(self, "_pass_" + p.name)(nl)
        if "fixed" in ps:
            fixed = ps["fixed"][:n]
            ps["acc"][:n][fixed] = 0.0  # wall particles are never moved (v stays 0)

    def _soil_args(self):
        s = self.plan.materials.soil
        return (s.bulk, s.shear, s.tan_phi, s.cohesion, s.alpha_phi, s.k_c, s.alpha_psi, s.yield_model)

    def _pass_soil_stress(self, nl, rho="rho", stress="stress_dev", update_history=False):
        """Mean stress (17) and the return mapping (16) / Bui et al. (2008) on the soil rows,
        then neighbours' copies (halo, images: eq. 23)."""
        ps, mats = self.particles, self.plan.materials
        soil.soil_stress_state(
            nl.targets,
            ps[rho],
            ps[stress],
            ps["material"],
            mats.rho0,
            *self._soil_args(),
            ps["mean_stress"],
            ps["eps_vp"] if "eps_vp" in ps else None,
            update_history,
        )
        if update_history:
            return
        tensors = ("stress_dev",)
        if self.plan.options.get("artificial_stress"):
            soil.artificial_stress(
                nl.targets,
                ps["rho"],
                ps["mean_stress"],
                ps["stress_dev"],
                self.scene.numerics.artificial_stress,
                ps["art_stress"],
                self.scene.dim == 3,
            )
            tensors += ("art_stress",)
        self.comm.refresh_halo(ps, ("mean_stress",) + tensors)
        self.refresh_images(scalars=("mean_stress",), tensors=tensors)
        if self.plan.options.get("equilibrium_soil_images") and ps.n_image:
            add_equilibrium_image_stress(
                ps.n_local,
                self.walls.tables()[0],
                ps["x"],
                ps["rho"],
                self.gravity,
                ps["mean_stress"],
                ps["stress_dev"],
            )
        if self.walls.frictional and ps.n_image:  # Coulomb walls: stick/slip per image, then its velocity
            w = self.walls
            src, sign, offset = w.tables()
            v_stick = (
                float(np.linalg.norm(self.gravity)) * self.dt_prev if self.dt_prev > 0 else np.inf
            )  # one step of g
            frictional_images(
                ps.n_local,
                src,
                offset,
                w.fric_axis,
                w.fric_side,
                w.mu,
                ps["mean_stress"],
                ps["stress_dev"],
                w.vsign,
                ps["x"],
                ps["v"],
                ps["rho"],
                self.gravity,
                v_stick,
            )
            refresh_image_vectors(ps.n_local, src, sign, offset, ps["x"], ps["v"], w.vsign)

    def _pass_soil_rates(self, nl):
        ps, mats, opt = self.particles, self.plan.materials, self.plan.options
        art = opt.get("artificial_stress")
        soil.soil_rates(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["v"],
            ps["rho"],
            ps["mean_stress"],
            ps["stress_dev"],
            ps["mass"],
            ps["material"],
            mats.sound_speed,
            mats.soil.shear,
            self.h,
            self.norm,
            ps["drho"],
            ps["acc"],
            ps["dstress"],
            mats.av_alpha if opt["soil_artificial_viscosity"] else None,
            mats.av_beta if opt["soil_artificial_viscosity"] else None,
            ps["art_stress"] if art else None,
            self.scene.numerics.artificial_stress_exponent,
            self.inv_w_dx,
        )

    def _pass_viscous_stress(self, nl):
        ps = self.particles
        fluid.viscous_stress(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["v"],
            ps["rho"],
            ps["mass"],
            ps["material"],
            self.plan.materials.viscosity,
            self.h,
            self.norm,
            ps["tau"],
            self.is3d,
        )
        self.comm.refresh_halo(ps, ("tau",))
        self.refresh_images(tensors=("tau",))

    def _pass_fluid_rates(self, nl):
        ps, mats, opt = self.particles, self.plan.materials, self.plan.options
        fluid.fluid_rates(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["v"],
            ps["rho"],
            ps["p"],
            ps["mass"],
            ps["material"],
            mats.sound_speed,
            self.h,
            self.norm,
            None if opt["symplectic_density"] else ps["drho"],
            ps["acc"],
            ps["tau"] if opt["viscous"] else None,
            mats.av_alpha if opt["artificial_viscosity"] else None,
            mats.av_beta if opt["artificial_viscosity"] else None,
            ps["xsph"] if opt["xsph"] else None,
            self.scene.numerics.xsph_epsilon,
            self.is3d,
            opt["mixed_water"] or None,
        )

    # -- one step ---------------------------------------------------------------------
    def predict(self):
        """Values at the current time n from the half-step values (no-op before step 1)."""
        if self.step_count == 0:
            return
        ps = self.particles
        n = ps.n_owned
        for value, half, rate in self.plan.integrated:
            lf_predict(
                n, 0.5 * self.dt_prev, as_rows(ps[value], n), as_rows(ps[half], n), as_rows(ps[rate], n)
            )

    def step(self, dt_max=math.inf):
        ps = self.particles
        self.predict()
        self.compute_rates()
        n = ps.n_owned
        max_acc = math.sqrt(self.comm.max(max_norm2(n, ps["acc"])))
        dt, self.dt_limit = self.stepper(max_acc)
        dt = self.comm.min(dt)
        if self.dt_first is None:
            self.dt_first = dt
        elif dt < self.scene.numerics.cfl.collapse_fraction * self.dt_first:
            self._blow_up(
                f"time step collapsed to {dt:.3g} s ({self.dt_limit} constraint; first step "
                f"{self.dt_first:.3g} s)",
                self._worst_acceleration(),
            )
        dt = min(dt, dt_max)
        weight = 0.5 * (self.dt_prev + dt)  # dt_prev = 0 on the first step: the half-kick
        for _, half, rate in self.plan.integrated:
            lf_kick(n, weight, as_rows(ps[half], n), as_rows(ps[rate], n))
        if self.plan.options["soil"]:  # plastic return mapping of the new half-step stress
            self._pass_soil_stress(
                self.lists[("soil", "soil")], "rho_half", "stress_dev_half", update_history=True
            )
        xsph = ps["xsph"] if self.plan.options["xsph"] else None
        w = self.walls
        moved2, reflected, depth = lf_drift(
            n, dt, ps["x"], ps["v_half"], ps["x_ref"], w.has_lo, w.lo, w.has_hi, w.hi, xsph
        )
        self.wall_reflections += reflected
        self.deepest_penetration = max(self.deepest_penetration, depth)
        self.t += dt
        self.step_count += 1
        self.dt_prev = dt
        status = self.comm.max(state_status(n, ps["x"], ps["v_half"], ps[self._rho_state], self.lo, self.hi))
        if status != STATE_OK:
            self._report_bad_state(status)
        if self.comm.max(depth) > self.h:
            self._blow_up(
                f"a particle crossed a wall by {depth:.3g} m in one step (more than h = {self.h:.3g} m)",
                self._worst_acceleration(),
            )
        rebalance = self.comm.rebalance_due(self.step_count, n)  # MPI: new cuts when the load drifted
        if self.comm.max(moved2) > (0.5 * self.skin) ** 2 or rebalance:
            self.rebuild()
        for p in self.plan.post_drift_passes:
            getattr(self, "_pass_" + p.name)(self.lists[(p.targets, p.neighbours)], dt)
        return dt

    def _pass_fluid_continuity(self, nl, dt):
        """rho_{n+1} = rho_n + dt (drho/dt)(x_{n+1}, v_{n+1/2}): ghosts and images carry v_half."""
        ps = self.particles
        self.comm.refresh_halo(ps, ("x", "v_half"))
        src, sign, offset = self.walls.tables()
        if len(src):
            refresh_image_vectors(
                ps.n_local, src, sign, offset, ps["x"], ps["v_half"], self.walls.velocity_signs()
            )
        fluid.continuity(
            nl.targets,
            nl.start,
            nl.index,
            ps["x"],
            ps["v_half"],
            ps["mass"],
            self.h,
            self.norm,
            ps["drho"],
            self.is3d,
        )
        n = ps.n_owned
        lf_kick(n, dt, as_rows(ps["rho"], n), as_rows(ps["drho"], n))

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
        """Bring values to the current time (predict) and the pressure with them, for output."""
        self.predict()
        ps, mats = self.particles, self.plan.materials
        if "p" in ps:
            fluid.tait_pressure(
                ps.n_owned, ps["rho"], ps["material"], mats.rho0, mats.eos_b, mats.eos_exponent, ps["p"]
            )
        if self.plan.options["soil"]:
            nl = self.lists[("soil", "soil")]
            soil.soil_stress_state(
                nl.targets,
                ps["rho"],
                ps["stress_dev"],
                ps["material"],
                mats.rho0,
                *self._soil_args(),
                ps["mean_stress"],
                ps["eps_vp"] if "eps_vp" in ps else None,
                False,
            )
        return ps

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
        # every call is reached by all ranks (after a reduction); MPI: all report the failing rank's message
        what, where = self.comm.agree(what, where, here)
        raise BlowUpError(what, where, self.t, self.step_count)
