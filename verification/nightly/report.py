"""`scoursph report`: the nightly verification report.

    scoursph report [--out runs/nightly] [--bench-json FILE] [--cases a,b] [--quick] [--no-study]

Runs every case of verification/registry.py (plus --case NAME=MODULE) in its own process
(collect.py), reads the benchmark gate's summary if given, compares tonight with the last
line of the history (history.py), and writes OUT/<date>/index.html and results.json, points
OUT/latest at that folder and appends tonight to the history. Exit status 0 only when every
case passed and nothing was flagged; 1 otherwise (the page says which and why); 2 on bad
input (an unknown case). A missing benchmark summary is a problem of the night (exit 1).
"""

from __future__ import annotations

import json
import os
import shutil
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

from . import collect, history, page, plots
from .run_case import jsonable


def select_cases(args):
    from verification.registry import CASES, NIGHTLY_CASES

    cases = {**CASES, **NIGHTLY_CASES}
    for spec in args.case:
        name, _, module = spec.partition("=")
        if not name or not module:
            raise ValueError(f"--case {spec!r}: expected NAME=MODULE")
        cases[name] = module
    if args.cases:
        wanted = [c.strip() for c in args.cases.split(",") if c.strip()]
        unknown = [c for c in wanted if c not in cases]
        if unknown:
            raise ValueError(f"--cases: unknown case(s) {', '.join(unknown)} (known: {', '.join(cases)})")
        cases = {c: cases[c] for c in wanted}
    return cases


def problems_of(records, flags):
    out = []
    for name, rec in records.items():
        st = rec["status"]
        if st == "crashed":
            if rec.get("crash"):
                why = rec["crash"].splitlines()[0]  # how the process ended; its log is on the page
            else:  # the exception's last traceback line
                err = next((rec[p]["error"] for p in ("import", "run") if rec.get(p, {}).get("error")), "")
                why = (err.strip().splitlines() or ["no result"])[-1]
            out.append({"kind": "case crashed", "what": name, "why": why[:500]})
        elif st == "failed":
            bad = [c for c in rec.get("run", {}).get("checks", []) if collect.unexpected(c)]
            why = "; ".join(
                f"{c['metric']} = {page.fmt(c['value'])} exceeds {page.fmt(c['tolerance'])}"
                if not c["passed"]
                else f"{c['metric']} = {page.fmt(c['value'])} passed, but the case lists it as a known "
                "failure (remove it from KNOWN_FAILURES)"
                for c in bad
            )
            if rec.get("study", {}).get("error"):
                why += (
                    ("; " if why else "") + "study raised " + rec["study"]["error"].strip().splitlines()[-1]
                )
            out.append({"kind": "case failed", "what": name, "why": why})
    return out + flags


def plan_text(rec):
    plan = rec.get("plan", {})
    if not plan:
        return ""
    text = f"tonight: run at resolution {plan.get('resolution')}"
    study, full = plan.get("study"), plan.get("full_study")
    if study:
        text += f"; study at {', '.join(map(str, study))}"
        left = [r for r in (full or []) if r not in study]
        if left:
            text += f" (the full study also has {', '.join(map(str, left))}, left out for time)"
    elif full:
        text += f"; no study tonight (the full study: {', '.join(map(str, full))})"
    if plan.get("note"):
        text += ". " + plan["note"]
    return text


def cost_figures(records):
    out = {}
    for name, rec in records.items():
        rows = rec.get("study", {}).get("rows", [])
        if not rows:
            continue
        cols = plots.accuracy_columns(rows, rec["study"].get("accuracy_columns"))
        if cols:
            out[name] = plots.cost_figure(name, rows, cols, rec.get("reference_costs", []))
    return out


def trend_figures(past, tonight, flags):
    nights = past + [tonight]
    flagged = {f["what"] for f in flags}
    out = {}
    by_case = {}
    for key in tonight["metrics"]:
        by_case.setdefault(key.split(" :: ", 1)[0], []).append(key)
    for case, keys in by_case.items():
        out[f"metrics of {case}"] = plots.metric_trend_figure(case, nights, keys, flagged)
    names = list(tonight["benchmarks"])
    if names:
        thresholds = {
            n: b["threshold"] for n, b in tonight["benchmarks"].items() if b.get("threshold") is not None
        }
        out["benchmarks"] = plots.bench_trend_figure(nights, names, thresholds, flagged)
    return out


def load_bench(path):
    """The gate's summary, or (None, why not) when it was asked for but is missing or unreadable:
    under `make nightly` that means the gate did not finish, a problem of the night, not bad input."""
    if path is None:
        return None, None
    try:
        return json.loads(Path(path).read_text()), None
    except (OSError, json.JSONDecodeError) as exc:
        return None, f"no benchmark summary at {path} ({exc.__class__.__name__}: the gate did not finish?)"


def point_latest(root, folder):
    """OUT/latest -> the folder (a relative symlink; a copy where links are not allowed)."""
    latest = root / "latest"
    if latest.is_symlink() or latest.is_file():
        latest.unlink()
    elif latest.is_dir():
        shutil.rmtree(latest)
    try:
        latest.symlink_to(folder.name, target_is_directory=True)
    except OSError:
        shutil.copytree(folder, latest)


def main(args):
    start = time.perf_counter()
    try:
        cases = select_cases(args)
    except ValueError as exc:
        print(f"scoursph: error: {exc}", file=sys.stderr)
        return 2
    if args.jobs < 1:
        print(f"scoursph: error: --jobs: at least 1, got {args.jobs}", file=sys.stderr)
        return 2
    root = Path(args.out)
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    folder = root / date
    if folder.exists():
        shutil.rmtree(folder)  # tonight's rerun replaces tonight's page
    folder.mkdir(parents=True)
    hist_path = Path(args.history) if args.history else root / "history.jsonl"
    meta = history.machine(cwd=collect.ROOT)
    print(
        f"report: {len(cases)} case(s) into {folder}/ (commit {meta['commit'][:10]}, "
        f"load {meta['load_1min']:.2f})"
    )
    flags_ = ["--quick"] if args.quick else (["--no-study"] if args.no_study else [])
    past = history.load(hist_path)
    records = collect.run_all(
        cases,
        folder,
        args.timeout,
        args.case_threads,
        flags_,
        cpu_limit=args.cpu_limit,
        jobs=args.jobs,
        cost={k: v for k, v in (past[-1].get("case_cpu_s") or {}).items() if v} if past else None,
    )
    bench, bench_problem = load_bench(args.bench_json)
    if bench is not None:
        (folder / "bench.json").write_text(json.dumps(bench, indent=1))
    cases_wall = time.perf_counter() - start
    tonight = history.entry(
        meta, records, bench, wall_s=cases_wall + float((bench or {}).get("wall_s") or 0.0)
    )
    flags = history.flags(tonight, past[-1] if past else None)
    problems = problems_of(records, flags)
    if bench_problem:
        problems.append({"kind": "benchmarks missing", "what": "benchmark gate", "why": bench_problem})
    bench_wall = (bench or {}).get("wall_s")
    cases_cpu = sum(r.get("process", {}).get("cpu_s", 0.0) for r in records.values())
    timing_text = (
        f"This nightly took {cases_wall / 60:.1f} min of wall time for the cases"
        + (f" and {bench_wall / 60:.1f} min for the benchmarks (gate run)" if bench_wall else "")
        + f" on this {meta['cpus']}-core machine at 1-min load {meta['load_1min']:.2f} -> "
        f"{os.getloadavg()[0]:.2f}, {args.jobs} case(s) side by side. The case processes used "
        f"{cases_cpu / 60:.1f} min of CPU time (one thread each): about {args.jobs} x the wall time they "
        "take on an idle machine. Per case below. "
        + ("Quick mode: each case once at its smallest resolution, no study." if args.quick else "")
    )
    ctx = {
        "meta": meta,
        "records": records,
        "problems": problems,
        "bench": bench,
        "out_dir": folder,
        "load_end": os.getloadavg()[0],
        "timing_text": timing_text,
        "plans": {n: plan_text(r) for n, r in records.items()},
        "cost_figures": cost_figures(records),
        "trend_figures": trend_figures(past, tonight, flags),
        "trend_text": (
            f"{len(past) + 1} night(s) in {hist_path}. Flagged: a metric that moved by more than "
            f"{history.MOVE_FRACTION:g} of its tolerance since the previous night; a benchmark past its gate."
        ),
        "footer": f"Generated by scoursph report in {time.perf_counter() - start:.0f} s.",
    }
    results = {
        "meta": meta,
        "cases": records,
        "problems": problems,
        "flags": flags,
        "bench": bench,
        "timing": {"cases_wall_s": cases_wall, "cases_cpu_s": cases_cpu, "bench_wall_s": bench_wall},
        "history_entry": tonight,
    }
    (folder / "results.json").write_text(json.dumps(jsonable(results), indent=1))
    (folder / "index.html").write_text(page.render(ctx))
    if not args.no_history:
        history.append(hist_path, jsonable(tonight))
    point_latest(root, folder)
    print(
        f"report: {folder / 'index.html'} "
        f"({'no problems' if not problems else f'{len(problems)} problem(s)'})"
    )
    for p in problems:
        print(f"  {p['kind']}: {p['what']}: {p['why'][:300]}")
    return 0 if not problems else 1
