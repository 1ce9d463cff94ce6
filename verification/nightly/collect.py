"""Run every case of the nightly in its own process, one after the other.

A case that raises, segfaults, runs out of memory, passes its CPU-time limit (RLIMIT_CPU: a
runaway case, whatever the load) or its wall-time timeout (a case that hangs) is recorded as
crashed (with the end of its log) and the next case starts. The wall timeout is generous: on
this shared host a case can get 1-10 % of a core for an hour while other jobs run. The parent
measures each child's wall time and CPU time (resource.getrusage of the waited child: the
whole process, imports and compile included) and the 1-minute load before and after, beside
the child's own timings.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def unexpected(check):
    """A check that failed without being a known failure, or a known failure that passed (like a
    strict xfail: the case's KNOWN_FAILURES entry must then go)."""
    return check["passed"] == bool(check.get("known_failure"))


def status(record):
    """'passed', 'failed' (a check failed unexpectedly, a known failure passed, or the study
    raised) or 'crashed' (no result)."""
    if record.get("crash") or record.get("import", {}).get("error") or record.get("run", {}).get("error"):
        return "crashed"
    checks = record.get("run", {}).get("checks", [])
    if any(unexpected(c) for c in checks) or record.get("study", {}).get("error"):
        return "failed"
    return "passed"


def _limit_cpu(seconds):
    def apply():
        resource.setrlimit(resource.RLIMIT_CPU, (int(seconds), int(seconds) + 10))

    return apply


def _ended(returncode):
    if returncode < 0:
        try:
            return f"killed by {signal.Signals(-returncode).name}" + (
                " (its CPU-time limit)" if -returncode == signal.SIGXCPU else ""
            )
        except ValueError:
            return f"killed by signal {-returncode}"
    return f"process exited with status {returncode}"


def run_case(name, module, out_dir, timeout, threads=1, flags=(), cpu_limit=None):
    """Run one case in a child process; return its record (see run_case.py) with the parent's
    timings under 'process' and a 'status'."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    case_json = out_dir / "case.json"
    case_json.unlink(missing_ok=True)
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])])
    # -X faulthandler: a case that dies of a signal leaves its Python stack in the log
    cmd = [
        sys.executable,
        "-X",
        "faulthandler",
        "-m",
        "verification.nightly.run_case",
        name,
        module,
        str(out_dir),
    ]
    cmd += list(flags)
    load_before, cpu_before, start = os.getloadavg()[0], _children_cpu(), time.perf_counter()
    crash = None
    with open(out_dir / "log.txt", "w") as log:
        try:
            proc = subprocess.run(
                cmd,
                stdout=log,
                stderr=subprocess.STDOUT,
                env=env,
                timeout=timeout,
                cwd=ROOT,
                preexec_fn=_limit_cpu(cpu_limit) if cpu_limit else None,
            )
            if proc.returncode != 0:
                crash = _ended(proc.returncode)
        except subprocess.TimeoutExpired:
            crash = f"timed out after {timeout:.0f} s of wall time (killed)"
    wall, cpu = time.perf_counter() - start, _children_cpu() - cpu_before
    record = json.loads(case_json.read_text()) if case_json.exists() else {"case": name, "module": module}
    if crash or not case_json.exists():
        record["crash"] = (crash or "no case.json written") + "; end of log:\n" + _tail(out_dir / "log.txt")
    record["process"] = {
        "wall_s": wall,
        "cpu_s": cpu,
        "load_1min_before": load_before,
        "load_1min_after": os.getloadavg()[0],
        "numba_threads": threads,
        "cpu_limit_s": cpu_limit,
        "timeout_s": timeout,
        "command": " ".join(cmd),
    }
    record["status"] = status(record)
    return record


def _tail(path, lines=40):
    try:
        return "\n".join(Path(path).read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return ""


def run_all(cases, out_dir, timeout, threads=1, flags=(), progress=print, cpu_limit=None):
    """{name: record} for {name: module} in order."""
    records = {}
    for name, module in cases.items():
        progress(f"report: {name} ({module}) ...")
        rec = run_case(name, module, Path(out_dir) / name, timeout, threads, flags, cpu_limit)
        p = rec["process"]
        progress(
            f"report: {name}: {rec['status']} in {p['wall_s']:.0f} s wall, {p['cpu_s']:.0f} s CPU "
            f"(load {p['load_1min_before']:.2f} -> {p['load_1min_after']:.2f})"
        )
        records[name] = rec
    return records
