"""The plan: from a scene, in plain Python, the ordered list of the terms it calls for, and
everything that follows from their declarations (solver/term.py): the particle fields to
allocate, the fields the leap-frog advances, the time-step constraints, the neighbour lists,
and when ghosts (MPI halo) and wall images must be refreshed. Nothing outside the plan is
allocated, compiled, exchanged or run.

A missing piece of physics is simply absent here (Oceananigans' `nothing`): no field, no
term, no exchanged field, no time-step limit. `scoursph run SCENE --explain` prints it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .fields import kinematics
from .materials import MaterialTable, Phase, build_material_table
from .particles import FieldSpec, Mirror
from .physics import TERMS
from .scene import Scene
from .term import Integrated, Stage, Term
from .timestep import Constraint

RATE_STAGES = (Stage.STATE, Stage.RATES, Stage.AFTER_RATES)
"""The stages that compute the rates at step n; ghosts and images stay current across them."""

FORCE_LIMIT = Constraint("force", "seed eq. (29)", None)
"""Every scene's state-dependent limit dt <= C_f sqrt(h / |a|max)."""


@dataclass(frozen=True)
class Scheduled:
    """A term and the fields refreshed on ghosts and images just before it runs."""

    term: Term
    refresh: tuple[str, ...]


@dataclass
class Plan:
    dim: int
    materials: MaterialTable
    terms: tuple[Term, ...]  # in step order
    absent: tuple[str, ...]  # registered terms this scene does not call for
    fields: dict[str, FieldSpec]
    integrated: tuple[Integrated, ...]
    constraints: tuple[Constraint, ...]
    dynamic_limits: tuple[Term, ...]  # terms whose dt limit depends on the state (dt_now)
    pairs: tuple[tuple[Phase, Phase], ...]  # neighbour lists: (targets, neighbours)
    phases: tuple[Phase, ...]  # the phases of the scene's materials
    accumulated: tuple[str, ...]  # rates zeroed before the rates stages
    position_correction: str | None  # field added to v in the drift (XSPH)
    halo_fields: tuple[str, ...]  # what ghosts receive at a neighbour rebuild
    rebuild_image_fields: tuple[str, ...]  # what new images receive at a rebuild
    schedule: dict[Stage, tuple[Scheduled, ...]]

    def term(self, cls):
        """The plan's instance of a term class, or None."""
        return next((t for t in self.terms if isinstance(t, cls)), None)

    def has_term(self, name):
        return any(t.name == name for t in self.terms)

    def equations(self):
        """Every (term name, equation) of the plan."""
        return [(t.name, e) for t in self.terms for e in t.equations]

    def bytes_per_particle(self):
        return sum(spec.nbytes_per_particle() for spec in self.fields.values())


def build_plan(scene: Scene) -> Plan:
    mats = build_material_table(scene)
    built = [(cls, cls.build(scene, mats)) for cls in TERMS]
    order = list(Stage)
    terms = tuple(sorted((t for _, t in built if t is not None), key=lambda t: order.index(t.stage)))
    absent = tuple(cls.name for cls, t in built if t is None)
    fields = _fields(scene.dim, terms)
    integrated = (Integrated("v", "v_half", "acc"),) + _unique(i for t in terms for i in t.integrates)
    _check(terms, fields, integrated)
    corrections = [t.position_correction for t in terms if t.position_correction]
    reads = _unique(f for t in terms for f in t.reads)
    constant = tuple(n for n, s in fields.items() if s.constant)
    return Plan(
        dim=scene.dim,
        materials=mats,
        terms=terms,
        absent=absent,
        fields=fields,
        integrated=integrated,
        constraints=(FORCE_LIMIT,) + tuple(t.dt_limit for t in terms if t.dt_limit is not None),
        dynamic_limits=tuple(t for t in terms if t.dt_limit is not None and t.dt_limit.constant_dt is None),
        pairs=_unique(t.pair for t in terms if t.pair),
        phases=tuple(Phase(k) for k in sorted(set(mats.phase.tolist()))),
        accumulated=_unique(f for t in terms for f in t.adds_to),
        position_correction=corrections[0] if corrections else None,
        halo_fields=_unique(reads + constant),
        rebuild_image_fields=("x",) + tuple(n for n in constant if fields[n].mirror is not Mirror.NONE),
        schedule=_schedule(terms, fields),
    )


def _unique(items):
    return tuple(dict.fromkeys(items))


def _fields(dim, terms):
    fields = kinematics(dim)
    for t in terms:
        for name, spec in t.fields.items():
            if name in fields and fields[name] != spec:
                raise ValueError(f"term '{t.name}' declares field '{name}' differently from another term")
            fields[name] = spec
    return fields


def _check(terms, fields, integrated):
    """Declarations that do not fit together are programming errors: say which."""
    for t in terms:
        for name in t.reads + t.writes + t.writes_everywhere + t.adds_to:
            if name not in fields:
                raise ValueError(f"term '{t.name}' uses field '{name}', which no term of the plan declares")
        for name in t.reads:
            if fields[name].mirror is Mirror.NONE:
                raise ValueError(f"term '{t.name}' reads '{name}' from neighbours, but it has no image rule")
    for i in integrated:
        for name in (i.value, i.half, i.rate):
            if name not in fields:
                raise ValueError(f"integrated field '{name}' is not allocated by any term")
    if len({t.position_correction for t in terms if t.position_correction}) > 1:
        raise ValueError("two terms correct the drift velocity")


def _schedule(terms, fields):
    """When ghosts and images must be refreshed, derived from what terms read and write.

    At the start of the rates stages and of each later stage every changing field is taken as
    stale (the predictor, kick and drift changed the state). Before a term that reads a stale
    field, that field is refreshed together with every other stale field a later term of the
    same stretch reads before anyone writes it again (one exchange instead of several)."""
    changing = {n for n, s in fields.items() if s.mirror is not Mirror.NONE and not s.constant}
    out = {}
    stretches = [RATE_STAGES, (Stage.AFTER_KICK,), (Stage.LEAVING,), (Stage.AFTER_DRIFT,)]
    for stages in stretches:
        run = [t for t in terms if t.stage in stages]
        stale = set(changing)
        for k, term in enumerate(run):
            need = set(term.reads) & stale
            batch = set()
            if need:
                batch = need | {f for f in stale if _read_before_written(f, run[k:])}
            stale -= batch
            stale |= set(term.writes) | set(term.adds_to)
            stale -= set(term.writes_everywhere)
            refresh = tuple(f for f in fields if f in batch)  # allocation order: deterministic on every rank
            out.setdefault(term.stage, []).append(Scheduled(term, refresh))
    return {stage: tuple(items) for stage, items in out.items()}


def _read_before_written(name, run):
    """Does some term of `run` read `name` before a term of `run` writes it? (The first term
    reads before it writes.)"""
    for t in run:
        if name in t.reads:
            return True
        if name in t.writes or name in t.adds_to or name in t.writes_everywhere:
            return False
    return False


def explain(plan: Plan, scene: Scene) -> str:
    """Human-readable plan: what will be computed, in which order, and what will not."""
    mats = plan.materials
    lines = [
        f"Plan for scene '{scene.scene.name}' ({plan.dim}D, "
        f"dx = {scene.scene.spacing:g} m, h = {scene.h:g} m)",
        "",
        "Materials:",
    ]
    for k, name in enumerate(mats.names):
        lines.append(
            f"  [{k}] {name}: phase {Phase(int(mats.phase[k])).label}, rho0 = {mats.rho0[k]:g}, "
            f"c = {mats.sound_speed[k]:g} m/s, mu = {mats.viscosity[k]:g} Pa s, "
            f"AV alpha = {mats.av_alpha[k]:g}, beta = {mats.av_beta[k]:g}"
        )
    lines += ["", "Terms, in step order (the predictor brings v, rho and stresses to step n first):"]
    number = 0
    for stage in Stage:
        in_stage = [t for t in plan.terms if t.stage is stage]
        if not in_stage:
            continue
        lines.append(f"  {stage.value}:")
        refresh = {s.term.name: s.refresh for s in plan.schedule.get(stage, ())}
        for t in in_stage:
            number += 1
            if refresh.get(t.name):
                lines.append(f"     (ghosts and images refreshed: {', '.join(refresh[t.name])})")
            pair = f": {t.targets.label} <- {t.neighbours.label}" if t.pair else ""
            lines.append(f"  {number:2d}. {t.name}{pair}")
            for e in t.equations:
                lines.append(f"       - {e.what} [{e.source}]")
            io = []
            if t.reads:
                io.append("reads from neighbours: " + ", ".join(t.reads))
            written = t.writes + t.adds_to + t.writes_everywhere
            if written:
                io.append("writes: " + ", ".join(written))
            if io:
                lines.append("       " + "; ".join(io))
            lines += ["       " + extra for extra in t.explain()]
    drift = " + " + plan.position_correction if plan.position_correction else ""
    lines.append(
        "  then the leap-frog (seed eqs. 24-27) kicks "
        + ", ".join(i.value for i in plan.integrated)
        + f" and drifts x with v{drift}"
    )
    lines += ["", "Time-step constraints (dt = min):"]
    for c in plan.constraints:
        value = "depends on the state" if c.constant_dt is None else f"{c.constant_dt:.3g} s"
        lines.append(f"  - {c.name} [{c.equation}]: {value}")
    lines += ["", f"Particle fields ({plan.bytes_per_particle()} bytes per particle):"]
    for name, spec in plan.fields.items():
        comps = "scalar" if spec.components == 0 else f"{spec.components} components"
        lines.append(f"  {name:16s} {np.dtype(spec.dtype).name:8s} {comps:14s} {spec.reason}")
    lines += ["", "Halo exchange (MPI) and image refresh:"]
    lines.append("  at each neighbour rebuild, ghosts get: " + ", ".join(plan.halo_fields))
    lines.append("  at each neighbour rebuild, new images get: " + ", ".join(plan.rebuild_image_fields))
    for items in plan.schedule.values():
        for s in items:
            if s.refresh:
                lines.append(f"  every step, before '{s.term.name}': " + ", ".join(s.refresh))
    if plan.absent:
        lines += [
            "",
            "Not in this plan (not compiled, allocated, exchanged or run): " + ", ".join(plan.absent),
        ]
    return "\n".join(lines)
