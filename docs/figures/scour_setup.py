"""The figure of docs/scour_setup.md: (a) the scour set-up drawn to scale, with the ballistic
nappe at q = 0.06 and 0.11 m^2/s and, where the OpenFOAM reference has been run, its
time-averaged free surface over the rigid bed; (b) the published equilibrium scour depths
against q for the two grain-size mappings, against the seed's 0.095 m layer.

    python docs/figures/scour_setup.py            # writes docs/figures/scour_setup.png
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Polygon, Rectangle  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from verification.analytic import scour_formulas as S  # noqa: E402

# the set-up (docs/scour_setup.md), metres
SOIL_DEPTH, SOIL_LENGTH, FALL, CROWN_WIDTH, DX = 0.095, 0.25, 0.01, 0.05, 0.005
LONG_RUN_LENGTH = 0.60
CFD_DATA = ROOT / "reference_cases" / "openfoam_overflow_nappe" / "data"
OUT = Path(__file__).with_suffix(".png")


def finest_cfd(q: float) -> Path | None:
    """The bed CSV of the finest OpenFOAM mesh run for this q, if any."""
    tag = f"q{q:.2f}".replace(".", "p")
    files = sorted(CFD_DATA.glob(f"bed_{tag}_dx*mm.csv"))
    if not files:
        return None

    def dx_of(p: Path) -> float:
        return float(p.stem.split("_dx")[1][:-2].replace("p", "."))

    return min(files, key=dx_of)


def draw_setup(ax) -> None:
    crown = SOIL_DEPTH + FALL
    ax.add_patch(Rectangle((0, 0), SOIL_LENGTH, SOIL_DEPTH, fc="#d9c38c", ec="k", lw=0.8, label="soil layer"))
    ax.add_patch(
        Rectangle(
            (SOIL_LENGTH, 0),
            LONG_RUN_LENGTH - SOIL_LENGTH,
            SOIL_DEPTH,
            fc="none",
            ec="#8a6d2f",
            ls=":",
            lw=1.0,
            label="long-run extension (to 0.60 m)",
        )
    )
    ax.add_patch(
        Polygon(
            [(-CROWN_WIDTH, 0), (0, 0), (0, crown), (-CROWN_WIDTH, crown)],
            fc="0.55",
            ec="k",
            lw=0.8,
            label="breakwater (caisson, rigid)",
        )
    )
    # rigid bottom and end wall retaining the soil
    ax.plot([-CROWN_WIDTH, LONG_RUN_LENGTH], [0, 0], "k", lw=2.5)
    ax.plot([SOIL_LENGTH, SOIL_LENGTH], [0, SOIL_DEPTH], "k", lw=2.5)
    ax.axvspan(SOIL_LENGTH, SOIL_LENGTH + 0.03, ymin=0, ymax=1, color="tab:red", alpha=0.08)
    ax.text(SOIL_LENGTH + 0.004, 0.125, "outlet\nzone", color="tab:red", fontsize=7, va="top")
    colours = {0.06: "tab:blue", 0.11: "tab:purple"}
    for q, c in colours.items():
        hy = S.setup_hydraulics(q, FALL)
        ax.plot([0, 0], [crown, crown + hy.y_c], color=c, lw=4, alpha=0.6)
        x = np.linspace(0, 0.16, 200)
        drop = S.G * x**2 / (2 * hy.u_c**2)
        up, lo = crown + hy.y_c - drop, crown - drop
        ax.plot(x[lo >= SOIL_DEPTH], lo[lo >= SOIL_DEPTH], "--", color=c, lw=1)
        ax.plot(
            x[up >= SOIL_DEPTH], up[up >= SOIL_DEPTH], "--", color=c, lw=1, label=f"ballistic nappe, q = {q}"
        )
        bed = finest_cfd(q)
        if bed is not None:
            arr = np.loadtxt(bed, delimiter=",", comments="#", skiprows=2)
            dxmm = bed.stem.split("_dx")[1].replace("p", ".").replace("mm", " mm")
            ax.plot(
                arr[:, 0],
                SOIL_DEPTH + arr[:, 2],
                color=c,
                lw=1.6,
                label=f"OpenFOAM mean surface, q = {q} ({dxmm})",
            )
        ax.annotate(
            f"inflow q={q}\ny_c={hy.y_c * 1000:.0f} mm, u_c={hy.u_c:.2f} m/s",
            xy=(0, crown + hy.y_c),
            xytext=(-0.125, crown + hy.y_c + 0.01),
            fontsize=7,
            color=c,
            arrowprops={"arrowstyle": "->", "color": c, "lw": 0.7},
        )
    ax.annotate(
        "",
        xy=(0.012, crown + 0.5 * 0.0716),
        xytext=(-0.01, crown + 0.5 * 0.0716),
        arrowprops={"arrowstyle": "->"},
    )
    ax.annotate(
        "fall 0.01 m",
        xy=(0.002, SOIL_DEPTH + 0.005),
        xytext=(0.03, SOIL_DEPTH - 0.02),
        fontsize=7,
        arrowprops={"arrowstyle": "->", "lw": 0.6},
    )
    ax.text(0.09, 0.04, "0.25 m x 0.095 m soil (seed)\nparticles 5 mm", fontsize=8)
    ax.set_xlim(-0.14, LONG_RUN_LENGTH + 0.01)
    ax.set_ylim(-0.01, 0.29)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (landward from the breakwater's landward face)")
    ax.set_ylabel("z [m]")
    ax.legend(fontsize=6.5, loc="upper right", ncol=2, framealpha=0.9)
    ax.set_title("(a) set-up, to scale", fontsize=9, loc="left")


def draw_formulas(ax) -> None:
    qs = np.linspace(0.06, 0.11, 11)
    styles = {"SAND": "-", "PARTICLE": "--"}
    for key, grains in (("SAND", S.SAND), ("PARTICLE", S.PARTICLE)):
        p = S.predictions(qs, grains)
        for i, (name, r) in enumerate(p["formulas"].items()):
            if key == "SAND" and name == "Veronese 1937 A":
                continue  # Veronese dropped d below 5 mm: his form B applies to sand
            ax.plot(
                qs,
                r["below_bed"],
                styles[key],
                color=f"C{i}",
                lw=1.2,
                label=name if key == "PARTICLE" else None,
            )
    ax.axhline(SOIL_DEPTH, color="k", lw=1.5)
    ax.text(0.0605, SOIL_DEPTH + 0.01, "seed's layer depth 0.095 m (rigid bottom below)", fontsize=7)
    ax.set_xlabel("q [m$^2$/s]")
    ax.set_ylabel("equilibrium scour below the original bed [m]")
    ax.set_title("(b) published formulas: solid d50 = 0.5 mm sand, dashed d = 5 mm", fontsize=9, loc="left")
    ax.set_ylim(0, 1.1)
    ax.legend(fontsize=6.5, loc="upper left")


def main() -> Path:
    fig, (a, b) = plt.subplots(2, 1, figsize=(8.0, 8.6), gridspec_kw={"height_ratios": [1.15, 1]})
    draw_setup(a)
    draw_formulas(b)
    fig.tight_layout()
    fig.savefig(OUT, dpi=150)
    plt.close(fig)
    return OUT


if __name__ == "__main__":
    print(main())
