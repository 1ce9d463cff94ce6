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
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np

from . import __version__
from .errors import BlowUpError
from .output.atomic import atomic_write_text
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

    def __init__(self, end_time, enabled):
        self.enabled = enabled
        self.end_time = end_time
        self.last = 0.0
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
        rate = sim.step_count / max(now - self.t0, 1e-9)
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


def run_scene(scene: Scene, out_dir, comm=None, quiet=False, write=True, overwrite=False) -> RunResult:
    """Run a scene; with `write`, into out_dir (refused with RunDirError, before any set-up,
    if it is not empty and not an earlier run, or is an earlier run and not `overwrite`)."""
    comm = comm or SerialCommunicator()
    out_dir = Path(out_dir)
    mode = "overwrite" if overwrite else "new"
    if write:  # refused before any work: writes nothing
        _on_root(lambda: check(out_dir, mode), out_dir, comm)
    sim = Simulation(scene, comm=comm)
    if write:
        _on_root(lambda: claim(out_dir, scene.scene.name, mode), out_dir, comm)
    threads = numba.get_num_threads()
    writers = []
    names = requested_fields(scene, sim.particles)
    arrays = [OUTPUT_TO_ARRAY[n] for n in names if n != "rank"]
    if write and comm.is_root():
        scene_text = scene_to_toml(scene)
        atomic_write_text(out_dir / "scene.toml", scene_text)
        meta = run_metadata(scene, comm, threads)
        writers.append(Hdf5Series(out_dir, meta, scene_text))
        if scene.output.vtk:
            writers.append(VtkSeries(out_dir))
    last = {}

    def snapshot():
        sim.current_state()
        data = comm.gather_owned(sim.particles, arrays)
        if comm.is_root():
            fields = {n: data[OUTPUT_TO_ARRAY[n] if n != "rank" else "rank"] for n in names}
            last.clear()
            last.update(fields)
            for w in writers:
                w.write(sim.t, sim.step_count, fields)

    progress = Progress(scene.scene.end_time, enabled=not quiet and comm.is_root())
    status = "completed"
    t0 = time.perf_counter()
    try:
        for t_out in scene.output_times():
            sim.advance_to(t_out, on_step=progress)
            snapshot()
    except BlowUpError as exc:
        status = f"blew up: {exc}"
        raise
    except Exception as exc:  # MPI: a failure on one rank ends every rank now (no hang in a collective)
        comm.fail(exc)
        raise
    finally:
        progress.close(sim)
        wall = time.perf_counter() - t0
        n = comm.sum(sim.particles.n_owned)
        rate = sim.step_count * n / wall if wall > 0 else 0.0
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
        if write and comm.is_root():
            for w in writers:
                if isinstance(w, Hdf5Series):
                    w.finish(**summary)
            atomic_write_text(out_dir / "run.json", json.dumps(summary, indent=2) + "\n")
            if scene.output.render and last:
                render_snapshot(
                    last,
                    out_dir / "final.png",
                    scalar=scene.output.render_field,
                    title=f"{scene.scene.name}  t = {sim.t:.4f} s",
                    domain=(scene.domain.min, scene.domain.max),
                )
    return RunResult(out_dir, status, wall, sim.step_count, n, rate, sim)
