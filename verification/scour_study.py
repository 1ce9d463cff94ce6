"""The scouring study (issue 11 items 6, 7, 10): the seed's overflow scour, dry and saturated, per q.

    python -m verification.scour_study run dry 0.11                 # one run (5 mm, to END_TIME)
    python -m verification.scour_study run saturated 0.06 --dx 0.0025 --end 0.3
    python -m verification.scour_study all --end 0.5                # every missing run, then the report
    python -m verification.scour_study report                       # tables and figures from the runs made
    python -m verification.scour_study long                         # the full-length study (nightly: hours)
    python -m verification.scour_study run saturated 0.11 --end 2.0 --continue   # extend from its checkpoint
    python -m verification.scour_study run saturated 0.11 --end 0.5 --set materials.sand.friction_angle=28
    python -m verification.scour_study sensitivity --end 0.5        # SENSITIVITY's variants at q = 0.11
    mpirun -n 2 python -m verification.scour_study run saturated 0.11 --end 0.1   # case ..._np2
    python -m verification.scour_study compare saturated_q0.11_dx5mm saturated_q0.11_dx5mm_np2

A run is solver/scenes/scour_{dry,saturated}.toml (the seed's set-up, docs/scour_setup.md) with
its inlet's discharge q, the spacing and the end time changed, and nothing else; a variant adds
`--set key=value` scene overrides (solver.scene.apply_overrides, as `scoursph run --set`), named in
the case (`..._friction_angle28`) and listed in its summary, and a run under mpirun gets `_np<ranks>`.
`--continue` extends a finished or stopped run from its newest checkpoint (the solver's restart:
only the end time and the output times change), adding the new segment's CPU and wall time. Each run goes to
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
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from verification.scour_zones import FACE_ZONE, WALL_ZONE

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "solver" / "scenes"
RESULTS = Path(__file__).with_name("results") / "scour"
RUNS = ROOT / "runs" / "scour_study"
SOILS = ("dry", "saturated")


@dataclass(frozen=True)
class Setup:
    """A scour set-up the study runs: its shipped scenes (one per soil), the layer length they have,
    where its case summaries go and the case-name prefix that keeps its runs apart."""

    name: str
    scene: str  # file name pattern in SCENES, {soil} filled in
    length: float  # the shipped scenes' soil layer length (m)
    results: Path
    prefix: str

    def scene_path(self, soil):
        return SCENES / self.scene.format(soil=soil)


SETUPS = {
    # the seed's set-up (docs/scour_setup.md): the 0.01 m fall, drowned nappe, 0.25 m layer
    "seed": Setup("seed", "scour_{soil}.toml", 0.25, RESULTS, ""),
    # issue 24 item 4: the nappe plunges onto an eroding bed (docs/scour_plunging.md)
    # issue 31: the same with a sand with a state, the seed's densities (docs/sand.md)
    "plunging": Setup(
        "plunging",
        "scour_plunging_{soil}.toml",
        0.63,
        RESULTS.with_name("scour_plunging_state"),
        "plunging_state_",
    ),
    # issue 24's plunging study, the seed's sand (constant phi, psi = 0, 1800 kg/m^3, n = 0.35): its runs
    "plunging_seed_sand": Setup(
        "plunging_seed_sand",
        "scour_plunging_seed_sand_{soil}.toml",
        0.63,
        RESULTS.with_name("scour_plunging"),
        "plunging_",
    ),
}
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
STEADY_WINDOW = 0.5  # s: the "hole stops deepening" is d changing < 2 % over this window
STEADY_CHANGE = 0.02
# the sensitivity runs of issue 11 item 6 for each parameter docs/scour_setup.md sec. 3 chose (base:
# scour_saturated.toml): friction angle 33 +- 5 deg, permeability 1e-3 x10 and /10, porosity 0.35 -> 0.45
# (0.35 is the base), the reduced bulk modulus 5.56 MPa x2 and /2
SAND = "materials.sand."
SENSITIVITY = {
    "phi 28": SAND + "friction_angle=28.0",
    "phi 38": SAND + "friction_angle=38.0",
    "k x10": SAND + "permeability=1.0e-2",
    "k /10": SAND + "permeability=1.0e-4",
    "n 0.45": SAND + "porosity=0.45",
    "K x2": SAND + "bulk_modulus=1.112e7",
    "K /2": SAND + "bulk_modulus=2.78e6",
}
SENSITIVITY_CASE = ("saturated", 0.11)
# The base the variants are measured against must be on their solver: a path under RESULTS to a kept
# base, or None for the base run in cases/ (the variants and the base are all on main's solver after seep5).
SENSITIVITY_BASE = None


def variant_tag(sets=(), ranks=1):
    """The case-name tail of a variant: each override's last key and value (`_friction_angle28`),
    and `_np<ranks>` for a run under MPI."""
    tail = ""
    for item in sets:
        key, _, value = item.partition("=")
        value = "".join(ch for ch in value.strip() if ch.isalnum() or ch in ".-+")
        tail += f"_{key.strip().rsplit('.', 1)[-1]}{value}"
    return tail + (f"_np{ranks}" if ranks > 1 else "")


def case_name(soil, q, dx, length=None, sets=(), ranks=1, setup="seed"):
    st = SETUPS[setup]
    length = st.length if length is None else length
    tail = "" if abs(length - st.length) < 1e-12 else f"_L{length:g}"
    return f"{st.prefix}{soil}_q{q:.2f}_dx{dx * 1000:g}mm{tail}{variant_tag(sets, ranks)}"


def scene_raw(soil, q, dx, end_time, length=None, sets=(), ranks=1, setup="seed"):
    """The shipped scene of the set-up with q, dx and end time changed (length: the soil layer's,
    docs/scour_setup.md sec. 2 recommends 0.60 m for long runs of the seed's set-up; the end wall and
    outlet move with it), then the variant's `sets` ("dotted.key=value", as `scoursph run --set`)."""
    from solver.scene import apply_overrides

    st = SETUPS[setup]
    length = st.length if length is None else length
    raw = tomllib.loads(st.scene_path(soil).read_text())
    raw["scene"]["spacing"] = float(dx)
    raw["scene"]["end_time"] = float(end_time)
    raw["scene"]["name"] = case_name(soil, q, dx, length, sets, ranks, setup)
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
    if abs(length - st.length) > 1e-12:
        shift = length - st.length
        raw["domain"]["max"][0] += shift
        raw["blocks"][0]["max"][0] = length
        end = next(b for b in raw["bodies"] if b["name"] == "end wall")
        end["vertices"] = [[x + shift, z] for x, z in end["vertices"]]
        raw["outlets"][0]["min"][0] += shift
        raw["outlets"][0]["max"][0] += shift
    return apply_overrides(raw, sets, st.scene_path(soil))


def solver_commit():
    """The commit the run's code is at (+ "-dirty" with uncommitted changes under solver/)."""
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True, check=True).stdout.strip()  # fmt: skip
        dirty = subprocess.run(["git", "status", "--porcelain", "solver"], cwd=ROOT, capture_output=True,
                               text=True).stdout.strip()  # fmt: skip
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run_case(soil, q, dx, end_time, length=None, threads=1, sets=(), resume=False, setup="seed"):
    """Run one case in this process (on every rank under mpirun); write its summary and scour.csv
    copy into RESULTS/cases. `resume`: continue the case's run directory from its newest checkpoint
    to end_time; its summary's CPU and wall time become the sums over the segments."""
    import numba

    from solver.errors import BlowUpError
    from solver.interrupt import Interrupted
    from solver.parallel.launch import communicator
    from solver.run import run_scene
    from solver.scene import parse_scene

    comm = communicator()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    st = SETUPS[setup]
    length = st.length if length is None else length
    name = case_name(soil, q, dx, length, sets, comm.size, setup)
    scene = parse_scene(scene_raw(soil, q, dx, end_time, length, sets, comm.size, setup), st.scene_path(soil))
    out = RUNS / name
    dest = st.results / "cases"
    before = (
        json.loads((dest / f"{name}.json").read_text()) if resume and (dest / f"{name}.json").exists() else {}
    )
    load0 = os.getloadavg()[0]
    commit = solver_commit()  # the code this segment runs (taken now: the tree may move on while it runs)
    c0, w0 = time.process_time(), time.perf_counter()
    status = "completed"
    try:
        run_scene(scene, out, comm=comm, quiet=True, overwrite=True, restart=out if resume else None)
    except BlowUpError as exc:
        status = f"blew up: {exc}"
    except (KeyboardInterrupt, Interrupted) as exc:  # SIGINT/SIGTERM: run.json, scour.csv and (for
        # Interrupted) a checkpoint are written; `run ... --continue` goes on from it
        status = f"stopped: {exc}"
    cpu = comm.sum(time.process_time() - c0)  # every rank's
    wall = time.perf_counter() - w0
    if not comm.is_root():
        return {"status": status}
    report = json.loads((out / "run.json").read_text())
    segment = {
        "t_start": report["segments"][-1]["t_start"],
        "t_end": report["simulated_time_s"],
        "wall_s": wall,
        "cpu_s": cpu,
        "load_start": load0,
        "load_end": os.getloadavg()[0],
        "solver_commit": commit,
        "continued": bool(resume),
    }
    earlier = before.get("segments") or (  # a summary written before segments were recorded
        [{k: before[k] for k in ("wall_s", "cpu_s", "load_start", "load_end")} | {"t_start": 0.0}]
        if before
        else []
    )
    segments = earlier + [segment]
    summary = {
        "case": name,
        "setup": setup,
        "soil": soil,
        "q": q,
        "dx": dx,
        "length": length,
        "sets": list(sets),
        "ranks": comm.size,
        "end_time": end_time,
        "status": status,
        "t_reached": report["simulated_time_s"],
        "steps": report["steps"],
        "particles_end": report["particles"],
        "wall_s": sum(g["wall_s"] for g in segments),
        "cpu_s": sum(g["cpu_s"] for g in segments),
        "stepping_wall_s": report.get("wall_time_total_s", report["wall_time_s"]),
        "threads": threads,
        "load_start": segments[0]["load_start"],
        "load_end": segment["load_end"],
        "max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "solver_commit": segment["solver_commit"],
        "segments": segments,
        "body_leaks": report.get("body_leaks"),
        "wall_reflections": report.get("wall_reflections"),  # the drift safeguard (issue 15): 0 = walls held
        "volume_balance": report.get("volume_balance"),
    }
    dest.mkdir(parents=True, exist_ok=True)
    (dest / f"{name}.json").write_text(json.dumps(summary, indent=2) + "\n")
    if (out / "scour.csv").exists():
        (dest / f"{name}_scour.csv").write_text((out / "scour.csv").read_text())
        if (out / "scour_profiles.csv").exists():  # the nappe-zone depth (verification/scour_zones.py)
            from verification.scour_zones import add_zone_columns, keep_profiles

            add_zone_columns(dest / f"{name}_scour.csv", out / "scour_profiles.csv")
            keep_profiles(name, out / "scour_profiles.csv", dest)
    print(
        f"{name}: {status}, t = {summary['t_reached']:.4f} s, {wall:.0f} s wall, {cpu:.0f} s CPU"
        + (f" (this segment; {summary['cpu_s']:.0f} s CPU in all)" if len(segments) > 1 else ""),
        flush=True,
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
def load_case(path):
    """One run's summary and its d(t) series (the `_scour.csv` beside the summary)."""
    c = json.loads(path.read_text())
    c.setdefault("sets", [])
    c.setdefault("ranks", 1)
    series = path.with_name(f"{c['case']}_scour.csv")
    rows = list(csv.DictReader(open(series))) if series.exists() else []
    c["t"] = np.array([float(r["t_s"]) for r in rows])
    c["d"] = np.array([float(r["depth_m"]) for r in rows])
    c["x_deepest"] = np.array([float(r["x_deepest_m"]) for r in rows])
    c["eroded"] = np.array([float(r["eroded_area_m2"]) for r in rows])
    # the nappe-zone depth (verification/scour_zones.py); nan where the copy has no zone columns
    zoned = bool(rows) and "depth_nappe_m" in rows[0]
    for key, col in (
        ("d_nappe", "depth_nappe_m"),
        ("x_nappe", "x_deepest_nappe_m"),
        ("d_face", "depth_face_m"),
    ):
        ok = zoned and col in rows[0]
        c[key] = np.array([float(r[col]) for r in rows]) if ok else np.full(len(rows), np.nan)
    return c


def load_cases():
    return [load_case(path) for path in sorted((RESULTS / "cases").glob("*.json"))]


def depth_at(c, t, key="d"):
    """d (key "d_nappe": the nappe-zone depth) at time t (nan if the run did not reach it)."""
    if not len(c["t"]) or c["t"][-1] < t - 1e-9:
        return float("nan")
    return float(np.interp(t, c["t"], c[key]))


def steady_change(c, window=STEADY_WINDOW, key="d", at=None):
    """|d(T) - d(T - window)| / d(T) at T = `at` (default: the time reached; nan before `window`, past
    the end or with d = 0): the issue's "hole stops deepening" test is this < STEADY_CHANGE. key
    "d_nappe": the same for the nappe-zone depth."""
    T = c["t"][-1] if len(c["t"]) and at is None else at
    if T is None or T < window - 1e-9 or not np.isfinite(depth_at(c, T, key)) or depth_at(c, T, key) <= 0:
        return float("nan")
    return abs(depth_at(c, T, key) - depth_at(c, T - window, key)) / depth_at(c, T, key)


def is_base(c):
    """A run of the shipped scene (q, dx, end time, length only): not a variant, not under MPI."""
    return not c["sets"] and c["ranks"] == 1


def variant_label(c):
    """The SENSITIVITY name of a variant's overrides (else the overrides themselves)."""
    names = {v: k for k, v in SENSITIVITY.items()}
    return ", ".join(names.get(item, item) for item in c["sets"]) + (
        f" (np {c['ranks']})" if c["ranks"] > 1 else ""
    )


def residual(c):
    """The largest |volume-balance residual| over materials, in particle volumes."""
    vb = c.get("volume_balance") or {}
    mats = vb.get("materials", {})
    dv = c["dx"] ** 2
    vals = [abs(m.get("residual", 0.0)) / dv for m in mats.values()]
    return max(vals) if vals else float("nan")


def q_exponent_fit(qs, ds):
    """(slope, its standard error, number of points) of the least-squares line of log d against
    log q over the positive depths (the error: residual variance over n - 2, nan with n < 3)."""
    qs, ds = np.asarray(qs, float), np.asarray(ds, float)
    ok = np.isfinite(ds) & (ds > 0)
    n = int(ok.sum())
    if n < 2:
        return float("nan"), float("nan"), n
    x, y = np.log(qs[ok]), np.log(ds[ok])
    slope, icept = np.polyfit(x, y, 1)
    if n < 3:
        return float(slope), float("nan"), n
    res = y - (slope * x + icept)
    se = np.sqrt(res @ res / (n - 2) / ((x - x.mean()) @ (x - x.mean())))
    return float(slope), float(se), n


# the long-run depth of each soil set against the formulas: dry has stopped by 0.25 s (its 1 s
# depth is the model's equilibrium by the issue's < 2 % test); saturated is still deepening at 2 s
LONG_RUN = {"dry": 1.0, "saturated": 2.0}


def formula_exponents():
    """{"formula, grain mapping": (exponent of q in this set-up, depths below the bed at Q_ALL)}
    for the mappings of docs/scour_setup.md sec. 3 plus the threshold-equivalent grain. Left out:
    a formula outside its grain range (Veronese A below 5 mm, Veronese B above) and one that
    predicts no scour at some q (Tschopp's constant term for coarse grains)."""
    from verification.analytic.scour_formulas import PARTICLE, SAND, predictions, threshold_grains

    out = {}
    for grains in (SAND, PARTICLE, threshold_grains()):
        p = predictions(np.array(Q_ALL), grains)
        for name, r in p["formulas"].items():
            if name == "Veronese 1937 A" and grains.d50 < 5e-3:
                continue  # for dm >= 5 mm only (docs/scour_setup.md sec. 5)
            if name == "Veronese 1937 B" and grains.d50 > 5e-3:
                continue  # his grain-free limit, dm < 5 mm
            if np.all(r["below_bed"] > 0) and np.isfinite(r["q_exponent_in_setup"]):
                out[f"{name}, {grains.label}"] = (r["q_exponent_in_setup"], r["below_bed"])
    return out


def _formula_section(cases, fx):
    """SPH long-run d(q) (LONG_RUN) against the formulas: exponent of q and depth ratio."""
    lines = ["", "## Long-run depth against the published formulas", ""]
    lines += [
        "SPH: log-log least-squares exponent of d(q) over the q reached, ± its standard error; formulas:",
        "the range of their exponents in this set-up (H and h_t grow with q) and of the SPH depth over",
        "the formula's equilibrium depth below the bed, over the formulas of each grain mapping above.",
        "",
        "| soil | time (s) | q values | SPH d (mm) | SPH exponent | grain mapping | formula exponents |"
        " SPH d / formula d |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for soil, t in LONG_RUN.items():
        sel = sorted((c for c in cases if c["soil"] == soil and c["dx"] == DX and c["length"] == 0.25),
                     key=lambda c: c["q"])  # fmt: skip
        pts = [(c["q"], depth_at(c, t)) for c in sel if np.isfinite(depth_at(c, t))]
        if len(pts) < 2:
            continue
        qs, ds = (np.array(v) for v in zip(*pts))
        e, se, n = q_exponent_fit(qs, ds)
        maps = {}
        for name, (fe, below) in fx.items():
            label = name.split(", ", 1)[1]
            idx = [Q_ALL.index(round(q, 2)) for q in qs]
            maps.setdefault(label, []).append((fe, ds / np.asarray(below)[idx]))
        for label, rows in maps.items():
            es = [r[0] for r in rows]
            ratios = np.concatenate([r[1] for r in rows])
            lines.append(
                f"| {soil} | {t:g} | {', '.join(f'{q:g}' for q in qs)} | "
                f"{', '.join(f'{1000 * d:.2f}' for d in ds)} | {e:.2f} ± {se:.2f} | {label} | "
                f"{min(es):.2f}-{max(es):.2f} | {ratios.min():.1e}-{ratios.max():.1e} |"
            )
    return lines


def report(out=RESULTS):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    every = load_cases()
    cases = [c for c in every if is_base(c)]  # variants: the sensitivity and MPI sections
    if not cases:
        print("no runs yet: python -m verification.scour_study all", file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    fixed = [t for t in FIXED_TIMES if any(c["t_reached"] >= t - 1e-9 for c in cases)]
    # table
    fields = ["case", "soil", "q", "dx_mm", "status", "t_reached_s"]
    fields += [f"d_{t:g}s_mm" for t in fixed]
    fields += ["d_end_mm", "d_change_last_0.5s_pct", "x_deepest_end_m", "eroded_end_cm2"]
    fields += [f"d_nappe_{t:g}s_mm" for t in fixed]
    fields += ["d_nappe_end_mm", "d_nappe_change_last_0.5s_pct", "x_deepest_nappe_end_m", "d_face_end_mm"]
    fields += ["body_leaks"]
    fields += ["balance_residual_particles", "steps", "particles_end", "wall_s", "cpu_s", "load_start"]
    fields += ["load_end", "threads", "solver"]
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
        row["d_end_mm"] = f"{1000 * c['d'][-1]:.2f}" if len(c["d"]) else ""
        change = steady_change(c)
        row["d_change_last_0.5s_pct"] = f"{100 * change:.0f}" if np.isfinite(change) else ""
        row["x_deepest_end_m"] = f"{c['x_deepest'][-1]:.3f}" if len(c["d"]) else ""
        row["eroded_end_cm2"] = f"{1e4 * c['eroded'][-1]:.1f}" if len(c["d"]) else ""
        for t in fixed:
            v = depth_at(c, t, "d_nappe")
            row[f"d_nappe_{t:g}s_mm"] = "" if not np.isfinite(v) else f"{1000 * v:.2f}"
        zoned = len(c["d"]) and np.isfinite(c["d_nappe"][-1])
        row["d_nappe_end_mm"] = f"{1000 * c['d_nappe'][-1]:.2f}" if zoned else ""
        change = steady_change(c, key="d_nappe")
        row["d_nappe_change_last_0.5s_pct"] = f"{100 * change:.0f}" if np.isfinite(change) else ""
        row["x_deepest_nappe_end_m"] = f"{c['x_nappe'][-1]:.3f}" if zoned else ""
        row["d_face_end_mm"] = f"{1000 * c['d_face'][-1]:.2f}" if zoned else ""
        row["body_leaks"] = c.get("body_leaks")
        row["balance_residual_particles"] = f"{residual(c):.2g}"
        row["steps"] = c["steps"]
        row["particles_end"] = c["particles_end"]
        row["wall_s"] = f"{c['wall_s']:.0f}"
        row["cpu_s"] = f"{c['cpu_s']:.0f}"
        row["load_start"] = f"{c['load_start']:.1f}"
        row["load_end"] = f"{c['load_end']:.1f}"
        row["threads"] = c["threads"]
        row["solver"] = c.get("solver_commit", "")
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
        "d_change_last_0.5s_pct: |d(end) - d(end - 0.5 s)| / d(end); the issue's \"the hole stops",
        'deepening" is < 2. solver: the commit the run was made at (a continued run: its last',
        "segment's; empty: made before the commit was recorded, before 2026-12-01 19:30 on branch scour3).",
        f"d_nappe: the same depth over the nappe zone only, from FACE_ZONE = {FACE_ZONE:g} m beside the",
        f"caisson's face to WALL_ZONE = {WALL_ZONE:g} m before the end wall (scour_zones.py says",
        "why), x_deepest_nappe where it is reached; d_face: the deepest drop within FACE_ZONE of the",
        "caisson's face (the bodies' corner artefact); empty for a run whose profiles were not kept.",
        "",
        "| " + " | ".join(fields) + " |",
        "|" + "---|" * len(fields),
    ]
    lines += ["| " + " | ".join(str(r[k]) for k in fields) + " |" for r in rows]
    # exponents of q
    lines += ["", "## Growth with q", ""]
    lines += [
        "| soil | dx (mm) | time (s) | q values | exponent of q (log-log fit of d, ± standard error) |",
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
                e, se, _ = q_exponent_fit(qs, [depth_at(c, t) for c in sel if np.isfinite(depth_at(c, t))])
                exps[(soil, dx, t)] = e
                lines.append(
                    f"| {soil} | {dx * 1000:g} | {t:g} | {', '.join(f'{q:g}' for q in qs)} | {e:.2f}"
                    + (f" ± {se:.2f}" if np.isfinite(se) else "")
                    + " |"
                )
    lines += _nappe_zone_section(cases)
    fx = formula_exponents()
    lines += ["", "Published formulas in this set-up (verification/analytic/scour_formulas.py, loss-free", ""]
    lines[-2] += " tailwater; equilibrium depths, below the original bed; the layer is 0.095 m deep):"
    lines += ["| formula, grain mapping | exponent of q | depth at q = 0.06 / 0.11 (m) |", "|---|---|---|"]
    for name, (e, below) in fx.items():
        lines.append(f"| {name} | {e:.2f} | {below[0]:.3f} / {below[-1]:.3f} |")
    lines += _formula_section(cases, fx)
    lines += _sensitivity_section(every, out)
    lines += _mpi_section(out)
    (out / "scour_study.md").write_text("\n".join(lines) + "\n")

    _plot_depth_vs_time(plt, cases, out / "depth_vs_time.png")
    _plot_nappe_depth(plt, cases, out / "depth_nappe_vs_time.png")
    _plot_depth_vs_q(plt, cases, fixed, fx, out / "depth_vs_q.png")
    _plot_resolution(plt, cases, out / "resolution.png")
    _plot_snapshots(plt, out / "snapshots_q0.11.png")
    late = tuple(
        t for t in (0.25, 0.5, 1.0, 2.0) if any(c["t_reached"] >= t - 1e-9 and c["q"] == 0.11 for c in cases)
    )
    _plot_snapshots(plt, out / "snapshots_q0.11_late.png", times=late, note="later times")
    _plot_sensitivity(plt, every, out / "sensitivity.png")
    print(f"report in {out}/scour_study.md")
    return 0


STEADY_TIMES = (1.0, 1.5, 2.0, 2.5)  # s: when the "hole stops deepening" test is read (those reached)


def _nappe_zone_section(cases):
    """The nappe-zone depth: growth with q, saturated against dry, and the issue's < 2 % test at
    STEADY_TIMES, each beside the whole-layer d."""
    zoned = [c for c in cases if np.isfinite(c["d_nappe"]).all() and len(c["d_nappe"])]
    if not zoned:
        return []
    lines = ["", "## The nappe-zone depth (d_nappe; verification/scour_zones.py)", ""]
    lines += [
        f"d_nappe: the deepest drop from {FACE_ZONE:g} m beside the caisson's face to {WALL_ZONE:g} m before"
        " the end wall (0.03 ≤ x ≤ 0.15 m in the 0.25 m layer); the whole-layer d beside it.",
        "",
        "| soil | dx (mm) | time (s) | q values | d_nappe (mm) | exponent of q (d_nappe) | d (mm) "
        "| exponent of q (d) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for soil in SOILS:
        for dx in sorted({c["dx"] for c in zoned}):
            sel = sorted((c for c in zoned if c["soil"] == soil and c["dx"] == dx and c["length"] == 0.25),
                         key=lambda c: c["q"])  # fmt: skip
            for t in FIXED_TIMES:
                sel_t = [c for c in sel if np.isfinite(depth_at(c, t))]
                if len(sel_t) < 2:
                    continue
                qs = [c["q"] for c in sel_t]
                dn = [depth_at(c, t, "d_nappe") for c in sel_t]
                d = [depth_at(c, t) for c in sel_t]
                en, sen, _ = q_exponent_fit(qs, dn)
                e, se, _ = q_exponent_fit(qs, d)
                lines.append(
                    f"| {soil} | {dx * 1000:g} | {t:g} | {', '.join(f'{q:g}' for q in qs)} | "
                    f"{', '.join(f'{1000 * v:.2f}' for v in dn)} | {en:.2f} ± {sen:.2f} | "
                    f"{', '.join(f'{1000 * v:.2f}' for v in d)} | {e:.2f} ± {se:.2f} |"
                )
    lines += [
        "",
        'The issue\'s "the hole stops deepening" (d changing < 2 % over 0.5 s) at each time reached,',
        "for d_nappe and (in brackets) d; x: where d_nappe is at that time (m).",
        "",
        "| case | " + " | ".join(f"{t:g} s" for t in STEADY_TIMES) + " |",
        "|---|" + "---|" * len(STEADY_TIMES),
    ]
    for c in sorted(zoned, key=lambda c: (c["dx"], c["length"], c["soil"], c["q"])):
        cells = []
        for t in STEADY_TIMES:
            if c["t_reached"] < t - 1e-9:
                cells.append("")
                continue
            a, b = steady_change(c, key="d_nappe", at=t), steady_change(c, at=t)
            xn = float(np.interp(t, c["t"], c["x_nappe"]))
            cells.append(f"{100 * a:.1f} % ({100 * b:.1f} %), x = {xn:.3f}")
        lines.append(f"| {c['case']} | " + " | ".join(cells) + " |")
    return lines


def sensitivity_cases(cases):
    """(base, [variants]) of the sensitivity study: the base run of SENSITIVITY_CASE at 5 mm and its
    serial variants (None, [] when there are none)."""
    soil, q = SENSITIVITY_CASE
    same = [
        c
        for c in cases
        if c["soil"] == soil and abs(c["q"] - q) < 1e-9 and c["dx"] == DX and c["length"] == 0.25
    ]
    base = next((c for c in same if is_base(c)), None)
    if SENSITIVITY_BASE is not None and (RESULTS / SENSITIVITY_BASE).exists():
        base = load_case(RESULTS / SENSITIVITY_BASE) | {"kept_in": SENSITIVITY_BASE}
    return base, [c for c in same if c["sets"] and c["ranks"] == 1]


def _sensitivity_section(cases, out):
    base, variants = sensitivity_cases(cases)
    if base is None or not variants:
        return []
    end = min(c["t_reached"] for c in variants)
    times = [t for t in (0.025, 0.1, 0.25, 0.5, 1.0) if t <= end + 1e-9]
    soil, q = SENSITIVITY_CASE
    lines = [
        "",
        f"## Sensitivity ({soil}, q = {q:g}, 5 mm; to {end:g} s, the end time all variants reached)",
        "",
        f"Each variant is the base scene with one override (`SENSITIVITY` in verification/scour_study.py,"
        f" `--set`). d in mm; in brackets d / d_base at the same time. Base: {base['case']} (solver "
        f"{base.get('solver_commit', '?')}"
        + (f"; the run on the variants' solver, kept in {base['kept_in']}" if "kept_in" in base else "")
        + ").",
        "",
        "| variant | override | "
        + " | ".join(f"d {t:g} s" for t in times)
        + f" | eroded {end:g} s (cm²) | body leaks | balance residual | steps | wall (s) | CPU (s)"
        " | load start/end | solver |",
        "|---|---|" + "---|" * (len(times) + 8),
    ]
    rows = [base] + sorted(variants, key=lambda c: list(SENSITIVITY.values()).index(c["sets"][0])
                           if c["sets"][0] in SENSITIVITY.values() else 99)  # fmt: skip
    for c in rows:
        cells = []
        for t in times:
            d, d0 = depth_at(c, t), depth_at(base, t)
            ratio = f" ({d / d0:.2f})" if c is not base and np.isfinite(d) and d0 > 0 else ""
            cells.append(f"{1000 * d:.2f}{ratio}" if np.isfinite(d) else "")
        a, a0 = (float(np.interp(end, k["t"], k["eroded"])) for k in (c, base))
        cells.append(f"{1e4 * a:.3f}" + (f" ({a / a0:.2f})" if c is not base and a0 > 0 else ""))
        lines.append(
            f"| {'base' if c is base else variant_label(c)} | {'; '.join(c['sets']) or '(none)'} | "
            + " | ".join(cells)
            + f" | {c.get('body_leaks')} | {residual(c):.2g} | {c['steps']} | {c['wall_s']:.0f}"
            f" | {c['cpu_s']:.0f} | {c['load_start']:.1f}/{c['load_end']:.1f} | {c.get('solver_commit', '')}|"
        )
    lines += ["", "(base wall/CPU: its whole run, which may be longer than the variants'.)"]
    return lines


def _mpi_section(out):
    paths = sorted(out.glob("compare_*.json"))
    if not paths:
        return []
    lines = ["", "## Under mpirun (written by `python -m verification.scour_study compare A B`)", ""]
    lines += [
        "| run | against | times compared | max abs(d difference) (mm) | max position difference (m) "
        "| max velocity difference (m/s) | particle count, ids | CPU A / B (s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for path in paths:
        r = json.loads(path.read_text())
        lines.append(
            f"| {r['b']} | {r['a']} | {r['times'][0]:g}-{r['times'][-1]:g} s ({len(r['times'])}) | "
            f"{1000 * r['max_depth_difference_m']:.3g} | {r['max_position_difference_m']:.3g} | "
            f"{r['max_velocity_difference_m_s']:.3g} | {r['ids']} | {r['cpu_a_s']:.0f} / {r['cpu_b_s']:.0f} |"
        )
    return lines


def compare(a, b, out=RESULTS):
    """Two runs of the same case (e.g. serial and mpirun -n 2): d(t) and the particle state (matched
    by id) at every snapshot time both reached; written to RESULTS/compare_<b>_vs_<a>.json."""
    from solver.output.hdf5_writer import read_series

    cases = {c["case"]: c for c in load_cases()}
    sa, sb = (dict((round(t, 9), f) for t, f in read_series(RUNS / n / "particles.h5")) for n in (a, b))
    times = sorted(set(sa) & set(sb))
    dx_max = dv_max = dd_max = 0.0
    ids = "same"
    for t in times:
        fa, fb = sa[t], sb[t]
        if not np.array_equal(fa["id"], fb["id"]):
            ids = f"differ at t = {t:g} s ({len(fa['id'])} / {len(fb['id'])})"
            break
        dx_max = max(dx_max, float(np.abs(fa["position"] - fb["position"]).max()))
        dv_max = max(dv_max, float(np.abs(fa["velocity"] - fb["velocity"]).max()))
        dd_max = max(dd_max, abs(depth_at(cases[a], t) - depth_at(cases[b], t)))
    result = {
        "a": a, "b": b, "times": times, "ids": ids, "max_position_difference_m": dx_max,
        "max_velocity_difference_m_s": dv_max, "max_depth_difference_m": dd_max,
        "cpu_a_s": cases[a]["cpu_s"], "cpu_b_s": cases[b]["cpu_s"],
        "wall_a_s": cases[a]["wall_s"], "wall_b_s": cases[b]["wall_s"],
    }  # fmt: skip
    (out / f"compare_{b}_vs_{a}.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return result


def _plot_sensitivity(plt, cases, path):
    base, variants = sensitivity_cases(cases)
    if base is None or not variants:
        return
    end = max(c["t_reached"] for c in variants)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    k = base["t"] <= end + 1e-9
    ax.plot(
        base["t"][k],
        1000 * base["d"][k],
        "k-",
        lw=2,
        label="base" + (" (variants' solver)" if "kept_in" in base else ""),
    )
    same = ("soil", "q", "dx", "length")
    current = next((c for c in cases if is_base(c) and all(c.get(k) == base.get(k) for k in same)), None)
    if "kept_in" in base and current is not None:
        k = current["t"] <= end + 1e-9
        ax.plot(current["t"][k], 1000 * current["d"][k], "k--", lw=1.5, label="base on the current solver")
    for c in variants:
        ax.plot(c["t"], 1000 * c["d"], "-", label=variant_label(c))
    ax.set_xlabel("t (s)")
    ax.set_ylabel("scour depth d (mm)")
    ax.set_title(f"sensitivity: {SENSITIVITY_CASE[0]}, q = {SENSITIVITY_CASE[1]}, 5 mm")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


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


def _plot_nappe_depth(plt, cases, path):
    """d_nappe(t) per q (solid) beside the whole-layer d(t) (dotted), dry and saturated, 5 mm."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), sharey=True)
    cmap = plt.get_cmap("viridis")
    for ax, soil in zip(axes, SOILS):
        sel = sorted((c for c in cases if c["soil"] == soil and c["dx"] == DX and c["length"] == 0.25
                      and np.isfinite(c["d_nappe"]).all()), key=lambda c: c["q"])  # fmt: skip
        for c in sel:
            colour = cmap((c["q"] - 0.06) / 0.05 * 0.9)
            ax.plot(c["t"], 1000 * c["d_nappe"], "-", color=colour, label=f"q = {c['q']:.2f} m²/s")
            ax.plot(c["t"], 1000 * c["d"], ":", color=colour, lw=0.9)
        ax.set_ylim(0.0, 1.6)
        zone = f"{FACE_ZONE:g} ≤ x ≤ L − {WALL_ZONE:g} m"
        ax.set_title(f"{soil}, 5 mm: d_nappe ({zone}), dotted: whole-layer d", fontsize=9)
        ax.set_xlabel("t (s)")
        ax.legend(fontsize=8)
    axes[0].set_ylabel("scour depth (mm); d clipped at 1.6 mm")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
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
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    nappe = f"d_nappe ({FACE_ZONE:g} ≤ x ≤ L − {WALL_ZONE:g} m)"
    for ax, key, what in zip(axes, ("d", "d_nappe"), ("whole-layer d", nappe)):
        for c in fine:
            coarse = next(
                (k for k in cases if k["dx"] == DX and k["soil"] == c["soil"] and k["q"] == c["q"]
                 and k["length"] == c["length"]), None)  # fmt: skip
            (line,) = ax.plot(c["t"], 1000 * c[key], "-", label=f"{c['soil']}, q = {c['q']:.2f}, 2.5 mm")
            if coarse is not None:
                ax.plot(coarse["t"], 1000 * coarse[key], "--", color=line.get_color(), label="same, 5 mm")
        ax.set_xlim(0.0, 1.05 * max(c["t_reached"] for c in fine))  # where both resolutions have data
        ax.set_xlabel("t (s)")
        ax.set_ylabel(f"{what} (mm)")
        ax.set_title(f"resolution, {what}: 5 mm against 2.5 mm", fontsize=9)
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


def run_all(cases, jobs=1, nice=10, setup="seed"):
    """Run the cases not yet in the set-up's cases/ (or shorter there than asked), `jobs` processes at
    a time, each a separate `nice`d process with one Numba thread. A case is (soil, q, dx, end,
    length) or (soil, q, dx, end, length, sets); length None: the set-up's."""
    st = SETUPS[setup]
    todo = []
    for soil, q, dx, end, length, *rest in cases:
        sets = tuple(rest[0]) if rest else ()
        length = st.length if length is None else length
        done = st.results / "cases" / f"{case_name(soil, q, dx, length, sets, setup=setup)}.json"
        if done.exists() and json.loads(done.read_text())["t_reached"] >= end - 1e-9:
            continue
        todo.append((soil, q, dx, end, length, sets))
    running = []
    for soil, q, dx, end, length, sets in todo:
        while len(running) >= jobs:
            running = [p for p in running if p.poll() is None]
            time.sleep(2)
        cmd = ["nice", "-n", str(nice), sys.executable, "-m", "verification.scour_study", "run", soil, str(q),
               "--dx", str(dx), "--end", str(end), "--length", str(length), "--setup", setup]  # fmt: skip
        cmd += [f"--set={item}" for item in sets]
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
    r.add_argument("--length", type=float, default=None, help="soil layer length (m; default: the set-up's)")
    r.add_argument("--setup", choices=tuple(SETUPS), default="seed",
                   help="seed: the seed's drowned overflow; plunging: issue 24's plunging nappe")  # fmt: skip
    r.add_argument("--threads", type=int, default=1)
    r.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="a scene override (as scoursph run --set), named in the case: a variant")  # fmt: skip
    r.add_argument("--continue", dest="resume", action="store_true",
                   help="continue the case's run from its newest checkpoint to --end")  # fmt: skip
    sn = sub.add_parser("sensitivity", help="the SENSITIVITY variants of SENSITIVITY_CASE, one at a time")
    sn.add_argument("--end", type=float, default=0.5)
    sn.add_argument("--only", action="append", choices=tuple(SENSITIVITY), help="these variants only")
    cp = sub.add_parser("compare", help="two runs of one case (serial / mpirun): d(t) and particles by id")
    cp.add_argument("a", help="case name, e.g. saturated_q0.11_dx5mm")
    cp.add_argument("b", help="case name, e.g. saturated_q0.11_dx5mm_np2")
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
        from solver.errors import SceneError

        try:
            s = run_case(
                args.soil,
                args.q,
                args.dx,
                args.end,
                args.length,
                args.threads,
                args.set,
                args.resume,
                args.setup,
            )
        except SceneError as exc:  # a bad --set: exit 2 naming the file and key
            print(f"scour_study: {exc}", file=sys.stderr)
            return 2
        return 0 if s["status"] == "completed" else 1
    if args.cmd == "compare":
        compare(args.a, args.b)
    if args.cmd == "finish":
        finish_case(args.soil, args.q, args.dx, args.length, args.cpu, args.wall)
    if args.cmd == "sensitivity":
        soil, q = SENSITIVITY_CASE
        names = args.only or tuple(SENSITIVITY)
        run_all([(soil, q, DX, args.end, 0.25, (SENSITIVITY[n],)) for n in names], jobs=1)
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
