"""Run every case of the nightly in its own process, `jobs` of them side by side (default 2,
one per core of this machine; each case runs on one thread, so two cases never share a core),
the costliest first (by the CPU time each took the previous night) so that the last case to
start is a short one.

A case that raises, segfaults, runs out of memory, passes its CPU-time limit (RLIMIT_CPU: a
runaway case, whatever the load) or its wall-time timeout (a case that hangs) is recorded as
crashed (with the end of its log) and the next case starts. The wall timeout is generous: on
this shared host a case can get 1-10 % of a core for an hour while other jobs run. The parent
measures each child's wall time and CPU time (resource.getrusage of the waited child: the
whole process, imports and compile included) and the 1-minute load before and after, beside
the child's own timings. The CPU time is exact per child even when cases run side by side:
the child is reaped with os.wait4, whose resource usage is that child's and its descendants'.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


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
    load_before, start = os.getloadavg()[0], time.perf_counter()
    with open(out_dir / "log.txt", "w") as log:
        proc = subprocess.Popen(
            cmd,
            stdout=log,
            stderr=subprocess.STDOUT,
            env=env,
            cwd=ROOT,
            preexec_fn=_limit_cpu(cpu_limit) if cpu_limit else None,
        )
        returncode, cpu, timed_out = _wait(proc, timeout)
    wall = time.perf_counter() - start
    crash = None
    if timed_out:
        crash = f"timed out after {timeout:.0f} s of wall time (killed)"
    elif returncode != 0:
        crash = _ended(returncode)
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


def _wait(proc, timeout):
    """(exit code, CPU seconds of the child and its descendants, timed out?) once proc ends; a
    timer kills it after `timeout` wall seconds. os.wait4 reaps this one child, so its CPU time
    is its own, not that of a case running beside it."""
    fired = threading.Event()

    def kill():
        fired.set()
        proc.kill()

    timer = threading.Timer(timeout, kill)
    timer.start()
    try:
        _, status, usage = os.wait4(proc.pid, 0)
    finally:
        timer.cancel()
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait again
    return proc.returncode, usage.ru_utime + usage.ru_stime, fired.is_set()


def _tail(path, lines=40):
    try:
        return "\n".join(Path(path).read_text(errors="replace").splitlines()[-lines:])
    except OSError:
        return ""


def run_all(cases, out_dir, timeout, threads=1, flags=(), progress=print, cpu_limit=None, jobs=1, cost=None):
    """{name: record} for {name: module}, in the order of `cases`; `jobs` cases run at a time,
    the costliest first by `cost` ({name: CPU seconds}, e.g. the previous night's; an unknown
    case counts as the costliest, so a new case never starts last)."""
    cost = cost or {}
    order = sorted(cases, key=lambda n: -cost.get(n, float("inf")))
    lock = threading.Lock()

    def one(name):
        with lock:
            progress(f"report: {name} ({cases[name]}) ...")
        rec = run_case(name, cases[name], Path(out_dir) / name, timeout, threads, flags, cpu_limit)
        p = rec["process"]
        with lock:
            progress(
                f"report: {name}: {rec['status']} in {p['wall_s']:.0f} s wall, {p['cpu_s']:.0f} s CPU "
                f"(load {p['load_1min_before']:.2f} -> {p['load_1min_after']:.2f})"
            )
        return rec

    with ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        done = dict(zip(order, pool.map(one, order)))
    return {name: done[name] for name in cases}
