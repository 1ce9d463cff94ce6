"""First-impact load statistics of saved series beside 2D interFoam and the experiment: the case's pressure
impulse and acoustic peak (verification/impact_pressure.py, metric 5) at sensors 1-3, their sensitivity to the
window's end, the 1 ms peak, and Lobovsky et al.'s own peak-anchored impulse (rise and decay times from the
half-maximum crossings, their sec. 5.1.2-5.1.3) for comparison.

python -m verification.impact_study.impulse RUN.npz ... [--trixi DIR] [--png OUT.png] [--md OUT.md]
(series of verification/impact_study/series.py; a partial record, stopped before the window's end, gives nan)

--trixi DIR adds the published 2D free-slip computations of the same tank at twice the scale (H = 0.6 m;
p* and t* carry over) that TrixiParticles keeps in validation/dam_break_2d/ (read at commit a720b1d5, not
copied here; reference_cases/openfoam_lobovsky_impact/published.py says what they are): De Courcy et al.
(2024) delta-SPH at H/400 as digitised, and TrixiParticles' WCSPH and EDAC runs at H/40, H/80, H/400. Their
sensors P1-P3 are Lobovsky's 1-3. TrixiParticles samples every 0.01 t* (a spike falls between samples: its
1 ms peak means little, its impulse does not) and clips negative pressure (its impulse is biased up where
the model has rarefactions).
"""

import argparse
import csv
import json
from pathlib import Path

import numpy as np

from verification import impact_pressure as ip
from verification.impact_study.remetric import load

ENDS = (0.3, 0.5, 0.75)  # t* after the impact: the window-end sensitivity


def peak_anchored_impulse(t, p):
    """Lobovsky et al.'s impulse of a 1 ms-filtered record: rise = 2 (t_peak - t at half-maximum before it),
    decay = 2 (t at half-maximum after it - t_peak), I = int p dt over [t_peak - rise, t_peak + decay]."""
    i = int(np.argmax(p))
    half = 0.5 * p[i]
    a = i
    while a > 0 and p[a] > half:
        a -= 1
    b = i
    while b < len(p) - 1 and p[b] > half:
        b += 1
    rise, decay = 2 * (t[i] - t[a]), 2 * (t[b] - t[i])
    w = (t >= t[i] - rise) & (t <= t[i] + decay)
    return float(np.trapezoid(p[w], t[w])), rise, decay


def statistics(t, p, t_impact, c0):
    """Per sensor 1-3: impulse over the case's window, the same with negative p* clipped to 0 before the
    filter (TrixiParticles' probe convention, `clip_negative_pressure=true` in its validation/dam_break_2d/
    sensors.jl: a diagnostic of the model's negative pressures at the wall), the impulse with the window's
    end at each of ENDS, the acoustic peak, the 1 ms peak and the peak-anchored impulse (value, rise, decay
    in t*)."""
    out = []
    for k in range(3):
        if not np.isfinite(p[:, k]).all():
            out.append(None)
            continue
        g, f, _ = ip.filtered(t, p[:, k])
        gc, fc, _ = ip.filtered(t, np.clip(p[:, k], 0.0, None))
        ga, fa, _ = ip.filtered(t, p[:, k], ip.acoustic_window(c0))
        ends = []
        for end in ENDS:
            w = (g >= t_impact + ip.IMPULSE_WINDOW[0]) & (g <= t_impact + end)
            ends.append(float(np.trapezoid(f[w], g[w])) if g[-1] >= t_impact + end else float("nan"))
        first = (g >= t_impact + ip.IMPULSE_WINDOW[0]) & (g <= t_impact + ip.IMPULSE_WINDOW[1])
        out.append(
            {
                "impulse": ip.impulse(g, f, t_impact),
                "clipped": ip.impulse(gc, fc, t_impact),
                "ends": ends,
                "peak_ac": ip.acoustic_peak(ga, fa, t_impact),
                "peak_1ms": float(f[first].max()),
                "anchored": peak_anchored_impulse(g[first], f[first]),
            }
        )
    return out


def trixi_records(folder):
    """De Courcy et al.'s and TrixiParticles' sensor records P1-P4 as (label, resolution, kind, t*, p*)."""
    folder = Path(folder)
    h = 0.6  # their column height (m)
    cols = []
    for i in range(1, 5):
        with open(folder / f"decourcy_pressure_sensor_P{i}.csv") as fh:
            rows = sorted((float(r[0]), float(r[1])) for r in list(csv.reader(fh))[1:])
        cols.append(np.array(rows))
    t = np.unique(np.concatenate([c[:, 0] for c in cols]))
    out = [
        ("De Courcy et al. 2024 H/400", 400, "decourcy", t, np.stack([np.interp(t, *c.T) for c in cols], 1))
    ]
    for method in ("wcsph", "edac"):
        for res in (40, 80, 400):
            data = json.loads((folder / f"validation_reference_{method}_{res}.json").read_text())
            d = [data[f"pressure_P{i}_fluid_1"] for i in range(1, 5)]
            t = np.asarray(d[0]["time"], float) * np.sqrt(ip.G / h)
            p = np.stack([np.asarray(x["values"], float) / (ip.RHO0 * ip.G * h) for x in d], 1)
            out.append((f"TrixiParticles {method.upper()} H/{res}", res, "trixi_" + method, t, p))
    return out


def records(paths, c0):
    """(label, cells or particles per H, kind, t*, p*[n, 4]) of the SPH series, the interFoam runs and the
    experiment (event 5; the sensor-2 band's three curves)."""
    out = []
    for path in paths:
        d, run = load(path)
        res = int(round((int(d["particles"]) / 2) ** 0.5))
        out.append((f"SPH H/{res} ({str(d['status'])[:24]})", res, "sph", run["t_star"], run["p_star"]))
    for r in sorted(ip.openfoam_reference().values(), key=lambda r: (r["walls"], r["cells_per_H"])):
        if r["top"] == "open":
            kind = "foam_" + r["walls"]
            out.append(
                (
                    f"interFoam {r['walls']} H/{r['cells_per_H']}",
                    r["cells_per_H"],
                    kind,
                    r["t_star"],
                    r["p_star"],
                )
            )
    events, band, _ = ip.experiment()
    t = events[1][0]
    out.append(
        ("experiment, event 5", None, "exp", t, np.stack([np.interp(t, *events[k]) for k in range(4)], 1))
    )
    bt = band[0]
    for name, curve in zip(("band 2.5 %", "band median", "band 97.5 %"), band[1:]):
        nan = np.full_like(curve, np.nan)
        out.append((name, None, "band", bt, np.stack([nan, curve, nan, nan], 1)))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs", nargs="*")
    ap.add_argument("--trixi")
    ap.add_argument("--png")
    ap.add_argument("--md")
    a = ap.parse_args()
    c0 = 10.0 * np.sqrt(2 * ip.G * ip.H)
    _, band, _ = ip.experiment()
    band_impact = ip.impact_time(*ip.filtered(band[0], band[2])[:2])
    rows = []
    recs = records(a.runs, c0) + (trixi_records(a.trixi) if a.trixi else [])
    for label, n, kind, t, p in recs:
        # the window sits at each record's own impact time at sensor 2 (the band's: its median curve's)
        t_imp = band_impact if kind == "band" else ip.impact_time(*ip.filtered(t, p[:, 1])[:2])
        rows.append((label, n, kind, t_imp, statistics(t, p, t_imp, c0)))
    head = (
        "| record | t*_imp s2 | impulse s1 / s2 / s3 | same, p* clipped at 0 | "
        "s2 impulse, window end +0.3 / +0.5 / +0.75 | "
        "acoustic peak s1 / s2 / s3 | 1 ms peak s1 / s2 / s3 | peak-anchored impulse s1 (rise, decay t*) |"
    )
    lines = [head, "|" + "---|" * 8]

    def fmt(stats, key, spec):
        return " / ".join("-" if s is None else format(s[key], spec) for s in stats)

    for label, _, _, t_imp, st in rows:
        s2 = st[1]
        anchored = st[0]["anchored"] if st[0] is not None else None
        lines.append(
            f"| {label} | {t_imp:.3f} | {fmt(st, 'impulse', '.3f')} | {fmt(st, 'clipped', '.3f')} | "
            + " / ".join(f"{v:.3f}" for v in s2["ends"])
            + f" | {fmt(st, 'peak_ac', '.2f')} | {fmt(st, 'peak_1ms', '.2f')} | "
            + (f"{anchored[0]:.3f} ({anchored[1]:.3f}, {anchored[2]:.3f})" if anchored else "-")
            + " |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    if a.md:
        Path(a.md).write_text(text)
    if a.png:
        plot(rows, a.png)


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(13, 7), sharex=True)
    for row, key, name in ((0, "impulse", "pressure impulse int p* dt*, t*_imp -0.1 to +0.5"),
                           (1, "peak_ac", "peak p* after the acoustic filter 4H/c0")):  # fmt: skip
        for k in range(3):
            ax = axes[row, k]
            for kind, color, label in (("sph", "C0", "SPH (ScourSPH)"), ("foam_slip", "C1", "interFoam slip"),
                                       ("foam_noSlip", "C2", "interFoam no slip"),
                                       ("trixi_wcsph", "C4", "TrixiParticles WCSPH (slip)"),
                                       ("trixi_edac", "C5", "TrixiParticles EDAC (slip)"),
                                       ("decourcy", "C6", "De Courcy et al. delta-SPH (slip)")):  # fmt: skip
                pts = [(n, st[k][key]) for _, n, kd, _, st in rows if kd == kind and st[k] is not None]
                pts = [(n, v) for n, v in pts if np.isfinite(v)]
                if pts:
                    x, y = zip(*sorted(pts))
                    ax.plot(x, y, "o-", color=color, label=label)
            for _, _, kind, _, st in rows:
                if kind == "exp" and st[k] is not None:
                    ax.axhline(st[k][key], color="k", lw=1, label="experiment, event 5")
            if k == 1:
                vals = [st[1][key] for _, _, kind, _, st in rows if kind == "band"]
                ax.axhspan(vals[0], vals[2], color="0.85", label="band 2.5-97.5 % curves")
            ax.set_xscale("log", base=2)
            ax.set_title(f"sensor {k + 1}: {name}", fontsize=8)
            if row == 1:
                ax.set_xlabel("particles or cells per H")
            if row == 0 and k == 0:
                ax.legend(fontsize=7)
    fig.suptitle("First-impact load at the far wall, Lobovsky et al. (2014) H = 300 mm: resolution study")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
