"""The plunging scour study (issue 24 item 4): the overflow made to plunge onto an eroding sand layer,
dry and saturated, six q, and its convergence at 5, 3.5 and 2.5 mm.

    python -m verification.scour_plunging run-all               # every missing run (hours), then the report
    python -m verification.scour_plunging run-all --only convergence
    python -m verification.scour_plunging report                # tables and figures from the runs made
    python -m verification.scour_study run saturated 0.11 --setup plunging --dx 0.0025 --end 1.0   # one run

The set-up is solver/scenes/scour_plunging_{dry,saturated}.toml, a sand with a state (docs/sand.md;
`--setup plunging_seed_sand`: issue 24's runs with the seed's sand, scour_plunging_seed_sand_*.toml)
(docs/scour_plunging.md: a 0.15 m
fall so that the nappe plunges, a 0.63 m layer, a free overfall downstream, 0.5 mm sand that erodes,
docs/erosion.md). The runs go through verification/scour_study.py's machinery (`--setup plunging`):
each leaves a summary and its d(t) series in verification/results/scour_plunging_state/cases/
(verification/results/scour_plunging/cases/ for the seed's sand).

The depth. d_jet(t): the deepest drop of the bed surface (solver/output/scour.py: the kernel soil
fraction's 1/2 contour of the bed, suspended soil left out, a surface particle thinned by its worn
share) over FACE_ZONE <= x <= L - WALL_ZONE (verification/scour_zones.py's zone columns: the
caisson's face and the end wall's last 0.10 m left out). The whole-layer d is kept beside it.

Convergence (the issue: "scour depth converging (5, 3.5, 2.5 mm within 10 %)"): at each time of
COMPARE_TIMES the relative difference of d_jet at 5 and at 3.5 mm to d_jet at 2.5 mm, against 10 %.
The formulas (verification/analytic/scour_formulas.py, without tuning): the equilibrium depths
below the original bed of the published plunging-jet formulas in this set-up (fall 0.15 m, the
loss-free supercritical tailwater, the scenes' sand), beside the SPH depth reached.
"""

from __future__ import annotations

import argparse
import csv
import sys

import numpy as np

from verification.scour_study import (
    DX,
    DX_FINE,
    Q_ALL,
    SETUPS,
    SOILS,
    depth_at,
    is_base,
    load_case,
    q_exponent_fit,
    run_all,
)

PLUNGING_SETUPS = ("plunging", "plunging_seed_sand")  # the sand with a state (issue 31) and the seed's sand
FALL = 0.15  # m, the crown above the soil surface in the scenes (docs/scour_plunging.md)
DX_MID = 0.0035
SPACINGS = (DX, DX_MID, DX_FINE)
END = 1.0  # s simulated: the affordable length on this 2-core machine (docs/scour_plunging.md, Cost)
COMPARE_TIMES = (0.25, 0.5, 1.0)  # s: the runs table's and the snapshots' times
CONVERGENCE_TIMES = (0.1, 0.25, 0.5, 0.65, 1.0)  # s: where the convergence is read (0.65: the 2.5 mm
# saturated run stopped at 0.698 s for want of time)
CONVERGENCE_Q = 0.11
CONVERGENCE_TOLERANCE = 0.10  # the "within 10 %"
SAND_LABEL = "0.5 mm sand (d90 1 mm)"


def convergence_cases(end=END):
    return [(soil, CONVERGENCE_Q, dx, end, None) for dx in SPACINGS for soil in SOILS]


def sweep_cases(end=END):
    return [(soil, q, DX, end, None) for q in Q_ALL for soil in SOILS]


def load_cases(setup="plunging"):
    return [load_case(p) for p in sorted((SETUPS[setup].results / "cases").glob("*.json"))]


def d_jet(c, t):
    """The jet-zone depth (scour_zones' d_nappe columns) at t; nan if not reached."""
    return depth_at(c, t, "d_nappe")


def convergence_rows(cases):
    """Per soil and time: d_jet at each spacing and the differences to the finest reached (2.5 mm, or
    3.5 mm where the 2.5 mm run did not reach t), as dicts; "ref" names the spacing compared with."""
    rows = []
    for soil in SOILS:
        by_dx = {c["dx"]: c for c in cases if c["soil"] == soil and abs(c["q"] - CONVERGENCE_Q) < 1e-9}
        for t in CONVERGENCE_TIMES:
            depth = {dx: d_jet(by_dx[dx], t) if dx in by_dx else float("nan") for dx in SPACINGS}
            reached = [dx for dx in (DX_FINE, DX_MID) if np.isfinite(depth[dx]) and depth[dx] > 0]
            if not reached or not np.isfinite(depth[DX]):
                continue
            ref = reached[0]
            row = {"soil": soil, "t": t, "ref": ref, "fine": depth[DX_FINE]}
            for dx in (DX, DX_MID):
                row[dx] = depth[dx]
                row[f"rel_{dx}"] = (depth[dx] - depth[ref]) / depth[ref] if dx != ref else float("nan")
            rows.append(row)
    return rows


CURVE_FROM = 0.1  # s: the d(t) curves are compared from here (before it the hole is a row or two deep)


def curve_differences(cases):
    """Per soil with a 2.5 mm run at q = CONVERGENCE_Q: the mean |d_jet(dx) - d_jet(2.5 mm)| over the
    common times CURVE_FROM..end (0.025 s apart) over the mean d_jet(2.5 mm), and the largest pointwise
    relative difference, for dx = 5 and 3.5 mm. The curve's mean reads the whole growth, not a time
    where one spacing has just lost a row and the other not yet."""
    out = []
    for soil in SOILS:
        by_dx = {c["dx"]: c for c in cases if c["soil"] == soil and abs(c["q"] - CONVERGENCE_Q) < 1e-9}
        if DX_FINE not in by_dx:
            continue
        end = min(min(c["t"][-1] for c in by_dx.values()), END)
        t = np.arange(CURVE_FROM, end + 1e-9, 0.025)
        fine = np.interp(t, by_dx[DX_FINE]["t"], by_dx[DX_FINE]["d_nappe"])
        row = {"soil": soil, "end": float(t[-1])}
        for dx in (DX, DX_MID):
            if dx in by_dx:
                d = np.interp(t, by_dx[dx]["t"], by_dx[dx]["d_nappe"])
                row[dx] = (
                    float(np.mean(np.abs(d - fine)) / np.mean(fine)),
                    float(np.max(np.abs(d - fine) / fine)),
                )
        out.append(row)
    return out


def _curve_section(rows):
    lines = [
        "",
        f"The whole curve d_jet(t), {CURVE_FROM:g} s to the end all spacings reached: mean |d − d(2.5 mm)|",
        "over mean d(2.5 mm) (the largest pointwise difference in brackets):",
        "",
        "| soil | to (s) | 5 mm | 3.5 mm | mean within 10 % |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        cells = [
            f"{100 * r[dx][0]:.1f} % ({100 * r[dx][1]:.1f} %)" if dx in r else "-" for dx in (DX, DX_MID)
        ]
        ok = all(r[dx][0] <= CONVERGENCE_TOLERANCE for dx in (DX, DX_MID) if dx in r)
        lines.append(f"| {r['soil']} | {r['end']:.3g} | {cells[0]} | {cells[1]} | {'yes' if ok else 'no'} |")
    return lines


def _seconds(s):
    return f"{s:.0f}" if np.isfinite(s) else "not measured"


def _load(c):
    """The 1-min load average at the run's start and end ("-" for a summary written afterwards)."""
    if "load_start" not in c:
        return "-"
    return f"{c['load_start']:.1f}-{c['load_end']:.1f}"


def _runs_section(cases):
    from verification.scour_study import residual

    lines = [
        "## Runs",
        "",
        "| case | t reached (s) | d_jet at " + " / ".join(f"{t:g}" for t in COMPARE_TIMES) + " s (mm) "
        "| x of d_jet at the end (m) | d at the end (mm) | steps | particles | CPU (s) | wall (s) | load "
        "| body leaks | balance residual (particle volumes) | solver |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for c in sorted(cases, key=lambda c: (-c["dx"], c["soil"], c["q"])):
        ds = " / ".join(
            f"{1000 * d_jet(c, t):.2f}" if np.isfinite(d_jet(c, t)) else "-" for t in COMPARE_TIMES
        )
        lines.append(
            f"| {c['case']} | {c['t_reached']:.3f} | {ds} | {c['x_nappe'][-1]:.3f} | {1000 * c['d'][-1]:.2f} "
            f"| {c['steps']} | {c['particles_end']} | {_seconds(c['cpu_s'])} | {_seconds(c['wall_s'])} "
            f"| {_load(c)} "
            f"| {c.get('body_leaks')} | {residual(c):.1g} | {c.get('solver_commit', '')} |"
        )
    return lines


def _convergence_section(conv):
    lines = [
        "",
        f"## Convergence (q = {CONVERGENCE_Q} m²/s; the issue's tolerance "
        f"{100 * CONVERGENCE_TOLERANCE:.0f} %)",
        "",
        "Each depth against the finest spacing that reached the time (2.5 mm; 3.5 mm where the 2.5 mm",
        "run stopped earlier: then the row says so and is no three-spacing test).",
        "",
        "| soil | t (s) | d_jet 5 mm | d_jet 3.5 mm | d_jet 2.5 mm | 5 mm vs finest | 3.5 mm vs finest "
        "| within 10 % |",
        "|---|---|---|---|---|---|---|---|",
    ]

    def mm(d):
        return f"{1000 * d:.2f}" if np.isfinite(d) else "not reached"

    def rel(r, dx):
        return "-" if dx == r["ref"] else f"{100 * r[f'rel_{dx}']:+.1f} %"

    for r in conv:
        ok = all(abs(r[f"rel_{dx}"]) <= CONVERGENCE_TOLERANCE for dx in (DX, DX_MID) if dx != r["ref"])
        verdict = ("yes" if ok else "no") + ("" if r["ref"] == DX_FINE else " (5 vs 3.5 mm only)")
        lines.append(
            f"| {r['soil']} | {r['t']:g} | {mm(r[DX])} | {mm(r[DX_MID])} | {mm(r['fine'])} "
            f"| {rel(r, DX)} | {rel(r, DX_MID)} | {verdict} |"
        )
    return lines


def _variant_section(sets, cases):
    """A model variant's runs and convergence (the base study's tables, its cases only)."""
    lines = ["", "## Variant: " + ", ".join(f"`{x}`" for x in sets), ""]
    lines += _runs_section(cases)[2:]
    conv = convergence_rows(cases)
    lines += _convergence_section(conv)[2:] if conv else ["", "(one spacing so far: nothing to compare)"]
    curves = curve_differences(cases)
    lines += _curve_section(curves) if curves else []
    return lines


def _sweep_section(cases, pred):
    """d_jet against q at 5 mm, its exponent, and the formulas' exponents and equilibrium depths."""
    lines = [
        "",
        "## Growth with q (5 mm) and the published formulas",
        "",
        f"Formulas: equilibrium depth below the original bed in this set-up (fall {FALL} m, loss-free",
        f"supercritical tailwater, {SAND_LABEL}; verification/analytic/scour_formulas.py, nothing tuned):",
        "",
        "| formula | exponent of q | depth at q = " + " / ".join(f"{q:g}" for q in Q_ALL) + " (m) |",
        "|---|---|---|",
    ]
    for name, r in pred["formulas"].items():
        depths = " / ".join(f"{v:.3f}" for v in r["below_bed"])
        lines.append(f"| {name} | {r['q_exponent_in_setup']:.2f} | {depths} |")
    lines += [
        "",
        "SPH: d_jet at each time against q (log-log least squares, ± standard error) and d_jet over each",
        "formula's equilibrium depth (range over the formulas):",
        "",
        "| soil | t (s) | q | d_jet (mm) | exponent of q | d_jet / formula equilibrium |",
        "|---|---|---|---|---|---|",
    ]
    for soil in SOILS:
        sel = sorted((c for c in cases if c["soil"] == soil and c["dx"] == DX), key=lambda c: c["q"])
        for t in COMPARE_TIMES:
            pts = [(c["q"], d_jet(c, t)) for c in sel if np.isfinite(d_jet(c, t))]
            if len(pts) < 2:
                continue
            qs, ds = (np.array(v) for v in zip(*pts))
            e, se, _ = q_exponent_fit(qs, ds)
            idx = [Q_ALL.index(round(q, 2)) for q in qs]
            ratios = np.concatenate([ds / r["below_bed"][idx] for r in pred["formulas"].values()])
            lines.append(
                f"| {soil} | {t:g} | {', '.join(f'{q:g}' for q in qs)} | "
                f"{', '.join(f'{1000 * d:.2f}' for d in ds)} | {e:.2f} ± {se:.2f} | "
                f"{ratios.min():.2g}-{ratios.max():.2g} |"
            )
    return lines


def report(out=None, setup="plunging"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from verification.analytic.scour_formulas import SAND, predictions

    results = SETUPS[setup].results
    out = out or results
    every = load_cases(setup)
    cases = [c for c in every if is_base(c)]
    variants = {}  # the same q = CONVERGENCE_Q study with scene overrides (a model variant), per override set
    for c in every:
        if c["sets"] and c["ranks"] == 1:
            variants.setdefault(tuple(c["sets"]), []).append(c)
    if not cases:
        print("no runs yet: python -m verification.scour_plunging run-all", file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    conv = convergence_rows(cases)
    pred = predictions(np.array(Q_ALL), SAND, fall=FALL)
    lines = [
        "# Plunging scour study: results",
        "",
        "Written by `python -m verification.scour_plunging report` from",
        f"verification/results/{results.name}/cases/ (set-up '{setup}'). d_jet: the bed's deepest drop over",
        "0.03 m ≤ x ≤ L − 0.10 m (verification/scour_plunging.py); d: the same over the whole layer. CPU:",
        "the run's CPU seconds",
        "(one process, one Numba thread); load: the 1-min load average at its start and end (the 2 cores",
        "were shared with other jobs).",
        "",
    ]
    lines += _runs_section(cases) + _convergence_section(conv) + _curve_section(curve_differences(cases))
    lines += _sweep_section(cases, pred)
    for sets, vcases in sorted(variants.items()):
        lines += _variant_section(sets, vcases)
    (out / "scour_plunging.md").write_text("\n".join(lines) + "\n")
    with open(out / "convergence.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["soil", "t_s", "d_jet_5mm_m", "d_jet_3.5mm_m", "d_jet_2.5mm_m"])
        for r in conv:
            w.writerow([r["soil"], r["t"], f"{r[DX]:.6g}", f"{r[DX_MID]:.6g}", f"{r['fine']:.6g}"])
    _plot(plt, cases, out / "depth_vs_time.png")
    _plot_profiles(plt, cases, out / "hole_profiles.png", results)
    _plot_snapshots(plt, out / "snapshots.png", setup=setup)
    print(f"report in {out}/scour_plunging.md")
    return 0


def _plot(plt, cases, path):
    fig, axs = plt.subplots(1, 3, figsize=(15, 4.2))
    for k, soil in enumerate(SOILS):
        ax = axs[k]
        for c in sorted((c for c in cases if c["soil"] == soil and c["dx"] == DX), key=lambda c: c["q"]):
            ax.plot(c["t"], 1000 * c["d_nappe"], label=f"q = {c['q']:g}")
        ax.set_title(f"{soil}, 5 mm: d_jet(t) per q")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("d_jet (mm)")
        ax.legend(fontsize=7)
    ax = axs[2]
    for soil, ls in zip(SOILS, ("--", "-")):
        at_q = (c for c in cases if c["soil"] == soil and abs(c["q"] - CONVERGENCE_Q) < 1e-9)
        for c in sorted(at_q, key=lambda c: -c["dx"]):
            ax.plot(c["t"], 1000 * c["d_nappe"], ls, label=f"{soil}, {1000 * c['dx']:g} mm")
    ax.set_title(f"q = {CONVERGENCE_Q}: d_jet(t) at 5, 3.5, 2.5 mm")
    ax.set_xlabel("t (s)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_profiles(plt, cases, path, results):
    """The bed surface change z_s(x, t) - z_s(x, 0) at q = CONVERGENCE_Q, each spacing, at COMPARE_TIMES."""
    from verification.scour_zones import read_profiles

    fig, axs = plt.subplots(1, 2, figsize=(13, 4), sharey=True)
    for ax, soil in zip(axs, SOILS):
        at_q = (c for c in cases if c["soil"] == soil and abs(c["q"] - CONVERGENCE_Q) < 1e-9)
        for c, color in zip(sorted(at_q, key=lambda c: -c["dx"]), ("C0", "C1", "C2")):
            kept = results / "cases" / f"{c['case']}_profiles.csv"
            if not kept.exists():
                continue
            x, t, z = read_profiles(kept)
            for tt, ls in zip(COMPARE_TIMES, (":", "--", "-")):
                if t[-1] >= tt - 1e-9:
                    k = int(np.argmin(np.abs(t - tt)))
                    ax.plot(x, 1000 * (z[:, k] - z[:, 0]), ls, color=color,
                            label=f"{1000 * c['dx']:g} mm, {tt:g} s")  # fmt: skip
        ax.set_title(f"{soil}, q = {CONVERGENCE_Q}: bed surface change")
        ax.set_xlabel("x (m)")
        ax.legend(fontsize=7, ncol=3)
    axs[0].set_ylabel("z_s(t) − z_s(0) (mm)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _plot_snapshots(plt, path, times=COMPARE_TIMES, setup="plunging"):
    """Particles under the jet at `times` for q = CONVERGENCE_Q at each spacing whose HDF5 series is on
    disk (runs/scour_study/): water by speed, bed soil brown, picked-up soil red."""
    from solver.output.hdf5_writer import read_series
    from verification.scour_study import RUNS, case_name

    rows = []
    for soil in SOILS:
        for dx in SPACINGS:
            h5 = RUNS / case_name(soil, CONVERGENCE_Q, dx, setup=setup) / "particles.h5"
            if h5.exists():
                rows.append((soil, dx, {round(t, 6): f for t, f in read_series(h5)}))
    if not rows:
        return
    fig, axes = plt.subplots(
        len(rows), len(times), figsize=(4.2 * len(times), 1.9 * len(rows)), squeeze=False
    )
    for i, (soil, dx, snaps) in enumerate(rows):
        for j, t in enumerate(times):
            ax = axes[i, j]
            f = snaps.get(round(t, 6))
            if f is None:
                ax.set_axis_off()
                continue
            x, mat, sus = f["position"], f["material"], f.get("suspended")
            speed = np.linalg.norm(f["velocity"], axis=1)
            water = mat == 0
            bed = (mat == 1) & (sus == 0 if sus is not None else True)
            size = 2.0 * (dx / DX) ** 2
            ax.scatter(x[water, 0], x[water, 1], s=size, c=speed[water], cmap="Blues", vmin=0, vmax=3,
                       linewidths=0)  # fmt: skip
            ax.scatter(x[bed, 0], x[bed, 1], s=size, c="#8c5a2b", linewidths=0)
            if sus is not None:
                up = (mat == 1) & (sus == 1)
                ax.scatter(x[up, 0], x[up, 1], s=2 * size, c="red", linewidths=0)
            ax.set_xlim(0.0, 0.45)
            ax.set_ylim(0.03, 0.2)
            ax.set_aspect("equal")
            ax.set_title(f"{soil}, {1000 * dx:g} mm, t = {t:g} s", fontsize=8)
            ax.tick_params(labelsize=6)
    fig.suptitle(
        f"q = {CONVERGENCE_Q} m²/s: water by speed (0-3 m/s), bed brown, picked-up sand red", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.scour_plunging", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("run-all", help="every missing run, then the report")
    a.add_argument("--end", type=float, default=END)
    a.add_argument("--jobs", type=int, default=1)
    a.add_argument("--only", choices=("convergence", "sweep"))
    r = sub.add_parser("report")
    for parser in (a, r):
        parser.add_argument("--setup", choices=PLUNGING_SETUPS, default="plunging",
                            help="the sand with a state (default) or the seed's sand (issue 24)")  # fmt: skip
    args = ap.parse_args(argv)
    if args.cmd == "run-all":
        todo = []
        if args.only in (None, "convergence"):
            todo += convergence_cases(args.end)
        if args.only in (None, "sweep"):
            todo += [c for c in sweep_cases(args.end) if c not in todo]
        run_all(todo, jobs=args.jobs, setup=args.setup)
    return report(setup=args.setup)


if __name__ == "__main__":
    raise SystemExit(main())
