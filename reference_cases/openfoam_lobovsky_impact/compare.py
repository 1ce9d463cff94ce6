"""The 2D interFoam reference against the experiment and SPH, with the impact case's own metrics
(reference_cases/lobovsky_measurement.py, shared with verification/impact_pressure.py: filtered,
impact_time, window_mean_sd, metrics, band_statistics).

    python -m reference_cases.openfoam_lobovsky_impact.compare [--sph-fields R=RUN.npz ...]

RUN.npz: an SPH run recorded by `python -m verification.impact_study.fields RUN.npz R` (sensors, the
wall pressure profile, the depth and velocity of the water within 0.1 m of the far wall); without
it the SPH rows come from the committed study (verification/results/impact_pressure/study.csv).
Writes data/comparison.md, data/comparison.csv, data/comparison.png and the manifest's
"comparison" section.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np

from reference_cases import _common as C
from reference_cases import lobovsky_measurement as lm
from reference_cases.mesh_convergence import GCI_SAFETY, richardson
from reference_cases.openfoam_lobovsky_impact import run as R

# the SPH case's committed resolution study (read as data: verification/impact_pressure.py writes it)
SPH_STUDY = C.REPO_ROOT / "verification" / "results" / "impact_pressure" / "study.csv"
GRADIENT_PAIR = (1, 3)  # sensors 2 and 4 (15 and 80 mm): the wall pressure gradient between them
FOAM_COLORS = ("C2", "C1", "C4")  # interFoam meshes, coarse to fine
SPH_COLORS = ("C0", "C9")  # SPH runs (free slip, no slip)
KEYS = ("impact_s2", "plateau_mean_s2", "plateau_sd_s2", "plateau_mean_s1", "plateau_mean_s4", "peak_s1",
        "peak_s2", "peak_s3")  # fmt: skip


def gradient(m: dict) -> float:
    """Mean wall pressure gradient between sensors 2 and 4 over the plateau, in rho g (hydrostatic = 1)."""
    a, b = GRADIENT_PAIR
    dy = lm.SENSORS_Y[b] - lm.SENSORS_Y[a]
    return (m[f"plateau_mean_s{a + 1}"] - m[f"plateau_mean_s{b + 1}"]) * lm.H / dy


def event_metrics(events) -> dict:
    """The case's metrics of the measured event 5 (each sensor has its own time base)."""
    out = {}
    tau = lm.acoustic_window(10.0 * np.sqrt(2.0 * lm.G * lm.H))
    for k, (te, pe) in enumerate(events):
        g, f, _ = lm.filtered(te, pe)
        out[f"impact_s{k + 1}"] = lm.impact_time(g, f)
        out[f"peak_s{k + 1}"] = float(f.max())
        ga, fa, _ = lm.filtered(te, pe, tau)
        out[f"plateau_mean_s{k + 1}"], out[f"plateau_sd_s{k + 1}"] = lm.window_mean_sd(ga, fa)
    return out


def sph_rows(fields: dict) -> dict:
    """SPH metrics per resolution: from recorded runs where given, else the committed study."""
    rows = {}
    with open(SPH_STUDY) as fh:
        for r in csv.DictReader(fh):
            rows[f"SPH H/{r['resolution']} (study)"] = {k: float(r[k]) for k in KEYS if k in r}
    for res, d in sorted(fields.items()):
        c0 = 10.0 * np.sqrt(2.0 * lm.G * lm.H)
        run = {"t_star": d["sensor_t_star"], "p_star": d["sensor_p_star"], "status": "completed",
               "reflections": 0, "c0": c0}  # fmt: skip
        rows[f"SPH {res} (fields run)"] = lm.metrics(run)
    return rows


def table(rows: dict, ref: dict) -> list[str]:
    lines = [
        "| source | impact t* s2 | plateau mean s2 (minus band median) | plateau sd s2 | mean s1 | mean s4 "
        "| gradient s2-s4 (rho g) | peak s1 / s2 / s3 |",
        "|---|---|---|---|---|---|---|---|",
        f"| experiment, band of 100 repetitions | {ref['impact_earliest']:.3f}-{ref['impact_latest']:.3f} | "
        f"{ref['plateau_median']:.3f} +- {ref['plateau_half_width']:.3f} | | | | | |",
    ]

    def f(m, k, fmt=".3f"):
        v = m.get(k, float("nan"))
        return "" if not np.isfinite(v) else format(v, fmt)

    for name, m in rows.items():
        grad = (
            gradient(m)
            if "plateau_mean_s4" in m and np.isfinite(m.get("plateau_mean_s4", np.nan))
            else np.nan
        )
        dm = m.get("plateau_mean_s2", np.nan) - ref["plateau_median"]
        lines.append(
            f"| {name} | {f(m, 'impact_s2')} | {f(m, 'plateau_mean_s2')} ({dm:+.3f}) "
            f"| {f(m, 'plateau_sd_s2')} "
            f"| {f(m, 'plateau_mean_s1')} | {f(m, 'plateau_mean_s4')} | "
            f"{'' if not np.isfinite(grad) else format(grad, '.2f')} | "
            f"{f(m, 'peak_s1', '.2f')} / {f(m, 'peak_s2', '.2f')} / {f(m, 'peak_s3', '.2f')} |"
        )
    return lines


def mesh_spread(foam_rows: dict, suffix: str = "") -> dict:
    """Spread of the plateau mean at sensor 2 over the interFoam meshes of the reference set-up, and
    the Richardson estimate where three meshes converge monotonically (mesh_convergence.py)."""
    ref = {}
    for k, m in foam_rows.items():
        mesh, _, rest = k.split("H/")[1].partition(",")
        if mesh.isdigit() and ("," + rest if rest else "") == suffix:
            ref[int(mesh)] = m
    out = {}
    for key in ("plateau_mean_s2", "impact_s2", "plateau_sd_s2"):
        vals = {n: ref[n][key] for n in sorted(ref)}
        entry = {
            "values": {f"H/{n}": round(v, 4) for n, v in vals.items()},
            "spread": round(np.ptp(list(vals.values())), 4),
        }
        if len(vals) >= 3:
            fit = richardson([lm.H / n for n in vals], list(vals.values()))
            if fit is not None:
                finest = max(vals)
                entry["richardson_limit"] = round(float(fit[1]), 4)
                entry["gci_finest"] = round(GCI_SAFETY * abs(vals[finest] - fit[1]), 4)
        out[key] = entry
    return out


def foot_boxes_openfoam(label: str, cells_per_h: int, box_w: float, box_y: np.ndarray) -> np.ndarray | None:
    """Mean p* (alpha- and area-weighted cell values) in boxes at the foot of the far wall (x > 1.61 m -
    box_w, y bands box_y), averaged over the fields written inside the plateau window (every 0.05 s);
    None without the run's fields (work/ is not in git)."""
    from reference_cases.openfoam_dam_break_2d.run import read_internal_field, time_dirs

    case = R.WORK_DIR / label
    if not (case / "0" / "C").is_file():
        return None
    m = R.mesh(cells_per_h)
    n = m["ny"] * (m["nx1"] + m["nx2"])
    c = read_internal_field(case / "0" / "C")
    inside = c[:, 0] > R.LX - box_w
    k = np.digitize(c[:, 1], box_y) - 1
    rows = []
    for t, d in time_dirs(case):
        if not lm.PLATEAU[0] <= t / lm.TIME_SCALE <= lm.PLATEAU[1] or not (d / "p").is_file():
            continue
        a = np.clip(read_internal_field(d / "alpha.water", n), 0.0, 1.0)
        p = read_internal_field(d / "p", n) / (lm.RHO0 * lm.G * lm.H)
        rows.append([np.sum((a * p)[inside & (k == j)]) / max(np.sum(a[inside & (k == j)]), 1e-12)
                     for j in range(len(box_y) - 1)])  # fmt: skip
    return np.mean(rows, axis=0) if rows else None


def wall_force(y: np.ndarray, p: np.ndarray, top: float = 0.3) -> float:
    """Integral of p* over the wall from 0 to `top` (trapezoid, p held at the ends), in rho g H^2."""
    yy = np.concatenate([[0.0], y[y < top], [top]])
    pp = np.interp(yy, y, p)
    return float(np.sum(0.5 * (pp[1:] + pp[:-1]) * np.diff(yy)) / lm.H)


def field_table(foam: dict, fields: dict) -> list[str]:
    """Where SPH differs from interFoam: the wall force, the pressure at the wall's foot (the particles'
    own p against the cells'), and the water's depth and mean velocity within 0.1 m of the wall."""
    lines = []
    win = lm.PLATEAU
    for res, d in sorted(fields.items()):
        w = (d["t_star"] >= win[0]) & (d["t_star"] <= win[1])
        prof = d["profile"][w].mean(axis=0)
        lines.append(
            f"SPH {res}: wall force 0-0.3 m (probe profile) {wall_force(d['profile_y'], prof):.4f} rho g H^2"
        )
        if "box_p" in d:
            boxes = np.nanmean(d["box_p"][w], axis=0)
            edges = d["box_y"]
            lines.append(
                f"SPH {res}: mean particle p* within {float(d['box_w']) * 1000:.0f} mm of the wall, "
                "y bands (mm) "
                + ", ".join(
                    f"{edges[j] * 1000:.0f}-{edges[j + 1] * 1000:.0f}: {boxes[j]:.3f}"
                    for j in range(len(boxes))
                )
            )
        for name, col in (("depth", "depth"), ("u", "u"), ("v", "v")):
            lines.append(f"SPH {res}: strip {name} mean over t* 3-5.5: {d[col][w].mean():.3f}")
    for label, r in sorted(foam.items(), key=lambda kv: kv[1]["cells_per_H"]):
        if r["top"] != "open" or r["walls"] != "noSlip":
            continue
        prof = np.loadtxt(R.DATA_DIR / f"openfoam_{label}_wall_profile.csv", delimiter=",", skiprows=2)
        lines.append(
            f"interFoam {label}: wall force 0-0.3 m {wall_force(prof[:, 0], prof[:, 1]):.4f} rho g H^2"
        )
        if fields:
            d = next(iter(fields.values()))
            if "box_p" in d:
                boxes = foot_boxes_openfoam(label, r["cells_per_H"], float(d["box_w"]), d["box_y"])
                if boxes is not None:
                    edges = d["box_y"]
                    lines.append(
                        f"interFoam {label}: mean cell p* (alpha-weighted) in the same boxes, "
                        "fields every 0.05 s: "
                        + ", ".join(
                            f"{edges[j] * 1000:.0f}-{edges[j + 1] * 1000:.0f}: {boxes[j]:.3f}"
                            for j in range(len(boxes))
                        )  # fmt: skip
                    )
        strip = R.DATA_DIR / f"openfoam_{label}_strip.csv"
        if strip.is_file():
            a = np.loadtxt(strip, delimiter=",", skiprows=2)
            w = (a[:, 1] >= win[0]) & (a[:, 1] <= win[1])
            lines.append(
                f"interFoam {label}: strip depth / u / v mean over t* 3-5.5 (every 0.05 s): "
                f"{a[w, 2].mean():.3f} / {a[w, 3].mean():.3f} / {a[w, 4].mean():.3f}"
            )
    return lines


def _style(r: dict) -> dict:
    mesh = {20: 0, 40: 1, 60: 2, 80: 2}.get(r["cells_per_H"], 2)
    ls = {("open", "noSlip"): "-", ("closed", "noSlip"): ":", ("open", "slip"): "--"}.get(
        (r["top"], r["walls"]), "-."
    )
    name = f"interFoam H/{r['cells_per_H']}" + R.variant(r["top"], r["walls"]).replace("_", ", ")
    return {"color": FOAM_COLORS[mesh], "ls": ls, "label": name}


def plot(foam: dict, fields: dict, events, band, path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    tau = lm.acoustic_window(10.0 * np.sqrt(2.0 * lm.G * lm.H))
    fig, axes = plt.subplots(2, 2, figsize=(12, 8))
    ax = axes[0, 0]
    bt, lo, _, hi = band
    ax.fill_between(bt, lo, hi, color="0.85", label="experiment: 2.5-97.5 % of 100 repetitions")
    te, pe = events[1]
    ax.plot(*lm.filtered(te, pe)[:2], color="0.4", lw=0.8, label="experiment, event 5 (1 ms)")
    for _label, r in sorted(foam.items(), key=lambda kv: kv[1]["cells_per_H"]):
        g, fa, _ = lm.filtered(r["t_star"], r["p_star"][:, 1])
        ax.plot(g, fa, lw=1.0, **_style(r))
    for j, (res, d) in enumerate(sorted(fields.items())):
        g, fa, _ = lm.filtered(d["sensor_t_star"], d["sensor_p_star"][:, 1], tau)
        ax.plot(
            g, fa, color=SPH_COLORS[j % 2], lw=1.2, label=f"SPH {res} (acoustic filter {tau * 1000:.0f} ms)"
        )
    ax.set_xlim(2.0, 5.6)
    ax.set_ylim(-0.2, 2.5)
    ax.set_xlabel("t sqrt(g/H)")
    ax.set_ylabel("p / (rho g H), sensor 2 (15 mm)")
    ax.legend(fontsize=7)
    ax.set_title("sensor 2")

    ax = axes[0, 1]
    for label, r in sorted(foam.items(), key=lambda kv: kv[1]["cells_per_H"]):
        prof = np.loadtxt(R.DATA_DIR / f"openfoam_{label}_wall_profile.csv", delimiter=",", skiprows=2)
        ax.plot(prof[:, 1], prof[:, 0], **_style(r))
    for j, (res, d) in enumerate(sorted(fields.items())):
        w = (d["t_star"] >= lm.PLATEAU[0]) & (d["t_star"] <= lm.PLATEAU[1])
        ax.plot(
            d["profile"][w].mean(axis=0), d["profile_y"], color=SPH_COLORS[j % 2], label=f"SPH {res} (probe)"
        )
    em = event_metrics(events)
    ax.plot([em[f"plateau_mean_s{k + 1}"] for k in range(4)], lm.SENSORS_Y, "ks", label="experiment, event 5")
    ax.set_ylim(0, 0.3)
    ax.set_xlabel("mean p / (rho g H) over t* 3-5.5")
    ax.set_ylabel("height on the far wall (m)")
    ax.legend(fontsize=7)
    ax.set_title("wall pressure profile, plateau mean")

    for ax, (col, name) in zip(axes[1], (("depth_m", "depth"), ("u_m_s", "u"))):
        for label, r in sorted(foam.items(), key=lambda kv: kv[1]["cells_per_H"]):
            if r["top"] != "open" or r["walls"] != "noSlip":
                continue
            st = _style(r)
            strip = R.DATA_DIR / f"openfoam_{label}_strip.csv"
            if not strip.is_file():
                continue
            with open(strip) as fh:
                rows = list(csv.DictReader(ln for ln in fh if not ln.startswith("#")))
            t = np.array([float(x["t_star"]) for x in rows])
            ax.plot(t, [float(x[col]) for x in rows], "o-", ms=3, color=st["color"],
                    label=f"interFoam H/{r['cells_per_H']}" + ("" if name == "depth" else " u"))  # fmt: skip
            if name == "u":
                ax.plot(t, [float(x["v_m_s"]) for x in rows], "s--", ms=3, color=st["color"],
                        label=f"interFoam H/{r['cells_per_H']} v")  # fmt: skip
        for j, (res, d) in enumerate(sorted(fields.items())):
            c = SPH_COLORS[j % 2]
            if name == "depth":
                ax.plot(d["t_star"], d["depth"], color=c, label=f"SPH {res}")
            else:
                ax.plot(d["t_star"], d["u"], color=c, label=f"SPH {res} u")
                ax.plot(d["t_star"], d["v"], color=c, ls="--", label=f"SPH {res} v")
        ax.set_xlim(2.0, 5.6)
        ax.set_xlabel("t sqrt(g/H)")
        ax.set_ylabel("mean depth (m)" if name == "depth" else "mean velocity (m/s)")
        ax.set_title(f"water within {R.STRIP} m of the far wall: " + ("area / width" if name == "depth" else
                     "mean u (solid), v (dashed)"))  # fmt: skip
        ax.legend(fontsize=7)
    fig.suptitle("Lobovsky et al. (2014) H = 0.3 m: 2D interFoam vs experiment vs SPH")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument(
        "--sph-fields", nargs="*", default=[], help="R=RUN.npz from verification.impact_study.fields"
    )
    a = p.parse_args(argv)
    fields = {}
    for item in a.sph_fields:
        res, path = item.split("=", 1)
        d = dict(np.load(path))
        walls = str(d.get("walls", "free_slip"))
        fields[f"H/{res}" + ("" if walls == "free_slip" else f", {walls} walls")] = d
    foam = lm.openfoam_reference()
    events, band, _ = lm.experiment()
    ref = lm.band_statistics(band)
    c0 = 10.0 * np.sqrt(2.0 * lm.G * lm.H)
    rows = {"experiment, event 5": event_metrics(events)}
    foam_rows = {}
    for r in sorted(foam.values(), key=lambda r: (r["top"], r["walls"], r["cells_per_H"])):
        name = f"interFoam H/{r['cells_per_H']}" + R.variant(r["top"], r["walls"]).replace("_", ", ")
        foam_rows[name] = lm.metrics({"t_star": r["t_star"], "p_star": r["p_star"], "status": "completed",
                                      "reflections": 0, "c0": c0})  # fmt: skip
    rows.update(foam_rows)
    rows.update(sph_rows(fields))
    lines = table(rows, ref)
    spread = {"open top, noSlip": mesh_spread(foam_rows), "open top, slip": mesh_spread(foam_rows, ", slip")}
    flines = field_table(foam, fields)
    md = R.DATA_DIR / "comparison.md"
    md.write_text(
        "# Lobovsky et al. (2014) H = 0.3 m: 2D interFoam vs experiment vs SPH (sensor 2 unless named)\n\n"
        "Written by `python -m reference_cases.openfoam_lobovsky_impact.compare`; metrics of\n"
        "verification/impact_pressure.py (impact and peaks after the 1 ms filter, plateau mean and sd over\n"
        "t* 3-5.5 after the acoustic filter 4H/c0 = 49 ms, for all sources alike); p* = p/(rho g H).\n"
        "Gradient: (mean p at sensor 2 - mean p at sensor 4) / 65 mm, in rho g (hydrostatic = 1).\n\n"
        + "\n".join(lines)
        + "\n\nWhere SPH differs (plateau window t* 3-5.5; strip = the water within 0.1 m of the far "
        "wall):\n\n"
        + "\n".join(f"* {ln}" for ln in flines)
        + "\n\ninterFoam mesh spread: "
        + json.dumps(spread)
        + "\n"
    )
    with open(R.DATA_DIR / "comparison.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["source", *KEYS, "gradient_s2_s4_rho_g"])
        for name, m in rows.items():
            g = gradient(m) if np.isfinite(m.get("plateau_mean_s4", np.nan)) else float("nan")
            w.writerow([name, *[f"{m.get(k, float('nan')):.5g}" for k in KEYS], f"{g:.4g}"])
    fig = plot(foam, fields, events, band, R.DATA_DIR / "comparison.png")
    C.set_manifest_section(
        R.MANIFEST,
        "comparison",
        {
            "command": "python -m reference_cases.openfoam_lobovsky_impact.compare "
            + " ".join(f"--sph-fields {x}" for x in a.sph_fields),
            "band": {k: round(v, 4) for k, v in ref.items()},
            "interfoam_mesh_spread": spread,
            "outputs": [str(C._rel(md)), str(C._rel(R.DATA_DIR / "comparison.csv")), str(C._rel(fig))],
        },
    )
    print("\n".join(lines))
    print("\n".join(flines))
    print("mesh spread:", json.dumps(spread))
    return 0


if __name__ == "__main__":
    sys.exit(main())
