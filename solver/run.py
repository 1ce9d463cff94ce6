"""Run a scene: set up, step to each output time, write snapshots, report.

The output directory is checked before anything is computed and claimed (created, marked as
a ScourSPH run) only after the scene has been validated and the solver set up, so bad input
never leaves a half-made run behind. A run never deletes what it did not write
(solver/output/run_dir.py).
"""

from __future__ import annotations

import datetime
import json
import platform
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from . import __version__
from .errors import BlowUpError
from .interrupt import Interrupted, StopSignals, exit_status
from .materials import Phase
from .output.atomic import atomic_write_text
from .output.balance import VolumeLedger
from .output.checkpoint import Checkpointer, open_restart, resume_outputs
from .output.fields import OUTPUT_TO_ARRAY, requested_fields
from .output.hdf5_writer import Hdf5Series
from .output.render import render_snapshot
from .output.run_dir import RunDirError, check, claim
from .output.vtk_writer import VtkSeries
from .parallel.communicator import SerialCommunicator
from .scene import Scene, scene_to_toml
from .simulation import Simulation


@dataclass
class RunResult:
    out_dir: Path
    status: str  # "completed" or "blew up: ..."
    wall_time: float
    steps: int
    particles: int
    particle_steps_per_second: float
    sim: Simulation


class Progress:
    """Simulated time, steps/s and ETA; updated a few times a second, never per step."""

    def __init__(self, end_time, enabled, first_step=0):
        self.enabled = enabled
        self.end_time = end_time
        self.last = 0.0
        self.first_step = first_step  # a restart counts its steps/s from its own first step
        if enabled:
            from rich.progress import BarColumn, TextColumn, TimeRemainingColumn
            from rich.progress import Progress as RichProgress

            self.bar = RichProgress(
                TextColumn("[bold]t = {task.fields[t]:.4f} / {task.total:.4f} s"),
                BarColumn(),
                TextColumn(
                    "{task.fields[rate]:8.1f} steps/s  dt = {task.fields[dt]:.2e} ({task.fields[limit]})"
                ),
                TimeRemainingColumn(),
                transient=False,
            )
            self.task = self.bar.add_task("run", total=end_time, t=0.0, rate=0.0, dt=0.0, limit="")
            self.bar.start()
            self.t0 = time.perf_counter()

    def __call__(self, sim):
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.last < 0.25:
            return
        self.last = now
        rate = (sim.step_count - self.first_step) / max(now - self.t0, 1e-9)
        self.bar.update(self.task, completed=sim.t, t=sim.t, rate=rate, dt=sim.dt_prev, limit=sim.dt_limit)

    def close(self, sim):
        if self.enabled:
            self.bar.update(self.task, completed=sim.t, t=sim.t)
            self.bar.stop()


def run_metadata(scene: Scene, comm, threads):
    return {
        "solver": "ScourSPH",
        "solver_version": __version__,
        "scene_name": scene.scene.name,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "numba": numba.__version__,
        "host": platform.node(),
        "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(sys.argv),
        "mpi_ranks": comm.size,
        "threads_per_rank": threads,
    }


def reflection_warning(count):
    """The end-of-run warning when the drift's safeguard had to reflect particles at a wall
    (issue 15: the walls should hold the water by themselves; the count is a diagnostic)."""
    return (
        f"scoursph: warning: {count} specular wall reflection(s): the drift's safeguard put particles "
        "back inside the walls (wall_reflections in run.json); the wall model did not hold them by itself"
    )


def _on_root(action, out_dir, comm):
    """action() on the root rank; its RunDirError raised on every rank (no rank left waiting)."""
    reason = None
    if comm.is_root():
        try:
            action()
        except RunDirError as exc:
            reason = exc.reason
    reason = comm.bcast(reason)
    if reason is not None:
        raise RunDirError(out_dir, reason)


def run_scene(
    scene: Scene, out_dir, comm=None, quiet=False, write=True, overwrite=False, restart=None, checkpoint=None
) -> RunResult:
    """Run a scene; with `write`, into out_dir (refused with RunDirError, before any set-up,
    if it is not empty and not an earlier run, or is an earlier run and not `overwrite`).
    `restart`: a run directory to continue from, at its newest checkpoint or the one `checkpoint`
    names (output/checkpoint.py; CheckpointError if it cannot be, before anything is written);
    out_dir is then that run's. SIGINT and SIGTERM, from the start (a signal during the set-up
    is acted on after the first step), end the run with a checkpoint: Interrupted (interrupt.py)."""
    comm = comm or SerialCommunicator()
    second = None
    if comm.size > 1:  # a second signal ends every rank at once (some may wait in a collective)

        def second(signum):
            name = signal.Signals(signum).name
            comm.abort(f"stopped at once by a second {name}: no checkpoint written", exit_status(signum))

    with StopSignals(announce=comm.is_root(), on_second=second) as stops:
        return _run_scene(scene, out_dir, comm, quiet, write, overwrite, restart, checkpoint, stops)


def _run_scene(scene, out_dir, comm, quiet, write, overwrite, restart, checkpoint, stops) -> RunResult:
    scene_json = json.dumps(scene.model_dump(mode="json"))
    resume = None
    if restart is not None:
        out_dir, resume = open_restart(
            restart, scene, scene_json, comm, checkpoint
        )  # the checkpoint, this rank's part
    out_dir = Path(out_dir)
    mode = "continue" if resume else "overwrite" if overwrite else "new"
    if write:  # refused before any work: writes nothing
        _on_root(lambda: check(out_dir, mode), out_dir, comm)
    if resume is not None:
        sim = Simulation(scene, comm=comm, plan=resume.plan, particles=resume.particles, resume=resume)
    else:
        sim = Simulation(scene, comm=comm)
    if write:
        _on_root(lambda: claim(out_dir, scene.scene.name, mode), out_dir, comm)
    threads = numba.get_num_threads()
    writers = []
    names = requested_fields(scene, sim.particles)
    arrays = [OUTPUT_TO_ARRAY[n] for n in names if n != "rank"]
    meta = resume.run["metadata"] if resume else run_metadata(scene, comm, threads)
    segments = list(resume.run["segments"]) if resume else []
    if write and comm.is_root():
        outputs = resume_outputs(out_dir, resume) if resume else {"snapshots": None, "vtk": None}
        scene_text = scene_to_toml(scene)
        atomic_write_text(out_dir / "scene.toml", scene_text)
        writers.append(Hdf5Series(out_dir, meta, scene_text, snapshots=outputs["snapshots"]))
        if scene.output.vtk:
            writers.append(VtkSeries(out_dir, entries=outputs["vtk"]))
    last = {}
    segment = {  # this run's part of the run directory's history (run.json "segments")
        "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "command": " ".join(sys.argv),
        "mpi_ranks": comm.size,
        "threads_per_rank": threads,
        "from_checkpoint": str(resume.path.relative_to(out_dir)) if resume else None,
        "t_start": sim.t,
        "step_start": sim.step_count,
    }

    def run_state(sim, status):
        """The run's own state for a checkpoint: outputs written, history, metadata."""
        done = dict(segment, t_end=sim.t, step_end=sim.step_count, wall_time_s=time.perf_counter() - t0)
        done["status"] = status
        series = {type(w).__name__: w for w in writers}
        return {
            "outputs": {
                "snapshots": series["Hdf5Series"].snapshots if "Hdf5Series" in series else [],
                "vtk": series["VtkSeries"].entries if "VtkSeries" in series else [],
            },
            "segments": segments + [done],
            "metadata": meta,
            "volume_stored0": None if ledger.stored0 is None else ledger.stored0.tolist(),
        }

    def snapshot():
        sim.current_state()
        data = comm.gather_owned(sim.particles, arrays)
        if comm.is_root():
            fields = {n: data[OUTPUT_TO_ARRAY[n] if n != "rank" else "rank"] for n in names}
            last.clear()
            last.update(fields)
            for w in writers:
                w.write(sim.t, sim.step_count, fields)

    # inflow/outflow/stored and body leaks (output/balance.py); a restart keeps the run's stored(0)
    ledger = VolumeLedger(sim, comm, stored0=resume.run.get("volume_stored0") if resume else None)
    progress = Progress(scene.scene.end_time, enabled=not quiet and comm.is_root(), first_step=sim.step_count)
    checkpoints = Checkpointer(
        scene.output, out_dir, comm, scene_json, run_state, stops=stops, enabled=write, t=sim.t
    )
    times = scene.output_times()
    if resume is not None:  # what was written before the checkpoint stays; the rest is redone
        times = [t for t in times if sim.t < t * (1 - 1e-12)]
    target = [0.0]

    def on_step(sim):
        progress(sim)
        if sim.t < target[0] * (1 - 1e-12):  # a step landing on an output time waits for its snapshot
            checkpoints.after_step(sim)

    status = "completed"
    t0 = time.perf_counter()
    try:
        for t_out in times:
            target[0] = t_out
            sim.advance_to(t_out, on_step=on_step)
            snapshot()
            checkpoints.after_step(sim)
        checkpoints.at_end(sim)
    except BlowUpError as exc:
        status = f"blew up: {exc}"
        raise
    except Interrupted as exc:  # every rank stopped after the same step (a collective decision)
        status = f"interrupted by {exc.signame} at t = {exc.t:.6g} s (step {exc.step})"
        raise
    except Exception as exc:  # MPI: a failure on one rank ends every rank now (no hang in a collective)
        comm.fail(exc)
        raise
    finally:
        progress.close(sim)
        wall = time.perf_counter() - t0
        n = comm.sum(sim.particles.n_owned)
        rate = (sim.step_count - segment["step_start"]) * n / wall if wall > 0 else 0.0
        summary = {
            "status": status,
            "wall_time_s": wall,
            "steps": sim.step_count,
            "particles": n,
            "particle_steps_per_second": rate,
            "neighbour_rebuilds": sim.rebuilds,
            "wall_reflections": comm.sum(sim.wall_reflections),
            "simulated_time_s": sim.t,
        }
        # a restarted run: the totals above count from t = 0 (steps, rebuilds, reflections), wall
        # time and rate are this run's; each part of the history is in "segments"
        summary["checkpoints"] = {
            "written": checkpoints.written,
            "last": str(checkpoints.last_path) if checkpoints.last_path else None,
            "failed": checkpoints.failures,
        }
        summary["segments"] = run_state(sim, status)["segments"]
        summary["wall_time_total_s"] = sum(s["wall_time_s"] for s in summary["segments"])
        summary.update(ledger.report(sim, comm))
        if write and comm.is_root():
            for w in writers:
                if isinstance(w, Hdf5Series):
                    w.finish(**summary)
            atomic_write_text(out_dir / "run.json", json.dumps(summary, indent=2) + "\n")
            write_run_products(out_dir, scene, status)
            if scene.output.render and last and not status.startswith("interrupted"):  # be quick
                render_snapshot(
                    last,
                    out_dir / "final.png",
                    scalar=scene.output.render_field,
                    title=f"{scene.scene.name}  t = {sim.t:.4f} s",
                    domain=(scene.domain.min, scene.domain.max),
                    bodies=[b.vertices for b in scene.bodies],
                    material_names=sim.plan.materials.names,
                    water_ids=sim.plan.materials.ids_of_phase(Phase.WATER),
                )
        if comm.is_root() and summary["wall_reflections"] > 0:
            print(reflection_warning(summary["wall_reflections"]), file=sys.stderr)
    return RunResult(out_dir, status, wall, sim.step_count, n, rate, sim)


def write_run_products(out_dir, scene, status):
    """Products computed from the written series: the scour profile, depth and plot of a scene with
    soil, and its picture of the hole unless output.render is off or the run was interrupted (be
    quick) (solver/output/scour.py). A failure here is reported, never fatal to the run."""
    from .output.scour import write_scour_outputs

    try:
        write_scour_outputs(
            out_dir, scene, hole_picture=scene.output.render and not status.startswith("interrupted")
        )
    except Exception as exc:  # noqa: BLE001 - a post-processing failure must not hide the run's outcome
        print(f"scour measurement failed: {exc}", file=sys.stderr)
