"""One verification case in its own process, for the nightly report:

    python -m verification.nightly.run_case NAME MODULE OUT [--resolution R]
                                           [--study R1 R2 ... | --no-study] [--quick]

imports MODULE, runs `run(resolution, out_dir)` (resolution: --resolution, else the module's
NIGHTLY_RESOLUTION, else DEFAULT_RESOLUTION), then `study(resolutions, out_dir=OUT/study)`
(resolutions: --study, else NIGHTLY_STUDY_RESOLUTIONS, else STUDY_RESOLUTIONS; none with
--no-study or without a study()). --quick: the smallest study resolution, no study.
Writes OUT/case.json: checks, notes, figures, extra tables, study rows, and the wall and CPU
time measured here around each part (time.perf_counter, time.process_time: every thread of
this process). An exception in run() or study() is recorded with its traceback; the other
part still runs. The process exits 0 whenever case.json was written: the verdict is in it.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import os
import sys
import traceback
from pathlib import Path

from verification.common import Stopwatch


def jsonable(v):
    """Numbers, strings, lists and dicts as JSON can hold them (NaN and inf as strings)."""
    if isinstance(v, dict):
        return {str(k): jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [jsonable(x) for x in v]
    if isinstance(v, Path):
        return str(v)
    if hasattr(v, "item") and getattr(v, "ndim", 1) == 0:  # numpy scalar
        v = v.item()
    if isinstance(v, bool) or v is None or isinstance(v, (int, str)):
        return v
    if isinstance(v, float):
        return v if math.isfinite(v) else repr(v)
    return str(v)


def _rel(path, out):
    path = Path(path)
    try:
        return str(path.resolve().relative_to(out.resolve()))
    except ValueError:
        return str(path)


def load_case(spec):
    """A case module by its dotted name, or an object in it as 'module:attribute' (any object
    with the module attributes of docs/nightly_report.md, e.g. a class of test doubles)."""
    module, _, attr = spec.partition(":")
    obj = importlib.import_module(module)
    return getattr(obj, attr) if attr else obj


def run_part(record, key, fn):
    """Call fn(); record its wall and CPU time under record[key], or its traceback."""
    clock = Stopwatch()
    try:
        value = fn()
        error = None
    except BaseException as exc:  # noqa: BLE001 - a case's failure must not stop the report
        if isinstance(exc, KeyboardInterrupt):
            raise
        value, error = None, traceback.format_exc()
    wall, cpu = clock.read()
    record[key] = {"process_wall_s": wall, "process_cpu_s": cpu, "error": error}
    return value


def plan(mod, resolution=None, study=None, no_study=False, quick=False):
    """(resolution, study resolutions or None) for a case module (docs/nightly_report.md)."""
    study_default = getattr(mod, "NIGHTLY_STUDY_RESOLUTIONS", getattr(mod, "STUDY_RESOLUTIONS", None))
    if quick:
        smallest = getattr(mod, "QUICK_RESOLUTION", min(study_default) if study_default else None)
        return resolution or smallest or getattr(mod, "DEFAULT_RESOLUTION", None), None
    if resolution is None:
        resolution = getattr(mod, "NIGHTLY_RESOLUTION", getattr(mod, "DEFAULT_RESOLUTION", None))
    if no_study or not hasattr(mod, "study"):
        return resolution, None
    return resolution, (tuple(study) if study else (tuple(study_default) if study_default else None))


def case_record(name, module_name, out, resolution=None, study=None, no_study=False, quick=False):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    record = {"case": name, "module": module_name, "pid": os.getpid()}
    mod = run_part(record, "import", lambda: load_case(module_name))
    if mod is None:
        return record
    resolution, study = plan(mod, resolution, study, no_study, quick)
    full = getattr(mod, "STUDY_RESOLUTIONS", None)
    record["plan"] = {
        "resolution": resolution,
        "study": list(study) if study else None,
        "full_study": list(full) if full and hasattr(mod, "study") else None,
        "note": getattr(mod, "NIGHTLY_NOTE", ""),
    }
    res = run_part(
        record,
        "run",
        lambda: mod.run(resolution, out_dir=out) if resolution is not None else mod.run(out_dir=out),
    )
    known = dict(getattr(mod, "KNOWN_FAILURES", {}))  # metric -> why it is expected to fail
    if res is not None:
        record["run"].update(
            resolution=res.resolution,
            particles=res.particles,
            steps=res.steps,
            wall_time_s=res.wall_time,
            cpu_time_s=res.cpu_time,
            checks=[
                {
                    "metric": c.metric,
                    "value": c.value,
                    "tolerance": c.tolerance,
                    "source": c.source,
                    "passed": c.passed,
                    "known_failure": known.get(c.metric),
                }
                for c in res.checks
            ],
            notes=list(res.notes),
            figures=[_rel(f, out) for f in [res.figure, *res.extra_figures] if f],
            tables=list(res.tables),
        )
    if study:
        study_dir = out / "study"
        rows = run_part(record, "study", lambda: mod.study(tuple(study), out_dir=study_dir))
        record["study"].update(
            resolutions=list(study),
            rows=list(rows or []),
            accuracy_columns=dict(getattr(mod, "ACCURACY_COLUMNS", {})),
        )
    if hasattr(mod, "reference_costs"):
        record["reference_costs"] = run_part(record, "reference_costs_timing", mod.reference_costs) or []
    return record


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name")
    ap.add_argument("module")
    ap.add_argument("out", type=Path)
    ap.add_argument("--resolution", type=int)
    ap.add_argument("--study", type=int, nargs="+", help="study resolutions (default: the module's)")
    ap.add_argument("--no-study", action="store_true")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    record = case_record(
        args.name, args.module, args.out, args.resolution, args.study, args.no_study, args.quick
    )
    path = args.out / "case.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(jsonable(record), indent=1))
    tmp.replace(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
