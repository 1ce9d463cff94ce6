"""The nightly history: one JSON line per night, and what counts as a regression.

A line holds the commit, date, host, the 1-minute load, every case's status, every metric's
value and tolerance, and every benchmark's speed ratio (benchmarks/gate.py). Tonight is
flagged against the previous line:
  * a metric that moved by more than a quarter of its tolerance since the previous night
    (a change that large is no round-off: the code or its data changed what the case gives);
  * a benchmark whose speed ratio is past the gate (the gate's own verdict, against the
    committed baseline, not against last night: a slow drift would pass night-to-night checks);
  * a case that passed last night and fails or crashes tonight is already a failure.
"""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
from datetime import datetime, timezone
from pathlib import Path

MOVE_FRACTION = 0.25  # of the tolerance (issue 12)


def git(*args, cwd=None):
    try:
        return subprocess.run(
            ["git", *args], capture_output=True, text=True, cwd=cwd, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return ""


def machine(cwd=None):
    """Commit, date, host and load of tonight's run."""
    return {
        "commit": git("rev-parse", "HEAD", cwd=cwd) or "unknown",
        "dirty": bool(git("status", "--porcelain", "--untracked-files=no", cwd=cwd)),
        "branch": git("rev-parse", "--abbrev-ref", "HEAD", cwd=cwd),
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "host": socket.gethostname(),
        "cpus": os.cpu_count(),
        "load_1min": os.getloadavg()[0],
    }


def metric_key(case, metric):
    return f"{case} :: {metric}"


def entry(meta, records, bench=None, wall_s=None):
    metrics = {}
    for name, rec in records.items():
        for c in rec.get("run", {}).get("checks", []):
            metrics[metric_key(name, c["metric"])] = {
                "value": c["value"],
                "tolerance": c["tolerance"],
                "passed": c["passed"],
            }
    benchmarks = {}
    for b in (bench or {}).get("benchmarks", []):
        benchmarks[b["name"]] = {k: b.get(k) for k in ("ratio", "baseline_ratio", "threshold", "regressed")}
        if "change" in b.get("reference_build", {}):  # the verdict of the side-by-side measurement
            benchmarks[b["name"]]["reference_build"] = b["reference_build"]
    return {
        **meta,
        "nightly_wall_s": wall_s,
        "cases": {name: rec["status"] for name, rec in records.items()},
        # what each case cost tonight: the next night starts the costliest first
        "case_cpu_s": {name: rec.get("process", {}).get("cpu_s") for name, rec in records.items()},
        "metrics": metrics,
        "benchmarks": benchmarks,
    }


def load(path):
    """The history's lines in order (a corrupt line is skipped, not fatal)."""
    path = Path(path)
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return out


def append(path, line):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a") as fh:
        fh.write(json.dumps(line) + "\n")


def _number(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def flags(tonight, previous):
    """Regression flags of tonight's entry against the previous night's (or None)."""
    out = []
    prev_metrics = (previous or {}).get("metrics", {})
    for key, m in tonight["metrics"].items():
        if key not in prev_metrics:
            continue
        v, v0, tol = _number(m["value"]), _number(prev_metrics[key]["value"]), _number(m["tolerance"])
        if math.isfinite(v) != math.isfinite(v0):
            moved = True
        elif not math.isfinite(v):
            moved = False
        else:
            moved = abs(v - v0) > MOVE_FRACTION * abs(tol) if math.isfinite(tol) else False
        if moved:
            out.append(
                {
                    "kind": "metric moved",
                    "what": key,
                    "why": f"{v0:.4g} -> {v:.4g}: moved {abs(v - v0):.3g}, more than a quarter of its "
                    f"tolerance {tol:.4g} ({MOVE_FRACTION * abs(tol):.3g}) since {previous.get('date', '?')} "
                    f"(commit {str(previous.get('commit', '?'))[:10]})",
                }
            )
    for name, b in tonight["benchmarks"].items():
        if b.get("regressed"):
            ref = b.get("reference_build")
            why = (
                f"{ref['change']:+.1%} against the build of {ref['commit'][:10]} timed side by side, "
                f"past the gate of +{ref['threshold']:.1%}"
                if ref
                else f"speed ratio {b['ratio']:.4g} against baseline {b['baseline_ratio']:.4g}: "
                f"{b['ratio'] / b['baseline_ratio'] - 1:+.1%}, past the gate of +{b['threshold']:.1%}"
            )
            out.append({"kind": "speed regression", "what": name, "why": why})
    return out
