"""The benchmark regression gate (issue 12): `make bench-check`.

    python benchmarks/gate.py check [--json SUMMARY] [--baseline FILE]     exit 1 on a regression
    python benchmarks/gate.py baseline [--runs 10]                          write the baseline
    python benchmarks/gate.py repeat [--runs 10] [--slowdown 0.10]          the gate's own test
    python benchmarks/gate.py loo [--from-raw FILE]         each baseline run judged by the others
    python benchmarks/gate.py reference-baseline [--runs 10] [-k NAME] [--commit C]   side-by-side spread
    python benchmarks/gate.py repeat --side-by-side [--runs 10] [--slowdown 0.10]   its own test

`check` runs benchmarks/bench_gate.py under pytest-benchmark in PROCESSES processes, one after
the other, and keeps each benchmark's lowest ratio (its time / the calibration kernel's, measured
interleaved in the same run; see bench_gate.py and calibration.py). A benchmark regressed when
that ratio is more than `threshold` (relative) above the baseline's median ratio, and stays so
in RETRIES re-measurements of it alone (one process each; it keeps its lowest ratio).
The step benchmarks (water, soil, two-phase, rebuild), the 2-rank MPI step and the cold compile
are then timed against the baseline commit's own build, the two builds taking turns on the same
cores (reference_build.py, reference_mpi.py, reference_compile.py), and that comparison decides
their verdict: the host's slow phases move the calibration ratio by 15-25 % for minutes, but slow
both builds alike.

The threshold comes from the measured run-to-run spread of the ratio: `baseline` runs the
suite RUNS times on an unchanged build and stores, per benchmark, the ratios, their median and
MAD-based relative standard deviation (and the plain one and the largest deviation), and
threshold = MULTIPLE x the MAD-based spread, at least FLOOR (the floor is for a quantity with
almost no spread, the memory per particle) and at least the largest deviation of a baseline run;
`reference-baseline` measures the side-by-side timing's spread (the baseline build against
itself) and its thresholds the same way. `repeat` runs `check` RUNS times, optionally with
the controlled slowdown of benchmarks/slowdown.py, and tabulates the verdicts: an unchanged
build must pass every run, a 10 % slowdown must be caught; `loo` judges each baseline run by a
baseline of the others (docs/benchmarks.md has the figures).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import reference_build

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BASELINE = HERE / "baselines" / "gate.json"
RAW = ROOT / "runs" / "bench" / "baseline_runs.jsonl"
MULTIPLE = 4.0
FLOOR = 0.02
RETRIES = 2  # re-measurements of a benchmark past its threshold before it is flagged
# One measurement is the lowest ratio of PROCESSES runs of the suite, each in its own process, one
# after the other. The host has slow phases lasting minutes in which the memory-bound steps lose
# 15-20 % against the calibration kernel, which stays in cache (the 2026-12-01 18:08 baseline:
# water 1.37-1.43 in six runs, 1.59-1.65 in four). A single process per measurement put those
# phases into the baseline's spread (thresholds +9 to +10 %), and a 10 % slowdown measured +7 to
# +9 % against it was missed in 2 of 2 runs; the lower of two processes is in a slow phase only
# when both are, so the baseline's spread is that of the fast phase (docs/benchmarks.md).
PROCESSES = 2
# How a run's per-round times become one ratio (benchmark / calibration), by wall time
# (perf_counter) or CPU time (process_time): the medians' ratio, the fastest rounds' ratio
# (noise on a shared host only slows a round down), or the median of the per-round ratios
# (each round's benchmark against the calibration call just before it). `baseline` measures the
# run-to-run spread of each and keeps the estimator with the smallest spread over the timed
# benchmarks; the gate then uses that one (docs/benchmarks.md).
ESTIMATORS = ("wall", "cpu", "wall_min", "cpu_min", "wall_paired", "cpu_paired")
DEFAULT_ESTIMATOR = "cpu_min"
# every gate benchmark, as named in bench_gate.py (test_<name>)
GATE = (
    "water_step",
    "soil_step",
    "two_phase_step",
    "neighbour_rebuild",
    "mpi_two_rank_step",
    "cold_compile",
    "bytes_per_particle",
)


def cpu_model():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def git_commit():
    try:
        return subprocess.run(
            ["git", "rev-parse", "HEAD"], capture_output=True, text=True, cwd=ROOT
        ).stdout.strip()
    except OSError:
        return "unknown"


def run_suite(slowdown=None, select=None):
    """One pytest-benchmark run of bench_gate.py: {name: extra_info}, the skipped/failed names
    with reasons, the pytest exit status and the wall time."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", COLUMNS="400")
    env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
    if slowdown:
        env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "bench.json"
        cmd = [
            sys.executable,
            "-m",
            "pytest",
            str(HERE / "bench_gate.py"),
            "--benchmark-only",
            f"--benchmark-json={out}",
            "-o",
            "addopts=",
            "-o",
            "python_files=bench_*.py",
            "-p",
            "no:cacheprovider",
            "-v",
            "-rfE",
        ]
        if select:
            cmd += ["-k", select]
        start = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
        wall = time.perf_counter() - start
        data = json.loads(out.read_text()) if out.exists() else {"benchmarks": []}
    found = {b["name"].removeprefix("test_"): b["extra_info"] for b in data["benchmarks"]}
    missing = {}
    for name in GATE:
        if name in found or (select and select not in name):
            continue
        line = next((ln for ln in proc.stdout.splitlines() if f"::test_{name} " in ln), "")
        m = re.search(r"(SKIPPED|FAILED|ERROR)\s*(?:\((.*)\))?", line)
        reason = f"{m.group(1).lower()}: {m.group(2) or 'see the pytest output'}" if m else "did not run"
        missing[name] = reason
    return {
        "found": found,
        "missing": missing,
        "returncode": proc.returncode,
        "wall_s": wall,
        "output": proc.stdout[-4000:] + proc.stderr[-2000:],
    }


def measure(slowdown=None, select=None, processes=None):
    """One measurement: the suite run PROCESSES times (each its own pytest process); per
    benchmark the run with the lowest ratio (DEFAULT_ESTIMATOR) is kept. A benchmark missing from
    any run is reported missing."""
    runs = [run_suite(slowdown, select) for _ in range(processes or PROCESSES)]
    merged = {**runs[0], "found": {}, "missing": {}, "wall_s": sum(r["wall_s"] for r in runs)}
    for r in runs:
        merged["missing"].update(r["missing"])
        for name, info in r["found"].items():
            best = merged["found"].get(name)
            if best is None or ratio_of(info, DEFAULT_ESTIMATOR) < ratio_of(best, DEFAULT_ESTIMATOR):
                merged["found"][name] = info
    for name in merged["missing"]:
        merged["found"].pop(name, None)
    merged["returncode"] = max(r["returncode"] for r in runs)
    merged["output"] = "".join(r["output"] for r in runs)[-6000:]
    return merged


def ratios(info):
    """{estimator: ratio} of one benchmark's run (the size itself where no time is involved)."""
    r = info.get("rounds", {})
    if not r.get("cal_wall"):
        return dict.fromkeys(ESTIMATORS, info["value"])
    med = statistics.median
    out = {}
    for clock, (x, c) in {"wall": ("wall", "cal_wall"), "cpu": ("cpu", "cal_cpu")}.items():
        xs, cs = r[x], r[c]
        out[clock] = med(xs) / med(cs)
        out[f"{clock}_min"] = min(xs) / min(cs)
        out[f"{clock}_paired"] = (
            med(a / b for a, b in zip(xs, cs)) if len(xs) == len(cs) else med(xs) / med(cs)
        )
    return out


def ratio_of(info, estimator):
    return ratios(info)[estimator]


def compare(run, baseline, clock=DEFAULT_ESTIMATOR):
    """The gate's verdict per benchmark: the summary the nightly report reads."""
    base = (baseline or {}).get("benchmarks", {})
    rows = []
    for name in GATE:
        if name in run["missing"]:
            reason = run["missing"][name]
            skipped = reason.startswith("skipped")
            rows.append(
                {
                    "name": name,
                    "skipped": reason if skipped else None,
                    "error": None if skipped else reason,
                    "regressed": not skipped,
                }
            )
            continue
        if name not in run["found"]:
            continue
        info = run["found"][name]
        b = base.get(name, {}).get(clock)
        row = {
            "name": name,
            "what": info["what"],
            "clock": clock,
            "value": info["value"],
            "value_cpu": info.get("value_cpu"),
            "unit": info["unit"],
            "calibration_s": info.get("calibration_s"),
            "ratio": ratio_of(info, clock),
            "ratios": ratios(info),
            "load_1min": info.get("load_1min"),
            "slowdown": info.get("slowdown"),
            "baseline_ratio": b.get("median", b.get("mean")) if b else None,
            "threshold": b["threshold"] if b else None,
        }
        row["change"] = row["ratio"] / row["baseline_ratio"] - 1 if b else None
        row["regressed"] = bool(b) and row["change"] > row["threshold"]
        rows.append(row)
    return rows


def summary(run, baseline, baseline_path, clock=None):
    clock = clock or (baseline or {}).get("estimator", DEFAULT_ESTIMATOR)
    rows = compare(run, baseline, clock)
    return {
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "host": socket.gethostname(),
        "cpu": cpu_model(),
        "commit": git_commit(),
        "load_1min": os.getloadavg()[0],
        "wall_s": run["wall_s"],
        "baseline_source": (
            f"{baseline_path.relative_to(ROOT) if baseline_path.is_relative_to(ROOT) else baseline_path} "
            f"(commit {str(baseline.get('commit', '?'))[:10]}, {baseline.get('date', '?')}, host "
            f"{baseline.get('host', '?')}, {baseline.get('runs', '?')} runs)"
            if baseline
            else "none: no baseline file, nothing is gated"
        ),
        "same_cpu_as_baseline": bool(baseline) and baseline.get("cpu") == cpu_model(),
        "estimator": clock,
        "benchmarks": rows,
        "regressed": [r["name"] for r in rows if r["regressed"]],
    }


def print_summary(s):
    print(
        f"benchmark gate: {s['date']}, host {s['host']}, load {s['load_1min']:.2f}, {s['wall_s']:.0f} s; "
        f"baseline {s['baseline_source']}"
    )
    if s["benchmarks"] and not s["same_cpu_as_baseline"] and "none:" not in s["baseline_source"]:
        print("  warning: the baseline was measured on another CPU model; ratios may not compare")
    for r in s["benchmarks"]:
        if r.get("skipped"):
            print(f"  {r['name']:20s} {r['skipped']}")
        elif r.get("error"):
            print(f"  {r['name']:20s} FAILED TO RUN: {r['error']}")
        else:
            ch = f"{r['change']:+.1%} (gate +{r['threshold']:.1%})" if r["baseline_ratio"] else "no baseline"
            ref = r.get("reference_build")
            if ref and "change" in ref:
                ch += (
                    f"; against the build of {ref['commit'][:10]} side by side {ref['change']:+.1%} "
                    f"(gate +{ref['threshold']:.1%}), which decides"
                )
            elif ref:
                ch += f"; side by side not measured: {ref['error']}"
            print(
                f"  {r['name']:20s} {r['value']:.4g} {r['unit']}, ratio {r['ratio']:.4g}, {ch}"
                f"{'  REGRESSED' if r['regressed'] else ''}"
            )


def load_baseline(path):
    path = Path(path)
    return json.loads(path.read_text()) if path.exists() else None


def gated_run(baseline, baseline_path, slowdown=None, select=None, estimator=None):
    """One gate run, and up to RETRIES re-measurements of each benchmark past its threshold
    (that benchmark alone); a benchmark keeps its lowest ratio over the attempts, so it is
    flagged only if every attempt was past the threshold. Returns (summary, pytest output)."""
    run = measure(slowdown, select)
    s = summary(run, baseline, baseline_path, estimator)
    attempts = dict.fromkeys(run["found"], 1)
    reference = (baseline or {}).get("reference_build")
    side_by_side = set(reference["benchmarks"]) & set(run["found"]) if reference else set()
    for _ in range(RETRIES):
        again = [
            r["name"]
            for r in s["benchmarks"]
            if r["regressed"] and r["name"] in run["found"] and r["name"] not in side_by_side
        ]
        if not again:
            break
        for name in again:
            retry = measure(slowdown, name, processes=1)
            attempts[name] += 1
            if name in retry["found"] and ratio_of(retry["found"][name], s["estimator"]) < ratio_of(
                run["found"][name], s["estimator"]
            ):
                run["found"][name] = retry["found"][name]
            run["wall_s"] += retry["wall_s"]
        s = summary(run, baseline, baseline_path, estimator)
    for r in s["benchmarks"]:
        r["attempts"] = attempts.get(r["name"], 1)
    if side_by_side:
        against_reference_build(s, reference, side_by_side, slowdown)
    return s, run["output"]


def pairs_of(reference, name):
    """Process pairs per side-by-side measurement of a benchmark, as its thresholds were measured."""
    return reference["benchmarks"][name].get("pairs", reference.get("pairs"))


def against_reference_build(s, reference, names, slowdown=None):
    """The verdict of the step benchmarks, the MPI step and the cold compile: their time against the
    baseline commit's build, timed side by side (reference_build.py). The calibration ratio stays in
    the row for the trend; its own verdict is kept as `calibration_regressed`. If the baseline commit
    cannot be exported (a shallow clone), the calibration verdict stands and the row says why."""
    try:
        tree = reference_build.reference_tree(reference["commit"])
    except RuntimeError as err:
        for r in s["benchmarks"]:
            if r["name"] in names:
                r["reference_build"] = {"error": str(err)}
        return
    for r in s["benchmarks"]:
        if r["name"] not in names:
            continue
        m = reference_build.measurement(
            r["name"], tree, slowdown=slowdown, pairs=pairs_of(reference, r["name"])
        )
        gate = reference["benchmarks"][r["name"]]["threshold"]
        r["calibration_regressed"] = r["regressed"]
        r["reference_build"] = {
            "commit": reference["commit"],
            "pair_ratios": m["pair_ratios"],
            "change": m["ratio"] - 1,
            "threshold": gate,
        }
        r["regressed"] = m["ratio"] - 1 > gate
    s["regressed"] = [r["name"] for r in s["benchmarks"] if r["regressed"]]


def cmd_check(args):
    s, output = gated_run(
        load_baseline(args.baseline), Path(args.baseline), args.slowdown, args.k, args.estimator
    )
    print_summary(s)
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(s, indent=1))
    if s["regressed"]:
        print(f"benchmark gate: REGRESSION in {', '.join(s['regressed'])}")
        if any(r.get("error") for r in s["benchmarks"]):
            print(output)
        return 1
    return 0


def spread(values):
    """Centre and spread of a benchmark's ratios over the baseline runs. The reference is the
    median and the spread the MAD-based standard deviation (1.4826 x median absolute deviation,
    relative): a run caught in one of the host's slow phases (every time on the machine 25-30 %
    longer for minutes) must not widen the gate for all the others; `check` re-measures before
    it flags (RETRIES), so such a phase does not raise a false alarm either."""
    med = statistics.median(values)
    mad = statistics.median(abs(v - med) for v in values)
    mean = statistics.fmean(values)
    std = statistics.stdev(values) if len(values) > 1 else 0.0
    return {
        "median": med,
        "mean": mean,
        "std_rel": std / mean,
        "mad_rel": 1.4826 * mad / med,
        "max_dev_rel": max(abs(v / med - 1) for v in values),
        "min": min(values),
        "max": max(values),
    }


def threshold_of(sp):
    """The gate of a benchmark from its baseline spread: MULTIPLE x the MAD-based spread, at least
    FLOOR, and never below the largest deviation an unchanged build showed among the baseline runs
    themselves (the memory per particle is bimodal, 385 or 396 bytes, 3 of 10 runs the larger:
    the MAD alone gave +2 %, which flagged an unchanged build at +2.8 % on 2026-12-02)."""
    return max(MULTIPLE * sp["mad_rel"], FLOOR, sp["max_dev_rel"])


def cmd_baseline(args):
    if args.from_raw:  # recompute from the raw rounds of earlier baseline runs
        runs = [json.loads(line) for line in Path(args.from_raw).read_text().splitlines() if line.strip()]
        args.runs = len(runs)
        return write_baseline(args, runs)
    runs = []
    for k in range(args.runs):
        run = measure()
        print(
            f"baseline run {k + 1}/{args.runs}: {run['wall_s']:.0f} s, load {os.getloadavg()[0]:.2f}; "
            + ", ".join(
                f"{n} {ratio_of(i, 'wall'):.4g} (CPU paired {ratio_of(i, 'cpu_paired'):.4g})"
                for n, i in run["found"].items()
            ),
            flush=True,
        )
        runs.append(
            {
                "load_1min": os.getloadavg()[0],
                "wall_s": run["wall_s"],
                "processes": PROCESSES,
                "found": run["found"],
            }
        )
        RAW.parent.mkdir(parents=True, exist_ok=True)
        with open(RAW, "a") as fh:  # every run's raw rounds, kept outside the repository (runs/)
            fh.write(json.dumps(runs[-1]) + "\n")
    return write_baseline(args, runs)


def write_baseline(args, runs):
    benches = {}
    for name in GATE:
        infos = [r["found"][name] for r in runs if name in r["found"]]
        if len(infos) < 2:
            continue
        benches[name] = {
            "what": infos[0]["what"],
            "unit": infos[0]["unit"],
            "values": [i["value"] for i in infos],
        }
        for est in ESTIMATORS:
            values = [ratio_of(i, est) for i in infos]
            sp = spread(values)
            benches[name][est] = {"ratios": values, **sp, "threshold": threshold_of(sp)}
    timed = [n for n, b in benches.items() if b["unit"] == "s"]
    score = (
        {e: statistics.fmean(benches[n][e]["mad_rel"] for n in timed) for e in ESTIMATORS} if timed else {}
    )
    estimator = args.estimator or (min(score, key=score.get) if score else DEFAULT_ESTIMATOR)
    out = {
        "host": socket.gethostname(),
        "cpu": cpu_model(),
        "commit": git_commit(),
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "runs": args.runs,
        "loads_1min": [r["load_1min"] for r in runs],
        "run_wall_s": [r["wall_s"] for r in runs],
        "rule": f"a measurement = the lowest ratio of {PROCESSES} processes; "
        f"reference = median ratio over the runs; threshold = max({MULTIPLE:g} x MAD-based "
        f"relative standard deviation, {FLOOR:g}, largest deviation of a baseline run); a benchmark past "
        f"it is re-measured up to {RETRIES} "
        "times and flagged only if every attempt is past it",
        "estimator": estimator,
        "mean_mad_rel_by_estimator": score,
        "benchmarks": benches,
    }
    path = Path(args.baseline)
    previous = load_baseline(path) or {}
    if "reference_build" in previous:
        # the side-by-side spread belongs to the method and the host, not to a commit: it carries
        # over, now against the new baseline commit (re-measure with `reference-baseline`)
        out["reference_build"] = {**previous["reference_build"], "commit": out["commit"]}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(f"baseline written to {path}")
    print(
        f"estimator: {estimator} (mean MAD-based relative spread over the timed benchmarks: "
        + ", ".join(f"{e} {v:.2%}" for e, v in score.items())
        + ")"
    )
    for name, b in benches.items():
        for est in ESTIMATORS:
            c = b[est]
            print(
                f"  {name:20s} {est:12s} median {c['median']:.4g}, MAD-std {c['mad_rel']:.2%}, std "
                f"{c['std_rel']:.2%}, max deviation {c['max_dev_rel']:.2%}, threshold +{c['threshold']:.1%}"
            )
    return 0


def cmd_reference_baseline(args):
    """The run-to-run spread of the side-by-side measurement on an unchanged build: the baseline
    commit's build against itself, RUNS times per benchmark; threshold as for the ratios. With -k
    only the benchmarks whose name contains it are measured; the others keep their stored
    thresholds. --commit moves the side-by-side baseline to another commit (the spread belongs to
    the method and the host, so stored thresholds carry over)."""
    baseline = load_baseline(args.baseline)
    if baseline is None:
        print(f"no baseline at {args.baseline}: run `python benchmarks/gate.py baseline` first")
        return 2
    previous = baseline.get("reference_build", {})
    commit = args.commit or previous.get("commit") or baseline["commit"]
    commit = (
        subprocess.run(["git", "rev-parse", commit], capture_output=True, text=True, cwd=ROOT).stdout.strip()
        or commit
    )
    tree = reference_build.reference_tree(commit)
    names = [n for n in reference_build.SIDE_BY_SIDE if not args.k or args.k in n]
    runs = {}
    for k in range(args.runs):
        for name in names:
            m = reference_build.measurement(name, tree, current=tree)
            load = os.getloadavg()[0]
            runs.setdefault(name, []).append({**m, "load_1min": load})
            pairs = ", ".join(f"{r:.3f}" for r in m["pair_ratios"])
            print(
                f"run {k + 1}/{args.runs}: {name} A/A {m['ratio']:.4f} (pairs {pairs}), load {load:.2f}",
                flush=True,
            )
    out = dict(previous.get("benchmarks", {}))
    for name, ms in runs.items():
        medians = [m["ratio"] for m in ms]
        sp = spread(medians)
        out[name] = {
            "ratios": medians,
            **sp,
            "threshold": threshold_of(sp),
            "pairs": reference_build.default_pairs(name),
            "pair_ratios": [m["pair_ratios"] for m in ms],
            "loads_1min": [m["load_1min"] for m in ms],
            "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        }
        if "by_estimator" in ms[0]:  # the MPI step's other estimators, for the record
            out[name]["by_estimator"] = {e: [m["by_estimator"][e] for m in ms] for e in ms[0]["by_estimator"]}
        print(
            f"  {name:20s} MAD-std {sp['mad_rel']:.2%}, max deviation {sp['max_dev_rel']:.2%}, "
            f"threshold +{out[name]['threshold']:.1%}"
        )
    baseline["reference_build"] = {
        **previous,
        "commit": commit,
        "pairs": reference_build.PAIRS,
        "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "rule": "a measurement = the median over process pairs (job pairs for the MPI step) of each "
        "pair's median ratio current / baseline-commit build (the cold compile: one ratio per pair); "
        f"threshold = max({MULTIPLE:g} x MAD-based relative spread of the baseline build against "
        f"itself over the runs, {FLOOR:g}, its largest deviation)",
        "benchmarks": out,
    }
    if "loads_1min" in previous and len(names) < len(reference_build.SIDE_BY_SIDE):
        baseline["reference_build"]["loads_1min"] = previous["loads_1min"]  # of the step benchmarks
    Path(args.baseline).write_text(json.dumps(baseline, indent=1) + "\n")
    print(f"side-by-side thresholds written to {args.baseline}")
    return 0


def leave_one_out(runs, estimator):
    """The gate on each baseline run of an unchanged build, judged by a baseline of the other
    runs (same rule, no re-measurement): [(run index, {benchmark: change}, [flagged])]."""
    out = []
    for k, run in enumerate(runs):
        others = [r for j, r in enumerate(runs) if j != k]
        changes, flagged = {}, []
        for name, info in run["found"].items():
            values = [ratio_of(r["found"][name], estimator) for r in others if name in r["found"]]
            if len(values) < 2:
                continue
            sp = spread(values)
            threshold = threshold_of(sp)
            changes[name] = ratio_of(info, estimator) / sp["median"] - 1
            if changes[name] > threshold:
                flagged.append(name)
        out.append((k, changes, flagged))
    return out


def cmd_loo(args):
    runs = [json.loads(line) for line in Path(args.from_raw).read_text().splitlines() if line.strip()]
    est = args.estimator or (load_baseline(args.baseline) or {}).get("estimator", DEFAULT_ESTIMATOR)
    result = leave_one_out(runs, est)
    for k, changes, flagged in result:
        print(
            f"run {k + 1}/{len(runs)} against the other {len(runs) - 1} ({est}): "
            + ", ".join(f"{n} {c:+.1%}{'!' if n in flagged else ''}" for n, c in changes.items())
        )
    bad = sum(1 for _, _, f in result if f)
    print(f"{bad} of {len(runs)} unchanged runs flagged by a baseline of the others (no re-measurement)")
    return 0


def repeat_side_by_side(args, baseline):
    """The side-by-side verdict alone, RUNS times: each step benchmark against the baseline build."""
    reference = baseline.get("reference_build")
    if reference is None:
        print(
            "the baseline has no side-by-side thresholds: run `python benchmarks/gate.py reference-baseline`"
        )
        return 2
    tree = reference_build.reference_tree(reference["commit"])
    per, flagged_runs = {}, 0
    for k in range(args.runs):
        flagged, pair_ratios = [], {}
        for name, b in reference["benchmarks"].items():
            if args.k and args.k not in name:
                continue
            m = reference_build.measurement(
                name, tree, slowdown=args.slowdown, pairs=pairs_of(reference, name)
            )
            change = m["ratio"] - 1
            pair_ratios[name] = m["pair_ratios"]
            per.setdefault(name, []).append((change, change > b["threshold"]))
            if change > b["threshold"]:
                flagged.append(name)
        flagged_runs += bool(flagged)
        print(
            f"run {k + 1}/{args.runs} side by side (slowdown {args.slowdown or 0:g}, load "
            f"{os.getloadavg()[0]:.2f}): "
            + ", ".join(
                f"{n} {v[-1][0]:+.1%}{'!' if v[-1][1] else ''} (pairs "
                + ", ".join(f"{p:.3f}" for p in pair_ratios.get(n, []))
                + ")"
                for n, v in per.items()
            ),
            flush=True,
        )
    print(f"{flagged_runs} of {args.runs} runs flagged a regression (slowdown {args.slowdown or 0:g})")
    for name, v in per.items():
        gate = reference["benchmarks"][name]["threshold"]
        print(
            f"  {name:20s} flagged {sum(f for _, f in v)}/{len(v)} (gate +{gate:.1%}), change min "
            f"{min(c for c, _ in v):+.1%} max {max(c for c, _ in v):+.1%}"
        )
    return 0


def cmd_repeat(args):
    baseline = load_baseline(args.baseline)
    if baseline is None:
        print(f"no baseline at {args.baseline}: run `python benchmarks/gate.py baseline` first")
        return 2
    if args.side_by_side:
        return repeat_side_by_side(args, baseline)
    results = []
    for k in range(args.runs):
        s, _ = gated_run(baseline, Path(args.baseline), args.slowdown, args.k, args.estimator)
        results.append(s)
        print(
            f"run {k + 1}/{args.runs} (slowdown {args.slowdown or 0:g}, load {s['load_1min']:.2f}): "
            + ", ".join(
                f"{r['name']} {r['change']:+.1%}{'!' if r['regressed'] else ''}"
                + (f" ({r['attempts']} attempts)" if r.get("attempts", 1) > 1 else "")
                + (
                    f" [side by side {r['reference_build']['change']:+.1%}]"
                    if "change" in r.get("reference_build", {})
                    else ""
                )
                for r in s["benchmarks"]
                if r.get("change") is not None
            ),
            flush=True,
        )
    flagged = sum(1 for s in results if s["regressed"])
    print(f"{flagged} of {args.runs} runs flagged a regression (slowdown {args.slowdown or 0:g})")
    per = {}
    for s in results:
        for r in s["benchmarks"]:
            if r.get("change") is not None:
                change = r.get("reference_build", {}).get("change", r["change"])
                per.setdefault(r["name"], []).append((change, r["regressed"]))
    for name, v in per.items():
        print(
            f"  {name:20s} flagged {sum(f for _, f in v)}/{len(v)}, change min {min(c for c, _ in v):+.1%} "
            f"max {max(c for c, _ in v):+.1%}"
        )
    if args.out:
        Path(args.out).write_text(json.dumps({"slowdown": args.slowdown, "runs": results}, indent=1) + "\n")
    return 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    for name in ("check", "baseline", "repeat", "loo", "reference-baseline"):
        p = sub.add_parser(name)
        p.add_argument(
            "--baseline", default=str(BASELINE), help=f"baseline file (default {BASELINE.relative_to(ROOT)})"
        )
        p.add_argument(
            "--estimator",
            choices=list(ESTIMATORS),
            help=f"ratio estimator (default: the baseline's choice, else {DEFAULT_ESTIMATOR})",
        )
        if name == "reference-baseline":
            p.add_argument("--runs", type=int, default=10)
            p.add_argument("-k", help="only the benchmarks whose name contains this (the others keep theirs)")
            p.add_argument("--commit", help="the side-by-side baseline commit (default: the stored one)")
            continue
        if name == "loo":
            p.add_argument(
                "--from-raw", default=str(RAW), help=f"raw baseline runs (default {RAW.relative_to(ROOT)})"
            )
            continue
        if name != "baseline":
            p.add_argument(
                "--slowdown", type=float, help="inject a controlled slowdown (fraction, e.g. 0.10)"
            )
            p.add_argument("-k", help="only the benchmarks whose name contains this")
        if name == "check":
            p.add_argument(
                "--json", help="write the gate's summary here (read by `scoursph report --bench-json`)"
            )
        else:
            p.add_argument("--runs", type=int, default=10)
        if name == "baseline":
            p.add_argument("--from-raw", help=f"recompute from saved raw runs (e.g. {RAW.relative_to(ROOT)})")
        if name == "repeat":
            p.add_argument("--out", help="write every run's summary here (JSON)")
            p.add_argument(
                "--side-by-side",
                action="store_true",
                help="only the step benchmarks against the baseline build (what decides their verdict)",
            )
    args = ap.parse_args(argv)
    commands = {
        "check": cmd_check,
        "baseline": cmd_baseline,
        "repeat": cmd_repeat,
        "loo": cmd_loo,
        "reference-baseline": cmd_reference_baseline,
    }
    return commands[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
