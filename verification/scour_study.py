"""The scouring study (issue 11 items 6, 7, 10): the seed's overflow scour, dry and saturated, per q.

    python -m verification.scour_study run dry 0.11                 # one run (5 mm, to END_TIME)
    python -m verification.scour_study run saturated 0.06 --dx 0.0025 --end 0.3
    python -m verification.scour_study all --end 0.5                # every missing run, then the report
    python -m verification.scour_study report                       # tables and figures from the runs made
    python -m verification.scour_study long                         # the full-length study (nightly: hours)

A run is solver/scenes/scour_{dry,saturated}.toml (the seed's set-up, docs/scour_setup.md) with
its inlet's discharge q, the spacing and the end time changed, and nothing else. Each run goes to
runs/scour_study/<case>/ (the HDF5 series, scour.csv, scour_profiles.csv, scour.png, run.json) and
leaves a small summary in verification/results/scour/cases/<case>.json plus a copy of its
scour.csv there (committed: the report is rebuilt from these without the HDF5 series, except the
snapshot figure, which reads the series when it is there).

The report, verification/results/scour/: scour_study.md (per run: soil, q, dx, simulated time
reached, depth at the seed's 0.025 s and at fixed later times, deepest point, eroded area,
body leaks, volume-balance residual, steps, particles, wall and CPU time, the load average),
scour_study.csv, and the figures
  depth_vs_time.png        d(t) per q, dry and saturated side by side (the seed's Figs. 12 and 7)
  depth_vs_q.png           d at fixed times against q, dry and saturated, with the q-exponent fits
                           and the range of the published formulas' exponents in this set-up
  snapshots_q0.11.png      particles at the seed's figure times (its Figs. 3-6 and 8-11)
  snapshots_q0.11_late.png the same at 0.25, 0.5 and 1 s (the times reached)
  resolution.png           d(t) at 5 and 2.5 mm for the runs made at both.

The scour depth is solver/output/scour.py's: d(t) = max over x of (z_s(x, 0) - z_s(x, t)), with
z_s the height where the kernel-interpolated soil fraction falls to 1/2. The seed's claims are
judged in docs/scour_study.md from these numbers, and the growth with q is compared with
verification/analytic/scour_formulas.py without tuning anything.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import resource
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "solver" / "scenes"
RESULTS = Path(__file__).with_name("results") / "scour"
RUNS = ROOT / "runs" / "scour_study"
SOILS = ("dry", "saturated")
Q_STUDY = (
    0.06,
    0.08,
    0.10,
    0.11,
)  # the affordable subset of the seed's 0.06-0.11 (issue 11: all six, long job)
Q_ALL = (0.06, 0.07, 0.08, 0.09, 0.10, 0.11)
DX = 0.005  # the seed's spacing
DX_FINE = 0.0025
END_TIME = 0.5  # s, the affordable study on the shared 2-core machine
LONG_END = 2.0  # s, the full length (nightly / long job)
LONG_LENGTH = 0.60  # m: docs/scour_setup.md sec. 2, the long-run hole and its mound outgrow 0.25 m
SEED_TIMES = (0.005, 0.01, 0.015, 0.02, 0.025)  # the seed's figure times (and 0.015)
EVERY = 0.025  # s between later snapshots
FIXED_TIMES = (0.025, 0.1, 0.25, 0.5, 1.0, 2.0)  # d(q) is read at these times (those reached)


def case_name(soil, q, dx, length=0.25):
    tail = "" if abs(length - 0.25) < 1e-12 else f"_L{length:g}"
    return f"{soil}_q{q:.2f}_dx{dx * 1000:g}mm{tail}"


def scene_raw(soil, q, dx, end_time, length=0.25):
    """The shipped scene with q, dx and end time changed (length: the soil layer's, docs/scour_setup.md
    sec. 2 recommends 0.60 m for long runs; the end wall and outlet move with it)."""
    raw = tomllib.loads((SCENES / f"scour_{soil}.toml").read_text())
    raw["scene"]["spacing"] = float(dx)
    raw["scene"]["end_time"] = float(end_time)
    raw["scene"]["name"] = case_name(soil, q, dx, length)
    raw["inlets"][0]["discharge"] = float(q)
    times = [t for t in SEED_TIMES if t <= end_time]
    k = 1
    while k * EVERY <= end_time * (1 + 1e-9) + 1e-12:
        if k * EVERY > SEED_TIMES[-1] + 1e-12:
            times.append(round(k * EVERY, 6))
        k += 1
    if times[-1] < end_time - 1e-9:
        times.append(end_time)
    raw["output"]["times"] = [0.0] + times
    raw["output"]["vtk"] = False
    raw["output"]["render"] = True
    if abs(length - 0.25) > 1e-12:
        shift = length - 0.25
        raw["domain"]["max"][0] += shift
        raw["blocks"][0]["max"][0] = length
        end = next(b for b in raw["bodies"] if b["name"] == "end wall")
        end["vertices"] = [[x + shift, z] for x, z in end["vertices"]]
        raw["outlets"][0]["min"][0] += shift
        raw["outlets"][0]["max"][0] += shift
    return raw


def run_case(soil, q, dx, end_time, length=0.25, threads=1):
    """Run one case in this process; write its summary and scour.csv copy into RESULTS/cases."""
    import numba

    from solver.errors import BlowUpError
    from solver.run import run_scene
    from solver.scene import parse_scene

    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    name = case_name(soil, q, dx, length)
    scene = parse_scene(scene_raw(soil, q, dx, end_time, length), SCENES / f"scour_{soil}.toml")
    out = RUNS / name
    load0 = os.getloadavg()[0]
    c0, w0 = time.process_time(), time.perf_counter()
    status = "completed"
    try:
        run_scene(scene, out, quiet=True, overwrite=True)
    except BlowUpError as exc:
        status = f"blew up: {exc}"
    except KeyboardInterrupt:  # Ctrl-C of a foreground run: run.json and scour.csv are written (a
        # background job ignores SIGINT: kill it and use `finish`)
        status = "stopped"
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    report = json.loads((out / "run.json").read_text())
    summary = {
        "case": name,
        "soil": soil,
        "q": q,
        "dx": dx,
        "length": length,
        "end_time": end_time,
        "status": status,
        "t_reached": report["simulated_time_s"],
        "steps": report["steps"],
        "particles_end": report["particles"],
        "wall_s": wall,
        "cpu_s": cpu,
        "stepping_wall_s": report["wall_time_s"],
        "threads": threads,
        "load_start": load0,
        "load_end": os.getloadavg()[0],
        "max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "body_leaks": report.get("body_leaks"),
        "volume_balance": report.get("volume_balance"),
    }
    dest = RESULTS / "cases"
    dest.mkdir(parents=True, exist_ok=True)
    (dest / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
    if (out / "scour.csv").exists():
        (dest / f"{name}_scour.csv").write_text((out / "scour.csv").read_text())
    print(
        f"{name}: {status}, t = {summary['t_reached']:.4f} s, {wall:.0f} s wall, {cpu:.0f} s CPU", flush=True
    )
    return summary


def finish_case(soil, q, dx, length=0.25, cpu_s=float("nan"), wall_s=float("nan")):
    """The summary of a run that was killed (no run.json): scour outputs from the snapshots on disk,
    the time reached from the last one; CPU and wall time as measured from outside (ps)."""
    from solver.output.hdf5_writer import read_series
    from solver.output.scour import write_scour_outputs
    from solver.scene import load_scene

    name = case_name(soil, q, dx, length)
    out = RUNS / name
    scene = load_scene(out / "scene.toml")
    write_scour_outputs(out, scene)
    series = read_series(out / "particles.h5")
    summary = {
        "case": name,
        "soil": soil,
        "q": q,
        "dx": dx,
        "length": length,
        "end_time": scene.scene.end_time,
        "status": "stopped (killed for want of time; summary from its snapshots)",
        "t_reached": series[-1][0],
        "steps": 0,
        "particles_end": int(len(series[-1][1]["position"])),
        "wall_s": wall_s,
        "cpu_s": cpu_s,
        "stepping_wall_s": float("nan"),
        "threads": 1,
        "load_start": float("nan"),
        "load_end": os.getloadavg()[0],
        "max_rss_mb": float("nan"),
        "body_leaks": None,
        "volume_balance": None,
    }
    dest = RESULTS / "cases"
    dest.mkdir(parents=True, exist_ok=True)
    (dest / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
    (dest / f"{name}_scour.csv").write_text((out / "scour.csv").read_text())
    return summary


# -- report ---------------------------------------------------------------------------------------
def load_cases():
    cases = []
    for path in sorted((RESULTS / "cases").glob("*.json")):
        c = json.loads(path.read_text())
        series = path.with_name(f"{c['case']}_scour.csv")
        rows = list(csv.DictReader(open(series))) if series.exists() else []
        c["t"] = np.array([float(r["t_s"]) for r in rows])
        c["d"] = np.array([float(r["depth_m"]) for r in rows])
        c["x_deepest"] = np.array([float(r["x_deepest_m"]) for r in rows])
        c["eroded"] = np.array([float(r["eroded_area_m2"]) for r in rows])
        cases.append(c)
    return cases


def depth_at(c, t):
    """d at time t (nan if the run did not reach it)."""
    if not len(c["t"]) or c["t"][-1] < t - 1e-9:
        return float("nan")
    return float(np.interp(t, c["t"], c["d"]))


def residual(c):
    """The largest |volume-balance residual| over materials, in particle volumes."""
    vb = c.get("volume_balance") or {}
    mats = vb.get("materials", {})
    dv = c["dx"] ** 2
    vals = [abs(m.get("residual", 0.0)) / dv for m in mats.values()]
    return max(vals) if vals else float("nan")


def q_exponent(qs, ds):
    """Slope of log d against log q (nan with fewer than two positive depths)."""
    qs, ds = np.asarray(qs, float), np.asarray(ds, float)
    ok = np.isfinite(ds) & (ds > 0)
    return float(np.polyfit(np.log(qs[ok]), np.log(ds[ok]), 1)[0]) if ok.sum() >= 2 else float("nan")


def formula_exponents():
    from verification.analytic.scour_formulas import PARTICLE, SAND, predictions

    out = {}
    for grains in (SAND, PARTICLE):
        p = predictions(np.array(Q_ALL), grains)
        for name, r in p["formulas"].items():
            if name == "Veronese 1937 A" and grains is SAND:
                continue  # for dm >= 5 mm only (docs/scour_setup.md sec. 5)
            if np.isfinite(r["q_exponent_in_setup"]):
                out[f"{name}, {grains.label}"] = (r["q_exponent_in_setup"], r["below_bed"])
    return out


def report(out=RESULTS):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = load_cases()
    if not cases:
        print("no runs yet: python -m verification.scour_study all", file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    fixed = [t for t in FIXED_TIMES if any(c["t_reached"] >= t - 1e-9 for c in cases)]
    # table
    fields = ["case", "soil", "q", "dx_mm", "status", "t_reached_s"]
    fields += [f"d_{t:g}s_mm" for t in fixed]
    fields += ["d_end_mm", "x_deepest_end_m", "eroded_end_cm2", "body_leaks", "balance_residual_particles"]
    fields += ["steps", "particles_end", "wall_s", "cpu_s", "load_start", "load_end", "threads"]
    rows = []
    for c in sorted(cases, key=lambda c: (c["dx"], c["soil"], c["q"], c["length"])):
        row = {
            "case": c["case"],
            "soil": c["soil"],
            "q": f"{c['q']:.2f}",
            "dx_mm": f"{c['dx'] * 1000:g}",
            "status": c["status"].split(":")[0],
            "t_reached_s": f"{c['t_reached']:.4f}",
        }
        for t in fixed:
            v = depth_at(c, t)
            row[f"d_{t:g}s_mm"] = "" if not np.isfinite(v) else f"{1000 * v:.1f}"
        row["d_end_mm"] = f"{1000 * c['d'][-1]:.1f}" if len(c["d"]) else ""
        row["x_deepest_end_m"] = f"{c['x_deepest'][-1]:.3f}" if len(c["d"]) else ""
        row["eroded_end_cm2"] = f"{1e4 * c['eroded'][-1]:.1f}" if len(c["d"]) else ""
        row["body_leaks"] = c.get("body_leaks")
        row["balance_residual_particles"] = f"{residual(c):.2g}"
        row["steps"] = c["steps"]
        row["particles_end"] = c["particles_end"]
        row["wall_s"] = f"{c['wall_s']:.0f}"
        row["cpu_s"] = f"{c['cpu_s']:.0f}"
        row["load_start"] = f"{c['load_start']:.1f}"
        row["load_end"] = f"{c['load_end']:.1f}"
        row["threads"] = c["threads"]
        rows.append(row)
    with open(out / "scour_study.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fields)
        w.writeheader()
        w.writerows(rows)
    lines = [
        "# Scour study: results table",
        "",
        "Written by `python -m verification.scour_study report` from verification/results/scour/cases/.",
        "d: scour depth (initial surface minus lowest surface, solver/output/scour.py) at the given",
        "simulated time; empty where the run did not reach it. Wall and CPU time of the whole run",
        "(set-up, JIT from cache, stepping, output), one process with `threads` Numba threads;",
        "load: 1-min load average at start and end (the 2 cores were shared with other jobs).",
        "balance residual: |inflow - outflow - stored change| in particle volumes (must be < 1).",
        "",
        "| " + " | ".join(fields) + " |",
        "|" + "---|" * len(fields),
    ]
    lines += ["| " + " | ".join(str(r[k]) for k in fields) + " |" for r in rows]
    # exponents of q
    lines += ["", "## Growth with q", ""]
    lines += [
        "| soil | dx (mm) | time (s) | q values | exponent of q (log-log fit of d) |",
        "|---|---|---|---|---|",
    ]
    exps = {}
    for soil in SOILS:
        for dx in sorted({c["dx"] for c in cases}):
            sel = [c for c in cases if c["soil"] == soil and c["dx"] == dx and c["length"] == 0.25]
            for t in fixed:
                qs = [c["q"] for c in sel if np.isfinite(depth_at(c, t))]
                if len(qs) < 2:
                    continue
                e = q_exponent(qs, [depth_at(c, t) for c in sel if np.isfinite(depth_at(c, t))])
                exps[(soil, dx, t)] = e
                lines.append(
                    f"| {soil} | {dx * 1000:g} | {t:g} | {', '.join(f'{q:g}' for q in qs)} | {e:.2f} |"
                )
    fx = formula_exponents()
    lines += ["", "Published formulas in this set-up (verification/analytic/scour_formulas.py, loss-free", ""]
    lines[-2] += " tailwater; equilibrium depths, all below the 0.095 m base):"
    lines += ["| formula, grain mapping | exponent of q | depth at q = 0.06 / 0.11 (m) |", "|---|---|---|"]
    for name, (e, below) in fx.items():
        lines.append(f"| {name} | {e:.2f} | {below[0]:.3f} / {below[-1]:.3f} |")
    (out / "scour_study.md").write_text("\n".join(lines) + "\n")

    _plot_depth_vs_time(plt, cases, out / "depth_vs_time.png")
    _plot_depth_vs_q(plt, cases, fixed, fx, out / "depth_vs_q.png")
    _plot_resolution(plt, cases, out / "resolution.png")
    _plot_snapshots(plt, out / "snapshots_q0.11.png")
    _plot_snapshots(plt, out / "snapshots_q0.11_late.png", times=(0.25, 0.5, 1.0), note="later times")
    print(f"report in {out}/scour_study.md")
    return 0


def _plot_depth_vs_time(plt, cases, path):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    cmap = plt.get_cmap("viridis")
    for ax, soil, fig_no in zip(axes, SOILS, (12, 7)):
        sel = sorted(
            (c for c in cases if c["soil"] == soil and c["dx"] == DX and c["length"] == 0.25),
            key=lambda c: c["q"],
        )
        for c in sel:
            colour = cmap((c["q"] - 0.06) / 0.05 * 0.9)
            ax.plot(c["t"], 1000 * c["d"], "-", color=colour, label=f"q = {c['q']:.2f} m²/s")
        # the rigid base when the holes come near it, else one particle spacing (a row removed)
        deepest = max([1000 * c["d"].max() for c in cases if len(c["d"])] + [0.0])
        ax.axhline(95 if deepest > 30 else 1000 * DX, color="0.5", lw=0.8, ls=":")
        ax.set_title(f"{soil} soil, dx = 5 mm (the seed's Fig. {fig_no})")
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    what = "the rigid base" if deepest > 30 else "one particle spacing"
    axes[0].set_ylabel(f"scour depth d (mm); dotted: {what}")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    # the seed's window alone (its figures stop at 0.025 s)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    for ax, soil, fig_no in zip(axes, SOILS, (12, 7)):
        for c in sorted(
            (c for c in cases if c["soil"] == soil and c["dx"] == DX and c["length"] == 0.25),
            key=lambda c: c["q"],
        ):
            k = c["t"] <= 0.0251
            ax.plot(c["t"][k], 1000 * c["d"][k], "o-", color=cmap((c["q"] - 0.06) / 0.05 * 0.9),
                    label=f"q = {c['q']:.2f}")  # fmt: skip
        ax.set_title(f"{soil}, t <= 0.025 s (the seed's Fig. {fig_no} window)")
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("scour depth d (mm)")
    fig.tight_layout()
    fig.savefig(path.with_name("depth_vs_time_seed_window.png"), dpi=110)
    plt.close(fig)


def _plot_depth_vs_q(plt, cases, fixed, fx, path):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    markers = {"dry": "o", "saturated": "s"}
    cmap = plt.get_cmap("plasma")
    for soil in SOILS:
        sel = sorted((c for c in cases if c["soil"] == soil and c["dx"] == DX and c["length"] == 0.25),
                     key=lambda c: c["q"])  # fmt: skip
        for k, t in enumerate(fixed):
            ds = [depth_at(c, t) for c in sel]
            qs = [c["q"] for c, d in zip(sel, ds) if np.isfinite(d)]
            ds = [d for d in ds if np.isfinite(d)]
            if len(qs) < 2:
                continue
            ax.plot(qs, [1000 * d for d in ds], markers[soil] + ("-" if soil == "dry" else "--"),
                    color=cmap(k / max(len(fixed), 1)), label=f"{soil}, t = {t:g} s")  # fmt: skip
    es = [e for e, _ in fx.values()]
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("q (m²/s)")
    ax.set_ylabel("scour depth d (mm)")
    ax.set_title(f"d against q; published formulas: d ∝ q^{min(es):.2f}–q^{max(es):.2f} in this set-up")
    q = np.array([0.06, 0.11])
    for e in (min(es), max(es)):
        ax.plot(q, 20 * (q / 0.06) ** e, "k:", lw=0.8)
    ax.text(0.11, 20 * (0.11 / 0.06) ** max(es), "  formula slopes", fontsize=7, va="center")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_resolution(plt, cases, path):
    fine = [c for c in cases if c["dx"] == DX_FINE]
    if not fine:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for c in fine:
        coarse = next(
            (k for k in cases if k["dx"] == DX and k["soil"] == c["soil"] and k["q"] == c["q"]
             and k["length"] == c["length"]), None)  # fmt: skip
        (line,) = ax.plot(c["t"], 1000 * c["d"], "-", label=f"{c['soil']}, q = {c['q']:.2f}, 2.5 mm")
        if coarse is not None:
            ax.plot(coarse["t"], 1000 * coarse["d"], "--", color=line.get_color(), label="same, 5 mm")
    ax.set_xlim(0.0, 1.25 * max(c["t_reached"] for c in fine))  # where both resolutions have data
    ax.set_xlabel("t (s)")
    ax.set_ylabel("scour depth d (mm)")
    ax.set_title("resolution: 5 mm against 2.5 mm")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_snapshots(plt, path, q=0.11, times=(0.005, 0.01, 0.02, 0.025), note="the seed's Figs. 3-6, 8-11"):
    """Particles at the seed's figure times (its Figs. 3-6, saturated, and 8-11, dry), or at `times`,
    when the HDF5 series of the 5 mm runs at q are on disk."""
    from solver.output.hdf5_writer import read_series

    series = {}
    for soil in SOILS:
        h5 = RUNS / case_name(soil, q, DX) / "particles.h5"
        if h5.exists():
            series[soil] = {round(t, 6): f for t, f in read_series(h5)}
    if not series:
        return
    fig, axes = plt.subplots(len(series), len(times), figsize=(3.2 * len(times), 2.3 * len(series)),
                             squeeze=False)  # fmt: skip
    colours = np.array([[0.2, 0.45, 0.9], [0.75, 0.55, 0.25]])
    for i, (soil, snaps) in enumerate(series.items()):
        for j, t in enumerate(times):
            ax = axes[i, j]
            f = snaps.get(round(t, 6))
            if f is None:
                ax.set_axis_off()
                continue
            x, mat = f["position"], f["material"].astype(int)
            order = np.argsort(mat, kind="stable")  # soil drawn over its pore water
            ax.scatter(x[order, 0], x[order, 1], s=1.2, c=colours[np.clip(mat[order], 0, 1)], linewidths=0)
            ax.set_xlim(-0.05, 0.28)
            ax.set_ylim(0.0, 0.22)
            ax.set_aspect("equal")
            ax.set_title(f"{soil}, t = {t:g} s", fontsize=9)
            ax.tick_params(labelsize=6)
    fig.suptitle(
        f"q = {q} m²/s, dx = 5 mm: blue water, brown soil (over its pore water; {note})",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# -- driver ---------------------------------------------------------------------------------------
FINE = (("dry", 0.11), ("saturated", 0.11))  # the 2.5 mm resolution check


def study_cases(end_time, qs=Q_STUDY, fine=FINE):
    """(soil, q, dx, end_time, length) of the affordable study: 5 mm at qs, 2.5 mm for `fine`."""
    cases = [
        (soil, q, DX, end_time, 0.25) for q in sorted(qs, key=lambda q: (q != max(qs), q)) for soil in SOILS
    ]
    cases += [(soil, q, DX_FINE, end_time, 0.25) for soil, q in fine]
    return cases


def run_all(cases, jobs=1, nice=10):
    """Run the cases not yet in RESULTS/cases (or shorter there than asked), `jobs` processes at a
    time, each a separate `nice`d process with one Numba thread."""
    todo = []
    for soil, q, dx, end, length in cases:
        done = RESULTS / "cases" / f"{case_name(soil, q, dx, length)}.json"
        if done.exists() and json.loads(done.read_text())["t_reached"] >= end - 1e-9:
            continue
        todo.append((soil, q, dx, end, length))
    running = []
    for soil, q, dx, end, length in todo:
        while len(running) >= jobs:
            running = [p for p in running if p.poll() is None]
            time.sleep(2)
        cmd = ["nice", "-n", str(nice), sys.executable, "-m", "verification.scour_study", "run", soil, str(q),
               "--dx", str(dx), "--end", str(end), "--length", str(length)]  # fmt: skip
        running.append(subprocess.Popen(cmd, cwd=ROOT))
    for p in running:
        p.wait()


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.scour_study", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="one run")
    r.add_argument("soil", choices=SOILS)
    r.add_argument("q", type=float)
    r.add_argument("--dx", type=float, default=DX)
    r.add_argument("--end", type=float, default=END_TIME)
    r.add_argument("--length", type=float, default=0.25, help="soil layer length (m)")
    r.add_argument("--threads", type=int, default=1)
    a = sub.add_parser("all", help="every missing run of the affordable study, then the report")
    a.add_argument("--end", type=float, default=END_TIME)
    a.add_argument("--jobs", type=int, default=2)
    a.add_argument("--coarse-only", action="store_true", help="only the 5 mm runs")
    lg = sub.add_parser("long", help="the full-length study: all six q, 5 and 2.5 mm, LONG_END s (hours)")
    lg.add_argument("--end", type=float, default=LONG_END)
    lg.add_argument("--jobs", type=int, default=2)
    lg.add_argument("--length", type=float, default=LONG_LENGTH, help="soil layer length (m)")
    sub.add_parser("report", help="tables and figures from the runs made")
    f = sub.add_parser("finish", help="summarise a run that was killed, from its snapshots")
    f.add_argument("soil", choices=SOILS)
    f.add_argument("q", type=float)
    f.add_argument("--dx", type=float, default=DX)
    f.add_argument("--length", type=float, default=0.25)
    f.add_argument("--cpu", type=float, default=float("nan"), help="CPU seconds measured from outside")
    f.add_argument("--wall", type=float, default=float("nan"), help="wall seconds measured from outside")
    args = ap.parse_args(argv)
    if args.cmd == "run":
        s = run_case(args.soil, args.q, args.dx, args.end, args.length, args.threads)
        return 0 if s["status"] == "completed" else 1
    if args.cmd == "finish":
        finish_case(args.soil, args.q, args.dx, args.length, args.cpu, args.wall)
    if args.cmd == "all":
        run_all(study_cases(args.end, fine=() if args.coarse_only else FINE), args.jobs)
    elif args.cmd == "long":
        run_all(
            [(s, q, dx, args.end, args.length) for dx in (DX, DX_FINE) for s in SOILS for q in Q_ALL],
            args.jobs,
        )
    return report()


if __name__ == "__main__":
    raise SystemExit(main())
