"""What a physics term is: a piece of the model that declares, as data, what it needs.

A term is a class in one module of `solver/physics/`, registered by one line in
`solver/physics/__init__.py`. Its class attributes and constructor declare

  stage        when it runs in a step (Stage)
  targets      pair terms: the phase whose rates it computes ...
  neighbours   ... summing over neighbours of this phase (None: a particle-local term)
  equations    what it computes and the source of each equation (printed by --explain)
  fields       the particle fields it needs allocated
  reads        fields it reads on ghost and image rows: they must be current before it runs
               (the halo exchange and the image refresh are derived from these, never typed)
  writes       fields it writes on owned rows (current nowhere else afterwards)
  writes_everywhere  fields it computes on every row, ghosts and images included (never exchanged)
  adds_to      rates it accumulates into (the step loop zeroes them before the rates stage)
  integrates   (value, half-step value, rate) triples the leap-frog advances
  dt_limit     its time-step constraint, if any: constant, or (constant_dt None) dt_now(ctx) each step
  slip_image_velocity  True: across a no-slip wall it reads the images' velocities as free slip
               (normal part reversed), through ctx.image_velocity; False: as the wall's kind says

and its methods do the work on a TermContext. `build(scene, materials)` returns the term, or
None when the scene does not call for it: then it is not compiled, allocated, exchanged or run.
Terms never see MPI: the step loop exchanges what they declare.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from .materials import MaterialTable, Phase
from .particles import FieldSpec
from .scene import Scene
from .timestep import Constraint


class Stage(Enum):
    """Where in a step a term runs, in step order."""

    REBUILD = "at each neighbour rebuild"
    STATE = "the state at step n: pressures, stresses (per particle or from neighbour sums)"
    RATES = "the rates at step n, from neighbour sums"
    AFTER_RATES = "after the rates"
    AFTER_KICK = "after the leap-frog kick, on the half-step values"
    LEAVING = "after the drift, before the state check: particles leaving through outlets removed"
    AFTER_DRIFT = "after the drift, on x at n+1 and v at n+1/2"


@dataclass(frozen=True)
class Equation:
    what: str
    source: str


@dataclass(frozen=True)
class Integrated:
    """A field the leap-frog advances: value at n, value at n+1/2, and its rate (seed eqs. 24-27)."""

    value: str
    half: str
    rate: str


class Term:
    """Base class: a term that does nothing, needs nothing and exists in no plan."""

    name: str = "term"
    stage: Stage = Stage.STATE
    targets: Phase | None = None
    neighbours: Phase | None = None
    changes_particles: bool = False  # adds or removes particles (then it calls ctx.request_rebuild())
    # No-slip walls reverse the whole image velocity (Takeda et al. 1994); only the viscous shear term
    # should see that. Terms that compress or damp by the normal approach (continuity, artificial
    # viscosity, XSPH) read the free-slip image velocity instead (Adami et al. 2012, sec. 2.3; Morris
    # et al. 1997): they set this and take velocities through ctx.image_velocity(self, name).
    slip_image_velocity: bool = False

    def __init__(self):
        self.equations: tuple[Equation, ...] = ()
        self.fields: dict[str, FieldSpec] = {}
        self.reads: tuple[str, ...] = ()
        self.writes: tuple[str, ...] = ()
        self.writes_everywhere: tuple[str, ...] = ()
        self.adds_to: tuple[str, ...] = ()
        self.integrates: tuple[Integrated, ...] = ()
        self.dt_limit: Constraint | None = None
        self.position_correction: str | None = None  # a field added to v in the drift (XSPH, eq. 22)

    @classmethod
    def build(cls, scene: Scene, materials: MaterialTable) -> Term | None:
        """The term configured for this scene, or None if the scene does not call for it."""
        raise NotImplementedError

    @property
    def pair(self) -> tuple[Phase, Phase] | None:
        """(targets, neighbours) of a pair term, else None."""
        return (self.targets, self.neighbours) if self.neighbours is not None else None

    def run(self, ctx: TermContext) -> None:
        """Do the term's work at its stage."""

    def derive(self, ctx: TermContext) -> None:
        """Bring fields derived from the state (pressure, stress) to the current time on owned
        rows, for output. Only terms that own such fields override it."""

    def dt_now(self, ctx: TermContext) -> float:
        """A state-dependent dt limit (dt_limit.constant_dt is None), after the rates stages."""
        return np.inf

    def start(self, ctx: TermContext) -> None:
        """Called once at set-up, before the first neighbour build, on the particle set that every
        MPI rank still holds whole: a term may append its initial particles here (all of them)."""

    def on_rebuild(self, ctx: TermContext) -> None:
        """Called after every neighbour rebuild (after the halo is built)."""

    # -- checkpoint and restart (solver/output/checkpoint.py) ------------------------------------
    def state(self):
        """What this term carries from one step to the next outside the particle fields (counters,
        accumulated totals, a moving inlet's position), for a checkpoint: this rank's share, as
        JSON data (numbers, strings, lists, dicts; NumPy arrays and scalars are written as lists
        and numbers, floats exactly). None (the default): nothing, everything is in the fields or
        is recomputed at a neighbour rebuild (which the restart replays)."""
        return None

    def restore(self, state) -> None:
        """Put back what state() returned (after the restart's neighbour rebuild)."""

    def regroup_state(self, states: list, size: int) -> list:
        """The states for `size` ranks from those a checkpoint written on len(states) ranks holds
        (a restart on another rank count). Default: a state every rank holds alike (a replicated
        counter) goes to every rank; a term whose ranks hold different shares (a per-rank count)
        must say how to regroup them (e.g. the sum on rank 0, zero elsewhere)."""
        if all(s == states[0] for s in states):
            return [states[0]] * size
        raise ValueError(
            f"term '{self.name}' holds different state on each rank and does not say how to regroup it "
            f"for {size} rank(s) (Term.regroup_state): restart on {len(states)} rank(s)"
        )

    def explain(self) -> list[str]:
        """Extra lines for --explain (options in force)."""
        return []


@dataclass
class TermContext:
    """What a term sees of a running simulation: particles, neighbour lists, the geometry of
    the kernel and the time step. Filled in by the Simulation; no communicator in it."""

    particles: object
    h: float
    norm: float  # kernel normalisation a_d
    is3d: object  # True in 3D, None in 2D: a compile-time switch for the kernels
    gravity: np.ndarray
    dt: float = 0.0  # the current step (set before the kick)
    dt_prev: float = 0.0  # the previous step
    lists: dict = field(default_factory=dict)  # (targets, neighbours) -> NeighbourList
    rows: dict = field(default_factory=dict)  # Phase -> owned rows of that phase (int64)
    images: object = None  # the wall-image term, if the scene has walls
    shared: dict = field(default_factory=dict)  # per-step values one term leaves for another
    integrated: tuple = ()  # the plan's (value, half, rate) triples: terms that freeze rows drop the rates
    position_correction: str | None = None  # the plan's drift-velocity correction field (XSPH), if any
    owns: object = None  # owns(x) -> bool mask: does this process own new particles at x? (MPI ownership)
    rebuild_requested: bool = False  # set by request_rebuild(); the step loop rebuilds and clears it

    def request_rebuild(self):
        """A term added or removed particles: the step loop migrates them and rebuilds halo, images
        and neighbour lists after the current stage (docs/adding_a_term.md, "Adding or removing
        particles")."""
        self.rebuild_requested = True

    def image_velocity(self, term: Term, name: str) -> np.ndarray:
        """The velocity field `name` as `term` reads it on image rows: the field itself, or for a term
        with slip_image_velocity, a copy whose wall images carry the free-slip mirror velocity."""
        if term.slip_image_velocity and self.images is not None:
            return self.images.slip_velocity(self.particles, name)
        return self.particles[name]

    def owned_here(self, x):
        """Mask of the rows of x whose owner is this process (all of them in a serial run)."""
        if self.owns is None:
            return np.ones(len(x), dtype=bool)
        return self.owns(x)

    def neighbours(self, term: Term):
        return self.lists[term.pair]

    def image_tables(self):
        """(source rows, axis signs, offsets) of the current images; empty without walls."""
        if self.images is None:
            dim = self.particles.dim
            return np.zeros(0, np.int64), np.zeros((0, dim)), np.zeros((0, dim))
        return self.images.tables()

    def image_sources(self):
        """The source row of every image row n_local + k (box walls' images, then bodies')."""
        if self.images is None:
            return np.zeros(0, np.int64)
        return self.images.sources()
