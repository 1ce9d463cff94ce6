"""What the no-slip wall changes in the interFoam runs of the Lobovsky tank: the flow in the corner
between the floor and the far wall over the plateau window (t* 3-5.5), from the fields written every
0.05 s into work/ (not in git: rerun with run.py to get them).

    python -m reference_cases.openfoam_lobovsky_impact.corner [LABEL ...] [--sph NAME=RUN.npz ...]
        [--png PATH] [--md PATH]

Per run (default: h20, h40, h60 with noSlip and slip walls), time means over the written fields in
the window:
  * backflow: the water's mean u (m/s) in the corner box x > 1.61 m - 50 mm, y < 20 mm (negative:
    water flowing back along the floor, away from the wall: a separated corner eddy);
  * downflow: the water's mean v in the box x > 1.61 m - 20 mm, y < 50 mm (negative: down the wall);
  * the fraction of the corner box's water cells with u < 0;
  * the total head p + rho |U|^2 / 2 + rho g y of the first cell row (the fluid next to the floor)
    at x = 1.45 m, 0.16 m before the wall, and of the row's upstream value at x = 1.3 m, in rho g H;
  * the first cell's wall shear mu u_1 / (dy / 2) at x = 1.3 m (Pa), what the viscous wall term of
    the solver exerts, against rho g H = 2943 Pa.
The figure: streamlines of the window-mean velocity in the corner (x 1.41-1.61 m, y 0-0.2 m), the
window-mean alpha = 0.5 contour, one panel per run. --sph adds SPH runs recorded by
verification/impact_study/fields.py (its corner bins: 10 mm; backflow and downflow as above, from
the particles, every 1 ms; no head or shear columns).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

from reference_cases.openfoam_dam_break_2d.run import read_internal_field, time_dirs

from . import run as R

DEFAULT = ("h20", "h40", "h60", "h20_slip", "h40_slip", "h60_slip")
BACKFLOW_BOX = (0.05, 0.02)  # m: x within 50 mm of the wall, y below 20 mm
DOWNFLOW_BOX = (0.02, 0.05)  # m: x within 20 mm of the wall, y below 50 mm
X_HEAD = (1.30, 1.45)  # m: where the first row's total head is read
MU = 1.0e-3  # Pa s, water (case/constant/transportProperties)
P_SCALE = R.RHO_W * R.G * R.H


def cells_per_h(label: str) -> int:
    return int(label.split("_")[0][1:])


def grid_fields(label: str, case: Path | None = None, n_per_h: int | None = None, window=R.PLATEAU) -> dict:
    """The run's fields in the t* window (default the plateau's) on the downstream block's uniform grid:
    {"x", "y", "t", "u", "v", "p", "alpha"}, arrays [time, ix, iy] (cells with x > XC)."""
    case = case or R.WORK_DIR / label
    n_per_h = n_per_h or cells_per_h(label)
    m = R.mesh(n_per_h)
    n = m["ny"] * (m["nx1"] + m["nx2"])
    c = read_internal_field(case / "0" / "C")[:, :2]
    down = c[:, 0] > R.XC
    xs = np.unique(np.round(c[down, 0], 9))
    ys = np.unique(np.round(c[down, 1], 9))
    ix = np.searchsorted(xs, np.round(c[down, 0], 9))
    iy = np.searchsorted(ys, np.round(c[down, 1], 9))
    out = {"x": xs, "y": ys, "t": [], "u": [], "v": [], "p": [], "alpha": [], "dy": m["dy"]}
    for t, d in time_dirs(case):
        if not window[0] <= t / R.TIME_SCALE <= window[1] or not (d / "U").is_file():
            continue
        U = read_internal_field(d / "U", n)[down]
        vals = {
            "u": U[:, 0],
            "v": U[:, 1],
            "p": read_internal_field(d / "p", n)[down],
            "alpha": np.clip(read_internal_field(d / "alpha.water", n)[down], 0.0, 1.0),
        }
        out["t"].append(t)
        for k, val in vals.items():
            g = np.full((len(xs), len(ys)), np.nan)
            g[ix, iy] = val
            out[k].append(g)
    for k in ("t", "u", "v", "p", "alpha"):
        out[k] = np.array(out[k])
    return out


def corner_metrics(f: dict, mu: float = MU) -> dict:
    """The module doc's numbers from grid_fields(), means over the window's fields (mu: the water's
    dynamic viscosity of the run, for the first-cell shear)."""
    x, y, a = f["x"], f["y"], f["alpha"]
    wall = R.LX

    def box_mean(key, bw, bh):
        s = (x[:, None] > wall - bw) & (y[None, :] < bh)
        w = a[:, s]
        return float(np.sum(w * f[key][:, s]) / np.sum(w))

    s = (x[:, None] > wall - BACKFLOW_BOX[0]) & (y[None, :] < BACKFLOW_BOX[1])
    wet = a[:, s] > 0.5
    reversed_fraction = float(np.sum(wet & (f["u"][:, s] < 0)) / max(np.sum(wet), 1))
    out = {
        "backflow_u": box_mean("u", *BACKFLOW_BOX),
        "downflow_v": box_mean("v", *DOWNFLOW_BOX),
        "reversed_fraction": reversed_fraction,
    }
    for x0 in X_HEAD:
        i = int(np.argmin(np.abs(x - x0)))
        u, v, p = f["u"][:, i, 0], f["v"][:, i, 0], f["p"][:, i, 0]
        head = (p + 0.5 * R.RHO_W * (u * u + v * v) + R.RHO_W * R.G * y[0]) / P_SCALE
        out[f"head_{x0:.2f}"] = float(np.mean(head))
        out[f"u1_{x0:.2f}"] = float(np.mean(u))
    i = int(np.argmin(np.abs(x - X_HEAD[0])))
    out["wall_shear_Pa"] = float(np.mean(mu * np.abs(f["u"][:, i, 0]) / (0.5 * f["dy"])))
    return out


def scheme_drag(label: str, window=(2.8, 3.2), x_range=(1.46, 1.59)) -> dict:
    """What a no-slip wall value would take out of the first cell row through linearUpwind grad(U), on a
    run's fields before the separation: where the flow lifts off the floor (v_f > 0 on the row's top
    face), the Gauss gradient with the wall value 0 instead of the cell's own u_1 raises the top face's
    extrapolated u by u_1 / 2, so the row exports an extra v_f u_1 / 2 of momentum per unit wall area:
    a deceleration v_f u_1 / (2 dy) of the row and an equivalent wall traction rho v_f u_1 / 2 (means
    over x_range and the window's fields)."""
    f = grid_fields(label, window=window)
    s = (f["x"] > x_range[0]) & (f["x"] < x_range[1])
    u1 = f["u"][:, s, 0]
    vf = 0.5 * (f["v"][:, s, 0] + f["v"][:, s, 1])
    extra = np.where(vf > 0, vf * u1 / 2, 0.0)
    return {"traction_Pa": float(R.RHO_W * extra.mean()), "deceleration": float((extra / f["dy"]).mean())}


def table(rows: dict) -> list[str]:
    lines = [
        "| run | backflow u, x > 1.56 m, y < 20 mm (m/s) | share of those cells with u < 0 "
        "| downflow v, x > 1.59 m, y < 50 mm (m/s) | first-row u at 1.30 / 1.45 m (m/s) "
        "| first-row total head at 1.30 / 1.45 m (rho g H) "
        "| mu u_1 / (dy/2) at 1.30 m (Pa; applied with noSlip only) |",
        "|---|---|---|---|---|---|---|",
    ]
    for label, m in rows.items():
        if "reversed_fraction" not in m:  # an SPH record
            lines.append(f"| {label} | {m['backflow_u']:+.2f} | | {m['downflow_v']:+.2f} | | | |")
            continue
        lines.append(
            f"| {label} | {m['backflow_u']:+.2f} | {m['reversed_fraction']:.2f} | {m['downflow_v']:+.2f} "
            f"| {m['u1_1.30']:.2f} / {m['u1_1.45']:.2f} | {m['head_1.30']:.3f} / {m['head_1.45']:.3f} "
            f"| {m['wall_shear_Pa']:.2f} |"
        )
    return lines


def sph_corner(path: Path) -> tuple[dict, dict]:
    """(grid fields, metrics) of an SPH record of verification/impact_study/fields.py: mean u, v per
    10 mm bin over the window (momentum / mass), alpha = the bin's mean water mass / (rho0 x its area)."""
    d = np.load(path)
    xs = 0.5 * (d["corner_x"][1:] + d["corner_x"][:-1])
    ys = 0.5 * (d["corner_y"][1:] + d["corner_y"][:-1])
    mass = d["corner_mass"]
    with np.errstate(invalid="ignore", divide="ignore"):
        u, v = d["corner_mom"][0] / mass, d["corner_mom"][1] / mass
    ts = d["t_star"]
    w = (ts >= R.PLATEAU[0]) & (ts <= R.PLATEAU[1])
    area = np.diff(d["corner_x"])[:, None] * np.diff(d["corner_y"])[None, :]
    alpha = np.clip(mass / (R.RHO_W * area * max(int(w.sum()), 1)), 0.0, 1.0)  # records in the window
    f = {"x": xs, "y": ys, "u": u[None], "v": v[None], "alpha": alpha[None]}
    m = {
        "backflow_u": float(np.nanmean(d["backflow"][w])),
        "downflow_v": float(np.nanmean(d["downflow"][w])),
    }
    return f, m


def backflow_series(label: str, window=(2.3, R.T_END_STAR)) -> tuple[np.ndarray, np.ndarray]:
    """(t*, backflow u) at every written field from the impact on: when the corner flow reverses."""
    f = grid_fields(label, window=window)
    x, y = f["x"], f["y"]
    s = (x[:, None] > R.LX - BACKFLOW_BOX[0]) & (y[None, :] < BACKFLOW_BOX[1])
    a = f["alpha"][:, s]
    return f["t"] / R.TIME_SCALE, np.sum(a * f["u"][:, s], axis=1) / np.maximum(a.sum(axis=1), 1e-12)


def plot_series(labels: list[str], path: Path) -> Path:
    """Backflow u against time (fields every 0.05 s) and sensor 2 (every step, 1 ms filter) of the
    interFoam runs, with the experiment's band at sensor 2."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from reference_cases import lobovsky_measurement as lm

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    _, band, _ = lm.experiment()
    bt, lo, med, hi = band
    a2.fill_between(bt, lo, hi, color="0.85", label="experiment: 2.5-97.5 % of 100 repetitions")
    a2.plot(bt, med, color="0.5", lw=0.8, label="experiment: median")
    for k, label in enumerate(labels):
        style = {"color": f"C{k % 3}", "ls": "-" if "slip" not in label else "--"}
        t, b = backflow_series(label)
        a1.plot(t, b, marker="o", ms=3, label=f"interFoam {label}", **style)
        d = R.read_sensors(R.DATA_DIR / f"openfoam_{label}_sensors.csv")
        g, f, _ = lm.filtered(d["t_star"], d["p_star"][:, 1])
        a2.plot(g, f, lw=0.9, label=f"interFoam {label}", **style)
    a1.axhline(0.0, color="k", lw=0.6)
    a1.set_ylabel("mean u, x > 1.56 m, y < 20 mm (m/s)")
    a1.set_title("Corner flow at the foot of the far wall: toward the wall (> 0) or back (< 0, separated)")
    a1.legend(fontsize=7, ncol=2)
    a2.set_ylabel("p / (rho g H), sensor 2 (1 ms filter)")
    a2.set_xlabel("t sqrt(g/H)")
    a2.set_xlim(2.3, R.T_END_STAR)
    a2.set_ylim(0.0, 2.0)
    a2.axvspan(*R.PLATEAU, color="C4", alpha=0.06)
    a2.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot(fields: dict, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(fields)
    ncol = min(3, len(labels))
    nrow = -(-len(labels) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.8 * nrow), squeeze=False)
    for ax, label in zip(axes.flat, labels):
        f = fields[label]
        x, y = f["x"], f["y"]
        sx, sy = x > 1.40, y < 0.21
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # empty SPH bins: no flow drawn there
            u = np.nan_to_num(np.nanmean(f["u"], axis=0)[np.ix_(sx, sy)].T)
            v = np.nan_to_num(np.nanmean(f["v"], axis=0)[np.ix_(sx, sy)].T)
            a = np.nan_to_num(np.nanmean(f["alpha"], axis=0)[np.ix_(sx, sy)].T)
        speed = np.hypot(u, v)
        ax.streamplot(x[sx], y[sy], np.where(a > 0.5, u, 0), np.where(a > 0.5, v, 0), color=speed,
                      cmap="viridis", density=1.4, linewidth=0.7, arrowsize=0.7)  # fmt: skip
        ax.contour(x[sx], y[sy], a, levels=[0.5], colors="C3", linewidths=1.0)
        for yc in R.SENSORS_Y[:3]:
            ax.plot([R.LX], [yc], "k>", ms=4)
        ax.set_xlim(1.40, R.LX)
        ax.set_ylim(0.0, 0.2)
        ax.set_aspect("equal")
        ax.set_title(f"{label}: mean over t* 3-5.5", fontsize=9)
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    for ax in list(axes.flat)[len(labels) :]:
        ax.axis("off")
    fig.suptitle("Corner of the far wall, window-mean flow (interFoam runs by label, SPH runs named); "
                 "red: alpha = 0.5 (SPH: water mass per bin), triangles: sensors 1-3",
                 fontsize=9)  # fmt: skip
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("labels", nargs="*", default=list(DEFAULT))
    p.add_argument(
        "--sph", action="append", default=[], help="NAME=RUN.npz (verification/impact_study/fields.py)"
    )
    p.add_argument("--png", type=Path, default=R.DATA_DIR / "corner.png")
    p.add_argument("--md", type=Path, default=R.DATA_DIR / "corner.md")
    a = p.parse_args(argv)
    fields, rows = {}, {}
    for label in a.labels:
        if not (R.WORK_DIR / label / "0" / "C").is_file():
            print(f"{label}: no fields in {R.WORK_DIR / label} (rerun run.py)", file=sys.stderr)
            return 2
        fields[label] = grid_fields(label)
        rows[label] = corner_metrics(fields[label])
    for spec in a.sph:
        name, _, path = spec.partition("=")
        if not path or not Path(path).is_file():
            print(f"--sph {spec}: expected NAME=RUN.npz of an existing file", file=sys.stderr)
            return 2
        fields[name], rows[name] = sph_corner(Path(path))
    lines = table(rows)
    slip = [label for label in a.labels if label.endswith("_slip")]
    if slip:
        lines += ["", "linearUpwind's wall-value drag on the first cell row, estimated on the slip runs' "
                  "fields at t* 2.8-3.2, x 1.46-1.59 m (scheme_drag):", "",
                  "| run | equivalent wall traction rho v_f u_1 / 2 (Pa) | row deceleration (m/s^2) |",
                  "|---|---|---|"]  # fmt: skip
        for label in slip:
            d = scheme_drag(label)
            lines.append(f"| {label} | {d['traction_Pa']:.0f} | {d['deceleration']:.1f} |")
    print("\n".join(lines))
    title = "# interFoam, corner of the far wall over t* 3-5.5 (corner.py)\n\n"
    a.md.write_text(title + "\n".join(lines) + "\n")
    print(plot(fields, a.png))
    foam = [label for label in a.labels if (R.DATA_DIR / f"openfoam_{label}_sensors.csv").is_file()]
    if foam:
        print(plot_series(foam, a.png.with_name(a.png.stem + "_series.png")))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
