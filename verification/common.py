"""What every verification case shares: checks with sourced tolerances, timed runs,
reference data, and the resolution-study table (error and wall time side by side)."""

from __future__ import annotations

import csv
import math
import os
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from reference_cases.mesh_convergence import GCI_SAFETY as GCI_SAFETY
from reference_cases.mesh_convergence import richardson as richardson
from solver.scene import SCENES_DIR, parse_scene
from solver.simulation import Simulation

# Package data: every path is found from a module's own location, so an installed package
# (a wheel, not the repository) finds the same files (pyproject.toml [tool.setuptools.package-data]).
DATA = Path(__file__).with_name("data")
SCENES = SCENES_DIR
RESULTS = Path(__file__).with_name("results")


def reference_case_dir(name):
    """reference_cases/<name> (its manifest.json and data/), shipped with the package."""
    import reference_cases

    return Path(reference_cases.__file__).resolve().parent / name


@dataclass
class Check:
    metric: str
    value: float
    tolerance: float
    source: str  # where the tolerance comes from
    passed: bool = field(init=False)

    def __post_init__(self):
        self.passed = bool(np.isfinite(self.value) and abs(self.value) <= self.tolerance)

    def line(self):
        mark = "PASS" if self.passed else "FAIL"
        return f"  [{mark}] {self.metric}: {self.value:.4g} (tolerance {self.tolerance:.4g}; {self.source})"


@dataclass
class CaseResult:
    case: str
    resolution: int
    particles: int
    steps: int
    wall_time: float
    series: dict  # observables over time
    checks: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    figure: Path | None = None
    cpu_time: float | None = None  # CPU s of the stepping (all threads of the process), beside wall_time
    # optional extras for the nightly report (docs/nightly_report.md): more figures, and tables
    # as {"title": str, "header": [str], "rows": [[value]]}
    extra_figures: list[Path] = field(default_factory=list)
    tables: list[dict] = field(default_factory=list)

    @property
    def passed(self):
        return all(c.passed for c in self.checks)


def scene_from_file(name, **overrides):
    """A scene file from scenes/ with some keys replaced (dotted 'table.key' -> value)."""
    raw = tomllib.loads((SCENES / name).read_text())
    for dotted, value in overrides.items():
        table = raw
        *parents, key = dotted.split(".")
        for p in parents:
            table = table.setdefault(p, {})
        table[key] = value
    return parse_scene(raw, SCENES / name)


class Stopwatch:
    """Wall time and CPU time since it was made. CPU time is time.process_time(): every thread
    of this process, so a Numba run on 2 threads counts both; on a loaded host the wall time
    grows with the load while the CPU time of a single-threaded run barely does."""

    def __init__(self):
        self.wall0, self.cpu0 = time.perf_counter(), time.process_time()

    def read(self):
        """(wall s, CPU s) so far."""
        return time.perf_counter() - self.wall0, time.process_time() - self.cpu0


class TimedRun(NamedTuple):
    sim: Simulation
    samples: list
    wall: float  # s of stepping and observing, set-up and first-step compile excluded
    cpu: float  # CPU s over the same span (Stopwatch)


def timed_run(scene, sample_times, observe):
    """Run a scene in memory, calling observe(sim) at each sample time.

    Returns a TimedRun: the Simulation, the observations, and the wall and CPU time excluding
    set-up and the compile of the first step, so that resolutions compare by their stepping cost."""
    sim = Simulation(scene)
    sim.step()  # compiles every kernel (cached on disk after the first process)
    clock = Stopwatch()
    out = []
    for t in sample_times:
        if t > sim.t:
            sim.advance_to(t)
        sim.current_state()
        out.append(observe(sim))
    wall, cpu = clock.read()
    return TimedRun(sim, out, wall, cpu)


def timed_samples(scene, sample_times, observe):
    """(Simulation, observations, wall time): timed_run without the CPU time (kept for callers)."""
    return tuple(timed_run(scene, sample_times, observe)[:3])


def read_csv(name):
    """Rows of a reference CSV (comment lines starting with # skipped) as dicts."""
    with open(DATA / name) as fh:
        lines = [ln for ln in fh if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def rms(a):
    a = np.asarray(a, float)
    return float(np.sqrt(np.mean(a * a)))


def write_study_table(path, header, rows):
    """Markdown table of a resolution study (error and wall time side by side)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in rows:
        lines.append("| " + " | ".join(f"{v:.4g}" if isinstance(v, float) else str(v) for v in r) + " |")
    path.write_text("\n".join(lines) + "\n")
    return path


def write_csv(path, rows, fields=None):
    """Rows (dicts) as a CSV file with a header (fields: the column order; default the first row's keys)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(fields or rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def save_study(rows, out_dir, stem, note=None):
    """A resolution study's rows (dicts) as OUT/stem.csv (read back by the checks) and stem.md
    (`note`, e.g. how the times were taken and the machine load, above the table)."""
    out = Path(out_dir)
    write_csv(out / f"{stem}.csv", rows)
    write_study_table(out / f"{stem}.md", list(rows[0]), [list(r.values()) for r in rows])
    if note:
        md = out / f"{stem}.md"
        md.write_text(note.rstrip() + "\n\n" + md.read_text())
    return rows


def timing_note(reproduce):
    """How a study's times were taken, for the line above its table: CPU time beside wall time,
    threads, and the machine load (wall times compare only at similar load; CPU times of a
    one-thread run survive a loaded host much better)."""
    return (
        "Times: stepping only (set-up and compile excluded), one process, "
        f"NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}; wall time and CPU time "
        "(time.process_time, all threads) side by side; load_1min is the 1-minute load average "
        f"after each run; {machine_load()}.\nReproduce: `{reproduce}`"
    )


def load_1min():
    return os.getloadavg()[0]


def study_row(path, resolution):
    """The row of a committed study CSV for one resolution (strings), or None."""
    path = Path(path)
    if not path.exists():
        return None
    with open(path) as fh:
        rows = {int(r["resolution"]): r for r in csv.DictReader(fh)}
    return rows.get(resolution)


def machine_load():
    """How busy the machine was when a study was timed: its wall times are comparable only at
    similar load (1-minute load average over the cores)."""
    load = os.getloadavg()[0]
    return f"{os.cpu_count()}-core machine, 1-min load average {load:.2f} when the table was written"


def save_figure(fig, path, dpi=120):
    import matplotlib.pyplot as plt

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def script_parser(module):
    """The argument parser of `python -m verification.MODULE`, its description the docstring's
    first line: every verification script answers --help and refuses what it does not know (exit 2)."""
    import argparse

    name = getattr(module.__spec__, "name", None) or module.__name__
    doc = (module.__doc__ or "").strip().splitlines()
    return argparse.ArgumentParser(prog=f"python -m {name}", description=doc[0] if doc else None)


def case_main(module, argv=None, out_dir="runs/verification"):
    """`python -m verification.CASE [RESOLUTION] [--study]`: one run at RESOLUTION (the case's
    DEFAULT_RESOLUTION when omitted), or its resolution study. Exit 0 when every check passes, 1 when
    one fails, 2 on bad arguments (argparse: the argument and the reason on stderr)."""
    import sys

    parser = script_parser(module)
    parser.add_argument(
        "resolution", nargs="?", type=int, default=module.DEFAULT_RESOLUTION,
        help=f"particles across the case's reference length (default {module.DEFAULT_RESOLUTION}; "
        f"its study: {', '.join(map(str, getattr(module, 'STUDY_RESOLUTIONS', ()))) or 'see the module'})",
    )  # fmt: skip
    if hasattr(module, "study"):
        parser.add_argument("--study", action="store_true", help="run the resolution study")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.resolution <= 0:
        parser.error(f"argument resolution: must be a positive integer, not {args.resolution}")
    if getattr(args, "study", False):
        rows = module.study()
        for row in rows:
            print(row)
        failures = study_failures(rows)
        for failure in failures:
            print("  FAIL:", failure)
        return 1 if failures else 0
    return report(module.run(args.resolution, out_dir=out_dir))


def study_failures(rows):
    """What is wrong with a resolution study's rows: none at all, or a non-finite number
    (an error or a wall time that is NaN or inf means a run that did not produce a result)."""
    if not rows:
        return ["the study produced no rows"]
    out = []
    for row in rows:
        for key, value in row.items():
            if isinstance(value, (int, float)) and not isinstance(value, bool) and not math.isfinite(value):
                out.append(f"resolution {row.get('resolution', '?')}: {key} = {value}")
    return out


def report(res):
    """Print a case's size, checks and notes; exit status 0 only if every check passed."""
    print(f"{res.particles} particles, {res.steps} steps, {res.wall_time:.1f} s")
    for check in res.checks:
        print(check.line())
    for note in res.notes:
        print("  note:", note)
    return 0 if res.passed else 1
