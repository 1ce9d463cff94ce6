"""The report's own figures, as PNG bytes: accuracy against wall and CPU time per case, and
the trends over the nights."""

from __future__ import annotations

import io
import math

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def png(fig, dpi=100):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    plt.close(fig)
    return buf.getvalue()


def number(v):
    try:
        v = float(v)
    except (TypeError, ValueError):
        return math.nan
    return v if math.isfinite(v) else math.nan


def log_ticks(axis):
    """Labels at 1, 2, 5 x 10^k in plain numbers (the default minor labels overlap)."""
    axis.set_major_locator(matplotlib.ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def accuracy_columns(rows, declared):
    """The study columns to plot: the case's ACCURACY_COLUMNS, else every numeric column whose
    name says it is an error (contains error, rms or _vs_), in order, as {column: label}."""
    if declared:
        return {k: v for k, v in declared.items() if any(not math.isnan(number(r.get(k))) for r in rows)}
    names = [k for k in (rows[0] if rows else {}) if any(w in k for w in ("error", "rms", "_vs_"))]
    return {k: k for k in names if any(not math.isnan(number(r.get(k))) for r in rows)}


def _groups(rows):
    """Rows of one study split into series: by their 'options' (or 'label') value, in order."""
    out = {}
    for r in rows:
        out.setdefault(str(r.get("options", r.get("label", ""))), []).append(r)
    return out


def cost_figure(case, rows, columns, references=()):
    """|error| against wall time (left) and CPU time (right), one row of panels per accuracy
    column; other codes' runs (references) on the same axes where they record that time."""
    cols = list(columns.items())
    fig, axs = plt.subplots(len(cols), 2, figsize=(10, 2.6 * len(cols) + 0.4), squeeze=False)
    for i, (col, label) in enumerate(cols):
        for j, (cost, name) in enumerate((("wall_time_s", "wall time (s)"), ("cpu_time_s", "CPU time (s)"))):
            ax = axs[i][j]
            for g, (group, grows) in enumerate(_groups(rows).items()):
                x = [number(r.get(cost)) for r in grows]
                y = [abs(number(r.get(col))) for r in grows]
                ok = [(a, b) for a, b in zip(x, y) if a > 0 and b > 0]
                if not ok:
                    continue
                ax.plot(*zip(*ok), "o-" if g == 0 else "D", color=f"C{g}", label=f"ScourSPH {group}".strip())
                for r, a, b in zip(grows, x, y):
                    if a > 0 and b > 0:
                        ax.annotate(
                            str(r.get("resolution", "")),
                            (a, b),
                            textcoords="offset points",
                            xytext=(3, 3),
                            fontsize=7,
                        )
            ref = [(number(r.get(cost)), abs(number(r.get(col))), r.get("label", "")) for r in references]
            ref = [t for t in ref if t[0] > 0 and t[1] > 0]
            if ref:
                ax.plot(
                    [t[0] for t in ref],
                    [t[1] for t in ref],
                    "s--",
                    color="k",
                    mfc="none",
                    label="reference code",
                )
                for a, b, lab in ref:
                    ax.annotate(
                        lab.split("(")[0].strip(),
                        (a, b),
                        textcoords="offset points",
                        xytext=(3, -9),
                        fontsize=6,
                    )
            ax.set_xscale("log")
            ax.set_yscale("log")
            log_ticks(ax.xaxis)
            ax.grid(alpha=0.3, which="both")
            ax.set_xlabel(name)
            if j == 0:
                ax.set_ylabel(label, fontsize=8)
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=6)
    fig.suptitle(f"{case}: error against cost (points labelled by resolution)", fontsize=10)
    fig.tight_layout()
    return png(fig)


LEGEND_MAX = 12  # more metrics than this: the legend names only those out of band or flagged tonight
CLIP = 3.0  # value / tolerance beyond this is drawn at the edge: the pass band stays readable


def scaled(m):
    """value / tolerance of a history metric, clipped to +-CLIP; a zero tolerance (an exact
    requirement such as 'no wall reflections') gives 0 when met and the edge when not."""
    if not m:
        return math.nan
    v, tol = number(m.get("value")), abs(number(m.get("tolerance")))
    if math.isnan(v) or math.isnan(tol):
        return CLIP if m.get("passed") is False else math.nan
    if tol == 0.0:
        return 0.0 if v == 0.0 else math.copysign(CLIP, v)
    return max(-CLIP, min(CLIP, v / tol))


def metric_trend_figure(case, history, keys, flagged=()):
    """Each metric of a case as value / tolerance over the nights (|x| <= 1 passes; clipped at
    +-CLIP); a red ring marks tonight's flagged metrics."""
    fig, ax = plt.subplots(figsize=(10, 3.2))
    dates = [h.get("date", "")[:16] for h in history]
    xs = range(len(history))
    many = len(keys) > LEGEND_MAX  # e.g. the stability matrix: three metrics per cell
    for k, key in enumerate(keys):
        ys = [scaled(h.get("metrics", {}).get(key)) for h in history]
        shown = not many or key in flagged or (ys and not abs(ys[-1]) <= 1)  # NaN counts as out of band
        label = key.split(" :: ", 1)[1][:70] if shown else None
        ax.plot(xs, ys, "o-", ms=3, color=f"C{k % 10}", label=label, alpha=1.0 if shown else 0.35)
        if key in flagged and ys:
            ax.plot([len(ys) - 1], [ys[-1]], "o", ms=10, mfc="none", mec="red", mew=2)
    ax.axhspan(-1, 1, color="green", alpha=0.07, lw=0)
    ax.axhline(1, color="k", lw=0.8, ls="--")
    ax.axhline(-1, color="k", lw=0.8, ls="--")
    ax.set_xticks(list(xs), dates, rotation=30, ha="right", fontsize=6)
    ax.set_ylabel("value / tolerance")
    ax.set_title(
        f"{case}: metrics over the nights (|value / tolerance| <= 1 passes; clipped at +-{CLIP:g})",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    if many:
        ax.text(
            0.01,
            0.02,
            f"{len(keys)} metrics; the legend names those out of band or flagged tonight",
            transform=ax.transAxes,
            fontsize=6,
        )
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return png(fig)


def bench_trend_figure(history, names, thresholds, flagged=()):
    """Each benchmark's speed ratio over the nights, relative to its baseline (1 = baseline,
    above = slower), with its gate as a dashed line of the same colour."""
    fig, ax = plt.subplots(figsize=(10, 3.2))
    dates = [h.get("date", "")[:16] for h in history]
    xs = range(len(history))
    for k, name in enumerate(names):
        ys = []
        for h in history:
            b = h.get("benchmarks", {}).get(name) or {}
            base = number(b.get("baseline_ratio"))
            ys.append(number(b.get("ratio")) / base if base else math.nan)
        ax.plot(xs, ys, "o-", ms=3, color=f"C{k % 10}", label=name)
        if name in thresholds:
            ax.axhline(1 + thresholds[name], color=f"C{k % 10}", ls="--", lw=0.8)
        if name in flagged and ys:
            ax.plot([len(ys) - 1], [ys[-1]], "o", ms=10, mfc="none", mec="red", mew=2)
    ax.axhline(1, color="k", lw=0.8)
    ax.set_xticks(list(xs), dates, rotation=30, ha="right", fontsize=6)
    ax.set_ylabel("ratio / baseline ratio")
    ax.set_title("benchmarks over the nights (above 1 = slower; dashed: each one's gate)", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.tight_layout()
    return png(fig)
