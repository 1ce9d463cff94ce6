"""The figures and table of docs/scour_long_layer.md: the saturated scour in the 0.60 m layer against
the 0.25 m layer at the same q (issue 11 item 6: does the end wall make the 0.25 m layer's late
deepening?).

    python docs/figures/scour_long_layer.py                       # 0.25 m cases from this checkout
    python docs/figures/scour_long_layer.py --ref-cases DIR --ref-profiles DIR   # another helper's reruns

Inputs: the study's case summaries and scour.csv copies (verification/results/scour/cases/<case>.json
and <case>_scour.csv, written by `python -m verification.scour_study run ... --length 0.6`) and the
surface profiles z_s(x, t) (<case>_profiles.csv, a copy of the run's scour_profiles.csv, kept in
verification/results/scour/long_layer/ because the run directories are not committed).

Where the hole is. d(t) is the study's (solver/output/scour.py: max over x of z_s0 - z_s). Its
maximum is split here by where along the layer it is reached:
  d_nappe: over 0 <= x <= NAPPE_ZONE (the first impact's dent lies at x = 0.03-0.13 m, and the nappe
           lands within 0.2 m in the rigid-bed cross-check of docs/scour_setup.md sec. 6);
  d_wall:  over the last WALL_ZONE before the end wall (the 0.25 m layer's trough and row loss at
           x = 0.19-0.2475 m lie in it).
Writes docs/figures/scour_long_layer.png (d, x of the deepest point, eroded area, d by zone) and
docs/figures/scour_long_layer_profiles.png (z_s - z_s0 along the layer at fixed times), and prints
the table of the doc.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from verification.scour_study import STEADY_CHANGE, STEADY_WINDOW, case_name  # noqa: E402

CASES = ROOT / "verification" / "results" / "scour" / "cases"
PROFILES = ROOT / "verification" / "results" / "scour" / "long_layer"
OUT = Path(__file__).with_name("scour_long_layer.png")
OUT_PROFILES = Path(__file__).with_name("scour_long_layer_profiles.png")
OUT_SNAPSHOTS = Path(__file__).with_name("scour_long_layer_snapshots.png")
RUNS = ROOT / "runs" / "scour_study"
SNAPSHOT_TIMES = (0.1, 0.5, 1.0, 2.0, 3.0)
NAPPE_ZONE = 0.15  # m from the breakwater face
WALL_ZONE = 0.06  # m before the end wall
PROFILE_TIMES = (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)


def load(case, cases_dir, profiles_dir, tag):
    """The case's summary, its d(t) series and (if present) its surface profiles; tag names the run."""
    summary = json.loads((cases_dir / f"{case}.json").read_text())
    rows = list(csv.DictReader(open(cases_dir / f"{case}_scour.csv")))
    c = {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}
    c["summary"] = summary
    c["L"] = summary.get("length", 0.25)
    c["tag"] = tag
    prof = profiles_dir / f"{case}_profiles.csv"
    if prof.exists():
        with open(prof) as f:
            head = next(csv.reader(f))
        data = np.loadtxt(prof, delimiter=",", skiprows=1)
        c["px"] = data[:, 0]
        c["pt"] = np.array([float(h.split("=")[1].rstrip(")")) for h in head[1:]])
        c["pz"] = data[:, 1:]  # (bins, times)
        drop = c["pz"][:, :1] - c["pz"]
        nappe = c["px"] <= NAPPE_ZONE
        wall = c["px"] >= c["L"] - WALL_ZONE
        c["d_nappe"] = np.maximum(drop[nappe].max(axis=0), 0.0)
        c["d_wall"] = np.maximum(drop[wall].max(axis=0), 0.0)
    return c


def at(t, ts, ys):
    return float(np.interp(t, ts, ys)) if ts[-1] >= t - 1e-9 else float("nan")


def steady(ts, ds, T):
    """|d(T) - d(T - 0.5 s)| / d(T): the issue's "stops deepening" test is this < 2 %."""
    if T < STEADY_WINDOW - 1e-9 or ts[-1] < T - 1e-9:
        return float("nan")
    dT = at(T, ts, ds)
    return abs(dT - at(T - STEADY_WINDOW, ts, ds)) / dT if dT > 0 else float("nan")


def label(c):
    return f"L = {c['L']:.2f} m ({c['tag']})"


def figure(runs, q):
    fig, axs = plt.subplots(2, 2, figsize=(12, 8), constrained_layout=True)
    ax = axs[0, 0]
    for c, col in runs:
        ax.plot(c["t_s"], c["depth_m"] * 1e3, color=col, label=label(c))
    ax.set(xlabel="t (s)", ylabel="d (mm)", title=f"(a) scour depth d(t), saturated q = {q:.2f} m²/s")
    ax.legend(fontsize=8)
    ax = axs[0, 1]
    for c, col in runs:
        ax.plot(c["t_s"], c["x_deepest_m"], ".", ms=3, color=col, label=label(c))
        ax.axhline(c["L"], color=col, lw=0.8, ls=":")
    ax.set(xlabel="t (s)", ylabel="x of the deepest point (m)",
           title="(b) where d is reached (dotted: each run's end wall)")  # fmt: skip
    ax.legend(fontsize=8)
    ax = axs[1, 0]
    for c, col in runs:
        ax.plot(c["t_s"], c["eroded_area_m2"] * 1e4, color=col, label=label(c) + " eroded")
        ax.plot(c["t_s"], c["deposited_area_m2"] * 1e4, color=col, ls="--", label="deposited")
    ax.set(xlabel="t (s)", ylabel="area (cm²)", title="(c) eroded (solid) and deposited (dashed) area")
    ax.legend(fontsize=8)
    ax = axs[1, 1]
    for c, col in runs:
        if "pt" not in c:
            continue
        ax.plot(c["pt"], c["d_nappe"] * 1e3, color=col, label=f"L = {c['L']:.2f} m, x ≤ {NAPPE_ZONE} m")
        ax.plot(c["pt"], c["d_wall"] * 1e3, color=col, ls="--",
                label=f"L = {c['L']:.2f} m, last {WALL_ZONE} m before the end wall")  # fmt: skip
    ax.set(xlabel="t (s)", ylabel="deepest drop in the zone (mm)",
           title="(d) under the nappe (solid) and at the end wall (dashed)")  # fmt: skip
    ax.legend(fontsize=8)
    fig.savefig(OUT, dpi=120)


def profiles_figure(runs, q):
    with_p = [(c, col) for c, col in runs if "pt" in c]
    fig, axs = plt.subplots(len(with_p), 1, figsize=(12, 3.2 * len(with_p)), constrained_layout=True,
                            squeeze=False)  # fmt: skip
    cmap = plt.get_cmap("viridis")
    xmax = max(c["L"] for c, _ in with_p)
    for ax, (c, _) in zip(axs[:, 0], with_p):
        for i, t in enumerate(PROFILE_TIMES):
            k = np.flatnonzero(np.abs(c["pt"] - t) < 1e-6)
            if not len(k):
                continue
            ax.plot(c["px"], (c["pz"][:, k[0]] - c["pz"][:, 0]) * 1e3, color=cmap(i / len(PROFILE_TIMES)),
                    label=f"t = {t:g} s")  # fmt: skip
        ax.axhline(0, color="k", lw=0.5)
        ax.axvline(c["L"], color="grey", lw=3)
        ax.axvspan(0, NAPPE_ZONE, color="tab:blue", alpha=0.06)
        ax.axvspan(c["L"] - WALL_ZONE, c["L"], color="tab:red", alpha=0.06)
        ax.set(xlim=(0, xmax + 0.01), xlabel="x (m)", ylabel="z_s - z_s0 (mm)",
               title=f"{label(c)}: surface change, saturated q = {q:.2f} m²/s "
               f"(shaded: the nappe zone and the end-wall zone)")  # fmt: skip
        ax.legend(fontsize=8, ncol=3)
    fig.savefig(OUT_PROFILES, dpi=120)


def snapshots_figure(case, L, q):
    """Particles of the long run at SNAPSHOT_TIMES (those reached): water blue, sand coloured by its
    horizontal displacement since t = 0 (by particle id), and the last snapshot. Needs the run's HDF5
    series (not committed)."""
    from solver.output.hdf5_writer import read_series

    path = RUNS / case / "particles.h5"
    if not path.exists():
        print(f"no {path}: snapshot figure skipped")
        return
    series = read_series(path)
    t0, f0 = series[0]
    sand0 = f0["material"] == 1
    x0 = dict(zip(f0["id"][sand0], f0["position"][sand0, 0]))
    picks = [(t, f) for t, f in series if any(abs(t - ts) < 1e-6 for ts in SNAPSHOT_TIMES)]
    if series[-1][0] > picks[-1][0] + 1e-9:  # and the last time reached
        picks.append(series[-1])
    height = 3.5 * len(picks) + 0.6
    fig, axs = plt.subplots(len(picks), 1, figsize=(10, height), squeeze=False)
    fig.subplots_adjust(left=0.07, right=0.88, top=1 - 0.5 / height, bottom=0.05, hspace=0.35)
    for ax, (t, f) in zip(axs[:, 0], picks):
        x, m = f["position"], f["material"]
        w = m == 0
        ax.scatter(x[w, 0], x[w, 1], s=1.0, c="tab:blue", alpha=0.35, lw=0)
        s_ = m == 1
        dxs = np.array([x[k, 0] - x0.get(i, x[k, 0]) for k, i in zip(np.flatnonzero(s_), f["id"][s_])])
        sc = ax.scatter(x[s_, 0], x[s_, 1], c=dxs * 1e3, cmap="magma_r", vmin=0, vmax=2, lw=0,
                        s=3.0)  # fmt: skip
        ax.fill([-0.05, 0, 0, -0.05], [0, 0, 0.105, 0.105], color="grey")
        ax.fill([L, L + 0.03, L + 0.03, L], [0, 0, 0.095, 0.095], color="grey")
        ax.set(xlim=(-0.055, L + 0.035), ylim=(0, 0.23), aspect="equal")
        ax.set_title(f"t = {t:g} s", fontsize=9, loc="left")
    fig.colorbar(sc, cax=fig.add_axes([0.9, 0.2, 0.015, 0.6]), label="sand: x - x(0) (mm)")
    fig.suptitle(f"{case}: water (blue), sand by its downstream displacement; saturated q = {q:.2f} m²/s")
    fig.savefig(OUT_SNAPSHOTS, dpi=110)


def table(runs):
    """The doc's table: d at fixed times, then d, its place, d by zone and the eroded area at tc, the
    latest output time every run has (so the layers are compared at one time), and the run's cost."""
    tc = min(float(c["t_s"][-1]) for c, _ in runs)  # the last output time every run has
    print(
        f"| run | t reached (s) | d 0.5 / 1 / 1.5 / 2 / 3 s (mm) | at tc = {tc:g} s: d (mm) | x deepest (m) "
        "| d_nappe (mm) | d_wall (mm) | eroded (cm²) | change over the last 0.5 s "
        "| CPU (s) | wall (s) | load | leaks | balance residual (particle volumes) |"
    )
    print("|" + "---|" * 14)
    for c, _ in runs:
        s = c["summary"]
        T = s["t_reached"]
        d = " / ".join(f"{at(t, c['t_s'], c['depth_m']) * 1e3:.2f}" for t in (0.5, 1.0, 1.5, 2.0, 3.0))
        zone = [at(tc, c["pt"], c[k]) * 1e3 if "pt" in c else float("nan") for k in ("d_nappe", "d_wall")]
        vb = s.get("volume_balance") or {}
        pv = vb.get("particle_volume", float("nan"))
        res = max((abs(m["residual"]) for m in vb.get("materials", {}).values()), default=float("nan"))
        loads = [g.get("load_start", float("nan")) for g in s.get("segments", [])] + [s.get("load_end")]
        print(
            f"| {label(c)} | {T:g} | {d} | {at(tc, c['t_s'], c['depth_m']) * 1e3:.2f} "
            f"| {at(tc, c['t_s'], c['x_deepest_m']):.4f} | {zone[0]:.2f} | {zone[1]:.2f} "
            f"| {at(tc, c['t_s'], c['eroded_area_m2']) * 1e4:.3f} | {steady(c['t_s'], c['depth_m'], T):.1%} "
            f"(at {T:g} s) | {s['cpu_s']:.0f} | {s['wall_s']:.0f} | {min(loads):.1f}-{max(loads):.1f} "
            f"| {s.get('body_leaks')} | {res / pv:.1e} |"
        )
    print(f"\n(stopped deepening: change < {STEADY_CHANGE:.0%} over {STEADY_WINDOW} s)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--q", type=float, default=0.11)
    ap.add_argument("--ref-cases", type=Path, default=CASES, help="where the 0.25 m case files are")
    ap.add_argument("--ref-profiles", type=Path, default=PROFILES, help="where the 0.25 m profiles are")
    ap.add_argument("--old-ref", type=Path, default=None,
                    help="also draw an older 0.25 m run (its case files' dir)")  # fmt: skip
    ap.add_argument("--old-profiles", type=Path, default=PROFILES)
    ap.add_argument("--long-cases", type=Path, default=CASES, help="where the 0.60 m case files are")
    ap.add_argument("--long-profiles", type=Path, default=PROFILES)
    args = ap.parse_args(argv)
    short = case_name("saturated", args.q, 0.005)
    runs = []
    if args.old_ref is not None:
        runs.append((load(short, args.old_ref, args.old_profiles, "before seep5"), "tab:grey"))
    runs.append((load(short, args.ref_cases, args.ref_profiles, "main"), "tab:orange"))
    long = case_name("saturated", args.q, 0.005, 0.6)
    runs.append((load(long, args.long_cases, args.long_profiles, "main"), "tab:blue"))
    figure(runs, args.q)
    profiles_figure(runs, args.q)
    snapshots_figure(case_name("saturated", args.q, 0.005, 0.6), 0.6, args.q)
    table(runs)


if __name__ == "__main__":
    main()
