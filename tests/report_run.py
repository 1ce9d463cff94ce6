"""One small real `scoursph report` run shared by tests/test_report.py and
tests/test_report_browser.py (a session-scoped fixture in tests/conftest.py would be the
alternative; this module keeps the report's tests in their own files).

Cases: the still-water tank at H/dx = 10 with a study at 10 and 20 (the real solver, a few
seconds), and the synthetic cases of tests/report_fakes.py (passing with extra figures and a
table, failing, raising, killed by SIGSEGV). A previous night is seeded in the history so that
one synthetic metric moved by more than a quarter of its tolerance, and a benchmark summary
with one regressed benchmark is passed, so the page carries every kind of problem."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CASES = {
    "small_hydro": "report_fakes:SmallHydrostatic",
    "synthetic": "report_fakes:Synthetic",
    "failing": "report_fakes:Failing",
    "known": "report_fakes:KnownFailing",
    "raising": "report_fakes:Raising",
    "segfault": "report_fakes:Segfault",
}
EXPECTED_CHECKS = 3 + 2 + 2 + 2  # still water, synthetic, failing, known; the crashed cases have none

BENCH = {
    "date": "2026-01-01T00:00:00+00:00",
    "host": "test",
    "load_1min": 1.0,
    "wall_s": 60.0,
    "baseline_source": "synthetic",
    "benchmarks": [
        {
            "name": "water_step",
            "what": "synthetic",
            "value": 0.011,
            "unit": "s",
            "calibration_s": 0.01,
            "ratio": 1.1,
            "baseline_ratio": 1.0,
            "threshold": 0.05,
            "change": 0.1,
            "regressed": True,
        },
        {
            "name": "soil_step",
            "what": "synthetic",
            "value": 0.02,
            "unit": "s",
            "calibration_s": 0.01,
            "ratio": 2.0,
            "baseline_ratio": 2.0,
            "threshold": 0.05,
            "change": 0.0,
            "regressed": False,
        },
        {
            "name": "two_phase_step",
            "skipped": "skipped: two-phase coupling not built yet",
            "regressed": False,
        },
    ],
    "regressed": ["water_step"],
}


@dataclass
class ReportRun:
    root: Path
    page: Path
    history: Path
    results: dict
    returncode: int
    output: str


def make_report_run(tmp: Path) -> ReportRun:
    root = tmp / "nightly"
    hist = tmp / "history.jsonl"
    previous = {
        "date": "2026-01-01T00:00:00+00:00",
        "commit": "0" * 40,
        "metrics": {
            "synthetic :: first synthetic metric": {"value": 0.5, "tolerance": 1.0, "passed": True},
            "synthetic :: second synthetic metric": {"value": 0.2, "tolerance": 1.0, "passed": True},
        },
        "benchmarks": {
            "water_step": {"ratio": 1.0, "baseline_ratio": 1.0, "threshold": 0.05, "regressed": False}
        },
    }
    hist.write_text(json.dumps(previous) + "\n")
    bench = tmp / "bench.json"
    bench.write_text(json.dumps(BENCH))
    cmd = [
        sys.executable,
        "-m",
        "scoursph",
        "report",
        "--out",
        str(root),
        "--history",
        str(hist),
        "--bench-json",
        str(bench),
        "--cases",
        ",".join(CASES),
        "--timeout",
        "1800",
        "--cpu-limit",
        "300",
    ]
    for name, spec in CASES.items():
        cmd += ["--case", f"{name}={spec}"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")])}
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, timeout=3600)
    pages = sorted(p for p in root.glob("*/index.html") if p.parent.name != "latest")
    assert pages, proc.stdout + proc.stderr
    return ReportRun(
        root,
        pages[-1],
        hist,
        json.loads((pages[-1].parent / "results.json").read_text()),
        proc.returncode,
        proc.stdout + proc.stderr,
    )


_shared: ReportRun | None = None


def shared_report_run(tmp_path_factory) -> ReportRun:
    """The run, made once per test session."""
    global _shared
    if _shared is None:
        _shared = make_report_run(tmp_path_factory.mktemp("report"))
    return _shared
