"""Command-line options of `scoursph report` (kept free of heavy imports: scoursph/cli.py
builds its parser from here)."""

from __future__ import annotations

from pathlib import Path


def add_arguments(p):
    p.add_argument(
        "--out",
        type=Path,
        default=Path("runs/nightly"),
        help="results root: the page goes to OUT/<date>/, OUT/latest points to it (default runs/nightly)",
    )
    p.add_argument(
        "--history", type=Path, help="history file, one JSON line per night (default OUT/history.jsonl)"
    )
    p.add_argument(
        "--bench-json", type=Path, help="the benchmark gate's summary (benchmarks/gate.py check --json)"
    )
    p.add_argument(
        "--cases",
        help="comma-separated subset of the cases (default: every case in verification/registry.py)",
    )
    p.add_argument(
        "--case",
        action="append",
        default=[],
        metavar="NAME=MODULE",
        help="add a case module to the registry for this report (repeatable; used by the tests)",
    )
    p.add_argument("--no-study", action="store_true", help="skip the resolution studies")
    p.add_argument(
        "--quick",
        action="store_true",
        help="each case once at its smallest study resolution, no study: a smoke test of the page",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=6 * 3600.0,
        help="wall seconds one case (run and study) may take before it is killed as hung (default 21600: "
        "on a shared host a case can get a few percent of a core for an hour)",
    )
    p.add_argument(
        "--cpu-limit",
        type=float,
        default=3600.0,
        help="CPU seconds one case may use before it is killed as runaway (RLIMIT_CPU; default 3600)",
    )
    p.add_argument(
        "--case-threads",
        type=int,
        default=1,
        help="Numba threads per case process (default 1: CPU and wall time then compare with the studies)",
    )
    p.add_argument(
        "--jobs",
        type=int,
        default=2,
        help="cases run side by side, one thread each (default 2: this machine's cores; 1 runs them "
        "one after the other)",
    )
    p.add_argument("--no-history", action="store_true", help="do not append tonight to the history file")
    return p
