"""Checkpoints: the whole state of a run in one HDF5 file, from which it continues bit for bit.

    RUN/checkpoints/NNNNNNNNN.h5         NNNNNNNNN = the step number
      attrs: format, format_version, solver_version, t, step, ranks, particles, created
      /meta/scene, /meta/state           the merged scene and the state below (JSON texts)
      /particles/<field>                 every particle field of every owned particle (half-step
                                         values, rates, stresses, plastic strain, x_ref, ids,
                                         ...), sorted by global id
      /layout/rank, /layout/row          where each particle was: its rank and its row there
      /decomposition/lo, hi, region_lo, region_hi    the MPI cuts (MPI runs only)
    state = {"shared": the step loop's scalars (t, step count, dt_prev, dt_first, the dt limit's
             name, rebuild count, settling record, gravity),
             "ranks": per rank: wall reflections, deepest penetration, next particle id,
             "terms": per rank: each stateful term's Term.state(),
             "run": the output position (snapshots and VTK files written so far), the next
             simulated-time checkpoint, the run segments so far, the run's metadata, extras}

One file, gathered on the root in global-id order (one field at a time, so the root holds at
most one field of the whole set on top of its own share): it restarts on any rank count, and
h5py reads it like a snapshot. A checkpoint is written to a temporary name, synced and renamed
(output/atomic.py), so a run killed while writing one (even by SIGKILL) leaves the previous
one intact; the leftover temporary file is removed when the run is continued.

A restart (`scoursph run SCENE --restart RUN[/checkpoints/NNNNNNNNN.h5]`) reads the newest
readable checkpoint (or the named one), refuses a scene that differs from the checkpoint's
except in scene.end_time, scene.description, output.* and parallel.* (exit 2, naming the
key), puts the particles back (on the same rank count each rank gets its own rows in their
order and the cuts; on another, every rank reads the set and the first rebuild cuts it) and
lets the Simulation replay its last neighbour rebuild (simulation.py `_resume`). The output
series are cut back to what had been written when the checkpoint was taken, and continue.
"""

from __future__ import annotations

import datetime
import json
import os
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np

from .. import __version__
from ..particles import ParticleSet
from .atomic import commit, partial_path
from .run_dir import MARKER

FORMAT = "scoursph-checkpoint"
FORMAT_VERSION = 1
FOLDER = "checkpoints"
NAME = re.compile(r"(\d{9})\.h5")
# keys of the merged scene a restart may change: they do not touch the state (end_time and the
# output schedule decide where the run stops and lands its steps from now on; parallel.* only
# the MPI cuts, a round-off matter like the rank count)
CHANGEABLE = ("scene.end_time", "scene.description", "output", "parallel")
# test hook (tests/test_restart.py): "K:SECONDS" pauses for SECONDS inside the K-th checkpoint
# this process writes, after the particle data and before the rename
PAUSE_ENV = "SCOURSPH_TEST_CHECKPOINT_PAUSE"


class CheckpointError(Exception):
    """A restart that cannot be done: names the path and the reason (exit status 2)."""

    def __init__(self, path, reason):
        self.path, self.reason = str(path), reason
        super().__init__(f"{path}: {reason}")


def checkpoint_path(run_dir, step) -> Path:
    return Path(run_dir) / FOLDER / f"{int(step):09d}.h5"


def list_checkpoints(run_dir) -> list[Path]:
    """The checkpoint files of a run directory, oldest first (by step)."""
    folder = Path(run_dir) / FOLDER
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.iterdir() if p.is_file() and NAME.fullmatch(p.name))


# -- JSON with exact floats ---------------------------------------------------------------------
def _plain(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"cannot write {type(o).__name__} into a checkpoint")


def to_json(value) -> str:
    """JSON text; floats are written by repr, which reads back to the same double (inf, nan too)."""
    return json.dumps(value, default=_plain)


# -- writing ------------------------------------------------------------------------------------
class CheckpointWriteError(Exception):
    """The root could not write a checkpoint (disk full, ...): raised on every rank."""


_writes = 0  # checkpoints written by this process (the test hook counts them)


class _RootWriter:
    """The root's side of a checkpoint write: a temporary file, renamed when complete. A failure
    is recorded (error), never raised, so the root keeps taking part in the gathers."""

    def __init__(self, path):
        self.path = Path(path)
        self.tmp = partial_path(self.path)
        self.error = None
        self.f = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.f = h5py.File(self.tmp, "w")
        except OSError as exc:
            self._fail(exc)

    def put(self, name, data):
        if self.error is None:
            try:
                self.f.create_dataset(name, data=data)
            except (OSError, ValueError, TypeError) as exc:
                self._fail(exc)

    def finish(self, attrs):
        if self.error is not None:
            return
        try:
            for k, v in attrs.items():
                self.f.attrs[k] = v
            _test_pause()
            self.f.close()
            self.f = None
            commit(self.tmp, self.path)  # fsync, rename over the final name, fsync the folder
        except (OSError, ValueError, TypeError) as exc:
            self._fail(exc)

    def _fail(self, exc):
        self.error = f"cannot write {self.path}: {getattr(exc, 'strerror', None) or exc}"
        if self.f is not None:
            try:
                self.f.close()
            except Exception:  # noqa: BLE001 - already failing; the temporary file goes next
                pass
            self.f = None
        if self.tmp.exists():
            self.tmp.unlink()


def write_checkpoint(run_dir, sim, comm, scene_json, run_state) -> Path:
    """Collective: gather every owned particle field on the root, in global-id order, and write
    RUN/checkpoints/<step>.h5 atomically with the step loop's state (Simulation.saved_state),
    the cuts and `run_state`. Returns the path on every rank; CheckpointWriteError on every
    rank if the root could not write it. Reads the state, never changes it."""
    ps = sim.particles
    n = ps.n_owned
    saved = sim.saved_state()
    per_rank = comm.gather({"rank": saved["rank"], "terms": saved["terms"], "n": n})
    ids = comm.gather(ps.owned("id").copy())
    path = checkpoint_path(run_dir, sim.step_count)
    writer = _RootWriter(path) if comm.is_root() else None
    if writer is not None:
        counts = [p["n"] for p in per_rank]
        order = np.argsort(np.concatenate(ids), kind="stable")
        writer.put("layout/rank", np.repeat(np.arange(len(counts), dtype=np.int32), counts)[order])
        writer.put("layout/row", np.concatenate([np.arange(c, dtype=np.int64) for c in counts])[order])
    for name in sorted(ps.arrays):  # one field at a time: the root holds one of the whole set
        parts = comm.gather(ps.owned(name).copy())
        if writer is not None:
            writer.put(f"particles/{name}", np.concatenate(parts)[order])
    if writer is not None:
        cuts = comm.decomposition_state()
        for k, v in (cuts or {}).items():
            writer.put(f"decomposition/{k}", np.asarray(v))
        state = {
            "shared": saved["shared"],
            "ranks": [p["rank"] for p in per_rank],
            "terms": [p["terms"] for p in per_rank],
            "run": run_state,
        }
        # datasets, not attributes: an attribute holds at most 64 KiB, and the run's record grows
        writer.put("meta/scene", scene_json)
        writer.put("meta/state", to_json(state))
        writer.finish(
            {
                "format": FORMAT,
                "format_version": FORMAT_VERSION,
                "solver_version": __version__,
                "t": float(sim.t),
                "step": int(sim.step_count),
                "ranks": int(comm.size),
                "particles": int(len(order)),
                "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            }
        )
    error = comm.bcast(writer.error if writer is not None else None)
    if error is not None:
        raise CheckpointWriteError(error)
    return path


def _test_pause():
    global _writes
    _writes += 1
    spec = os.environ.get(PAUSE_ENV)
    if not spec:
        return
    which, _, seconds = spec.partition(":")
    if int(which) == _writes:
        sys.stderr.write(f"scoursph: test hook: paused inside checkpoint write {_writes}\n")
        sys.stderr.flush()
        time.sleep(float(seconds))


# -- reading ------------------------------------------------------------------------------------
def read_header(path) -> dict:
    """The attributes of a checkpoint file, checked; CheckpointError if it is not a readable one."""
    path = Path(path)
    try:
        with h5py.File(path, "r") as f:
            attrs = dict(f.attrs)
            if attrs.get("format") != FORMAT:
                raise CheckpointError(path, "is not a ScourSPH checkpoint")
            if int(attrs.get("format_version", -1)) != FORMAT_VERSION:
                raise CheckpointError(
                    path,
                    f"has checkpoint format {attrs.get('format_version')}, this solver reads "
                    f"{FORMAT_VERSION}",
                )
            if "particles" not in f or "layout" not in f or "meta" not in f:
                raise CheckpointError(path, "is incomplete (no particle data)")
            texts = {k: f["meta"][k][()] for k in ("scene", "state") if k in f["meta"]}
    except OSError as exc:
        raise CheckpointError(path, f"cannot be read as HDF5 ({exc})") from None
    try:
        for k in ("scene", "state"):
            text = texts[k]
            attrs[k] = json.loads(text.decode() if isinstance(text, bytes) else text)
        for key in ("t", "step", "ranks"):
            float(attrs[key])
    except (KeyError, TypeError, ValueError) as exc:
        raise CheckpointError(path, f"has a damaged header ({type(exc).__name__}: {exc})") from None
    return attrs


def find_checkpoint(arg, name=None) -> tuple[Path, Path, list[str]]:
    """(run directory, checkpoint file, warnings) for `--restart ARG [--checkpoint NAME]`: the run
    directory's newest readable checkpoint (unreadable newer ones are named in the warnings), or
    the one NAME gives (a file name in its checkpoints/ folder, or a step number). ARG may also
    be a checkpoint file inside a run directory's checkpoints/ folder."""
    path = Path(arg)
    if path.is_file():
        run_dir = path.parent.parent
        if path.parent.name != FOLDER or not NAME.fullmatch(path.name) or not (run_dir / MARKER).is_file():
            raise CheckpointError(path, f"is not a checkpoint in a run directory's {FOLDER}/ folder")
        if name is not None:
            raise CheckpointError(path, "is a checkpoint file already: --checkpoint needs a run directory")
        read_header(path)
        return run_dir, path, []
    if not path.is_dir():
        raise CheckpointError(path, "no such run directory")
    if not (path / MARKER).is_file():
        raise CheckpointError(path, f"is not a ScourSPH run directory (no {MARKER} marker)")
    found = list_checkpoints(path)
    if name is not None:
        chosen = path / FOLDER / _file_name(name)
        if chosen not in found:
            have = ", ".join(p.name for p in found) or "none"
            raise CheckpointError(chosen, f"no such checkpoint (--checkpoint {name}; the run has: {have})")
        read_header(chosen)
        return path, chosen, []
    if not found:
        raise CheckpointError(
            path,
            f"holds no checkpoint ({FOLDER}/ is empty or missing: the run stopped before its first one; "
            "output.checkpoint_interval and output.checkpoint_wall_interval set how often they are written)",
        )
    warnings = []
    for candidate in reversed(found):
        try:
            read_header(candidate)
        except CheckpointError as exc:
            warnings.append(f"skipped unreadable checkpoint {candidate}: {exc.reason}")
            continue
        return path, candidate, warnings
    raise CheckpointError(path, "none of its checkpoints is readable: " + "; ".join(warnings))


def _file_name(name) -> str:
    """A checkpoint's file name from --checkpoint: 000001234.h5, 000001234 or 1234."""
    text = str(name).strip()
    stem = text[:-3] if text.endswith(".h5") else text
    return f"{int(stem):09d}.h5" if stem.isdigit() else text


def scene_differences(old, new, prefix="") -> list[tuple[str, object, object]]:
    """(dotted key, checkpoint value, scene value) where two merged scenes (model_dump JSON) differ."""
    out = []
    if isinstance(old, dict) and isinstance(new, dict):
        for k in list(old) + [k for k in new if k not in old]:
            out += scene_differences(old.get(k), new.get(k), f"{prefix}{k}.")
        return out
    if isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        for i, (a, b) in enumerate(zip(old, new)):
            out += scene_differences(a, b, f"{prefix[:-1]}[{i}].")
        return out
    return [] if old == new else [(prefix[:-1], old, new)]


def upgrade_scene(old: dict, new: dict) -> dict:
    """The checkpoint's merged scene as this version would write it. Checkpoints written before
    outlets had a kind (2026-12-02) deleted on entry: their outlets are kind "delete", and their
    missing [outlet_defaults] is taken as the new scene's (a default table, whose effect is each
    outlet's kind, compared itself)."""
    old = dict(old)
    if "outlet_defaults" not in old and "outlet_defaults" in new:
        old["outlet_defaults"] = new["outlet_defaults"]
        old["outlets"] = [dict(o, kind=o.get("kind", "delete")) for o in old.get("outlets", [])]
    return old


def check_scene(path, header, scene_json) -> None:
    """CheckpointError naming the first key where the scene differs from the checkpoint's in
    a way a restart may not change, or an end time before the checkpoint's time."""
    new = json.loads(scene_json)
    diffs = [
        d
        for d in scene_differences(upgrade_scene(header["scene"], new), new)
        if not any(d[0] == c or d[0].startswith(c + ".") for c in CHANGEABLE)
    ]
    if diffs:
        key, a, b = diffs[0]
        more = f" (and {len(diffs) - 1} more key(s))" if len(diffs) > 1 else ""
        raise CheckpointError(
            path,
            f"the scene differs from the checkpoint's at {key}: {_short(a)} in the checkpoint, {_short(b)} "
            f"now{more}; a restart may change only scene.end_time, scene.description, output.* and "
            "parallel.*",
        )
    t = float(header["t"])
    end = float(new["scene"]["end_time"])
    if end < t:
        raise CheckpointError(path, f"scene.end_time = {end:g} s is before the checkpoint's t = {t:.6g} s")


def _short(v):
    text = json.dumps(v)
    return text if len(text) <= 60 else text[:57] + "..."


def open_restart(arg, scene, scene_json, comm, name=None):
    """(run directory, Resume) for `--restart ARG [--checkpoint NAME]`, on every rank: the root finds
    the checkpoint and checks the scene against it; a CheckpointError is raised on every rank alike."""
    from ..plan import build_plan

    found, error = None, None
    if comm.is_root():
        try:
            run_dir, path, warnings = find_checkpoint(arg, name)
            header = read_header(path)
            check_scene(path, header, scene_json)
            found = (str(run_dir), str(path), header)
            for w in warnings:
                sys.stderr.write(f"scoursph: warning: {w}\n")
        except CheckpointError as exc:
            error = (exc.path, exc.reason)
    found, error = comm.bcast((found, error))
    if error is not None:
        raise CheckpointError(*error)
    run_dir, path, header = found
    plan = build_plan(scene)
    resume = None
    try:
        resume = load_resume(path, header, plan, comm)
        error = None
    except CheckpointError as exc:
        error = (exc.path, exc.reason)
    errors = [e for e in comm.allgather(error) if e is not None]
    if errors:
        raise CheckpointError(*errors[0])
    resume.plan = plan
    return Path(run_dir), resume


def resume_outputs(run_dir, resume) -> dict:
    """Root: cut the run directory back to the checkpoint (snapshot and VTK files written after
    it, later checkpoints, leftover temporary files), and the series to continue
    ({"snapshots": [...], "vtk": [...]} for the writers)."""
    outputs = resume.run["outputs"]
    truncate_outputs(run_dir, len(outputs["snapshots"]), len(outputs["vtk"]))
    later = remove_later_checkpoints(run_dir, resume.step)
    if later:
        sys.stderr.write(
            f"scoursph: continuing from {resume.path.name}: removed {len(later)} later checkpoint(s) of the "
            "run it replaces\n"
        )
    return {"snapshots": outputs["snapshots"], "vtk": outputs["vtk"]}


@dataclass
class Resume:
    """What a Simulation needs to continue (simulation.py `_resume`), for this rank."""

    path: Path
    particles: ParticleSet
    shared: dict
    rank_state: dict
    terms: dict
    decomposition: dict | None
    run: dict
    ranks_before: int
    t: float
    step: int
    extras: dict = field(default_factory=dict)
    plan: object = None


def load_resume(path, header, plan, comm) -> Resume:
    """This rank's part of a checkpoint (collective only in what the caller does around it).

    Same rank count: this rank's rows in their order, its own diagnostics and term states, the
    cuts. Another rank count: every particle (in global-id order) on every rank, to be cut by
    the first rebuild; diagnostics summed (wall reflections, on rank 0) or the largest taken
    (deepest penetration, next id); term states through Term.regroup_state."""
    path = Path(path)
    state = header["state"]
    before = int(header["ranks"])
    same = before == comm.size
    with h5py.File(path, "r") as f:
        stored = set(f["particles"])
        wanted = set(plan.fields)
        if stored != wanted:
            missing, extra = sorted(wanted - stored), sorted(stored - wanted)
            raise CheckpointError(
                path,
                "holds other particle fields than this scene's plan "
                + (f"(missing: {', '.join(missing)}) " if missing else "")
                + (f"(not in the plan: {', '.join(extra)}) " if extra else "")
                + f"(written by ScourSPH {header.get('solver_version')})",
            )
        if same:
            rank, row = f["layout/rank"][:], f["layout/row"][:]
            sel = np.flatnonzero(rank == comm.rank)
            sel = sel[np.argsort(row[sel], kind="stable")]
        else:
            sel = slice(None)
        data = {}
        for name, spec in plan.fields.items():
            a = f["particles"][name][:][sel]
            shape = (a.shape[0],) if spec.components == 0 else (a.shape[0], spec.components)
            if a.dtype != np.dtype(spec.dtype) or a.shape != shape:
                raise CheckpointError(
                    path, f"field '{name}' has dtype {a.dtype} and shape {a.shape[1:]}, not the plan's"
                )
            data[name] = a
        cuts = None
        if same and "decomposition" in f:
            cuts = {k: f["decomposition"][k][:] for k in f["decomposition"]}
    n = len(data["id"])
    ps = ParticleSet(plan.dim, plan.fields, capacity=int(n * 1.3) + 64)
    if n:
        ps.append_owned(**data)
    ranks = state["ranks"]
    term_states = state["terms"]
    if same:
        mine = ranks[comm.rank]
        terms = term_states[comm.rank]
    else:
        mine = {
            "wall_reflections": sum(int(r["wall_reflections"]) for r in ranks) if comm.is_root() else 0,
            "deepest_penetration": max(float(r["deepest_penetration"]) for r in ranks),
            "next_id": max(int(r["next_id"]) for r in ranks),
        }
        terms = {}
        for term in plan.terms:
            shares = [s.get(term.name) for s in term_states]
            if all(s is None for s in shares):
                continue
            try:
                terms[term.name] = term.regroup_state(shares, comm.size)[comm.rank]
            except ValueError as exc:
                raise CheckpointError(path, str(exc)) from None
    known = {t.name for t in plan.terms}
    unknown = sorted({k for s in term_states for k in s} - known)
    if unknown:
        raise CheckpointError(
            path, f"holds the state of term(s) not in this scene's plan: {', '.join(unknown)}"
        )
    return Resume(
        path=path,
        particles=ps,
        shared=state["shared"],
        rank_state=mine,
        terms=terms,
        decomposition=cuts,
        run=state["run"],
        ranks_before=before,
        t=float(header["t"]),
        step=int(header["step"]),
        extras=state["run"].get("extras", {}),
    )


# -- continuing the run directory -----------------------------------------------------------------
def truncate_outputs(run_dir, n_snapshots, n_vtk) -> list[Path]:
    """Remove the snapshot and VTK files numbered from n_snapshots / n_vtk on (written after the
    checkpoint, they are written again) and leftover temporary files; the removed paths."""
    run_dir = Path(run_dir)
    removed = []
    for sub, pattern, keep in (("snapshots", r"(\d{6})\.h5", n_snapshots), ("vtk", r"(\d{6})\.vtp", n_vtk)):
        folder = run_dir / sub
        if not folder.is_dir():
            continue
        for p in folder.iterdir():
            m = re.fullmatch(pattern, p.name)
            if (m and int(m.group(1)) >= keep) or re.fullmatch(r"\..+\.partial\.[A-Za-z0-9]+", p.name):
                p.unlink()
                removed.append(p)
    folder = run_dir / FOLDER
    if folder.is_dir():
        for p in folder.iterdir():
            if re.fullmatch(r"\..+\.partial\.h5", p.name):
                p.unlink()
                removed.append(p)
    return removed


def remove_later_checkpoints(run_dir, step) -> list[Path]:
    """Checkpoints after `step` belong to the continuation being replaced: removed."""
    later = [p for p in list_checkpoints(run_dir) if int(NAME.fullmatch(p.name).group(1)) > step]
    for p in later:
        p.unlink()
    return later


def prune(run_dir, keep) -> list[Path]:
    """Keep the newest `keep` checkpoints; the removed paths."""
    old = list_checkpoints(run_dir)[:-keep] if keep > 0 else []
    for p in old:
        p.unlink()
    return old


# -- when to write --------------------------------------------------------------------------------
class Checkpointer:
    """When to write a checkpoint, and writing it: every `output.checkpoint_interval` simulated
    seconds (after the first step that reaches each multiple), every
    `output.checkpoint_wall_interval` wall-clock seconds (the root's clock), at the end of the
    run (`output.checkpoint_at_end`), and when SIGINT or SIGTERM arrived (`stops`, then
    Interrupted is raised). `after_step` is collective: one reduction per step under MPI
    carries the signal and the root's clock, so every rank decides alike. Writing a checkpoint
    reads the state, never changes it: a run with checkpoints is the run without them."""

    def __init__(self, out, run_dir, comm, scene_json, run_state, stops=None, enabled=True, t=0.0):
        self.out = out  # scene.output
        self.run_dir = Path(run_dir)
        self.comm = comm
        self.scene_json = scene_json
        self.run_state = run_state  # () -> dict of the run's own state (outputs written, segments)
        self.stops = stops
        self.enabled = enabled
        self.interval = float(out.checkpoint_interval)
        self.wall_interval = float(out.checkpoint_wall_interval)
        self.k = 0  # the next simulated-time checkpoint is due at k * interval (> t; from t on a restart)
        if self.interval > 0:
            self.k = int(np.floor(t / self.interval)) + 1
            self._advance(t)
        self.wall_last = time.monotonic()
        self.last_step = None
        self.last_path = None
        self.written = 0
        self.failures = []

    def after_step(self, sim):
        """Collective, after each step (and after the snapshot of a step that landed on an
        output time): write a checkpoint if one is due; after a stop signal, write one and raise
        Interrupted."""
        from ..interrupt import Interrupted

        signum = self.stops.pending if self.stops is not None else 0
        wall_due = (
            self.enabled
            and self.comm.is_root()
            and self.wall_interval > 0
            and time.monotonic() - self.wall_last >= self.wall_interval
        )
        code = self.comm.max(2 * int(signum) + int(wall_due))  # a signal outranks the clock
        signum, wall_due = code // 2, bool(code % 2)
        sim_due = self.enabled and self.interval > 0 and sim.t >= self.k * self.interval * (1 - 1e-12)
        if signum:
            path, error = None, None
            if self.enabled:
                try:
                    path = self.write(sim, reason=f"interrupted by {_signame(signum)}")
                except CheckpointWriteError as exc:
                    error = str(exc)
            raise Interrupted(signum, sim.t, sim.step_count, path, error)
        if sim_due or wall_due:
            self._write_or_warn(sim, "checkpointed")

    def at_end(self, sim):
        if self.enabled and self.out.checkpoint_at_end and self.last_step != sim.step_count:
            self._write_or_warn(sim, "completed")

    def _write_or_warn(self, sim, reason):
        try:
            self.write(sim, reason)
        except CheckpointWriteError as exc:  # a full disk must not end a week-long run: say it, go on
            self.failures.append(str(exc))
            if self.comm.is_root():
                sys.stderr.write(f"scoursph: warning: checkpoint not written: {exc}\n")

    def _advance(self, t):
        while self.k * self.interval <= t * (1 + 1e-12):
            self.k += 1

    def write(self, sim, reason):
        if self.interval > 0:
            self._advance(sim.t)
        self.wall_last = time.monotonic()
        run_state = self.run_state(sim, reason)
        path = write_checkpoint(self.run_dir, sim, self.comm, self.scene_json, run_state)
        self.last_step, self.last_path = sim.step_count, path
        self.written += 1
        if self.comm.is_root():
            prune(self.run_dir, int(self.out.checkpoint_keep))
        return path


def _signame(signum):
    import signal

    return signal.Signals(signum).name
