"""Overview figure of the overflow-nappe reference data (data/*.csv): free surface, bed
pressure and velocity profiles for every mesh and q, and the first-impact jet against
ballistics.

    python -m reference_cases.openfoam_overflow_nappe.plot      # writes data/overview.png
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from reference_cases.openfoam_overflow_nappe import run as R  # noqa: E402


def runs(data_dir: Path) -> dict:
    """{q: {dx_mm: label}} of the official runs present in data_dir."""
    out: dict = {}
    for p in sorted(data_dir.glob("bed_q*_dx*mm.csv")):
        m = re.fullmatch(r"bed_(q(\d+p\d+)_dx([\dp]+)mm)\.csv", p.name)
        if m:
            out.setdefault(float(m.group(2).replace("p", ".")), {})[float(m.group(3).replace("p", "."))] = (
                m.group(1)
            )
    return out


def main(data_dir: Path = R.DATA_DIR) -> Path:
    rr = runs(data_dir)
    qs = sorted(rr)
    fig, axes = plt.subplots(len(qs), 4, figsize=(17, 3.8 * len(qs)), squeeze=False)
    for row, q in zip(axes, qs):
        meshes = rr[q]
        fine = min(meshes)
        yc = float(R.critical_depth(q))
        for k, (dxmm, label) in enumerate(sorted(meshes.items(), reverse=True)):
            c = f"C{k}"
            bed = R.read_csv(data_dir / f"bed_{label}.csv")
            row[0].plot(bed[:, 0], R.Y_SOIL + bed[:, 2], color=c, label=f"mean surface, dx = {dxmm:.3g} mm")
            row[1].plot(bed[:, 0], bed[:, 1], color=c, label=f"dx = {dxmm:.3g} mm")
            vel = R.read_csv(data_dir / f"velocity_{label}.csv")
            for j, xs in enumerate(R.STATIONS):
                v = vel[(vel[:, 0] == xs) & (vel[:, 2] > 0.5)]
                row[2].plot(v[:, 3] + 1.5 * j, v[:, 1], color=c, lw=1.2 if dxmm == fine else 0.8)
        x = np.linspace(0, 0.08, 100)
        up, lo = R.ballistic_surfaces(x, q)
        keep = lo >= R.Y_SOIL
        row[0].plot(x[keep], up[keep], "k--", lw=0.8, label="ballistic jet (critical depth)")
        row[0].plot(x[keep], lo[keep], "k--", lw=0.8)
        row[0].axhline(R.Y_SOIL, color="k", lw=2)
        row[0].plot([0, 0], [R.Y_CROWN, R.Y_CROWN + yc], color="tab:blue", lw=4, alpha=0.5)
        row[0].set_xlim(0, R.LX)
        row[0].set_aspect("equal")
        row[0].set_title(f"q = {q}: time-averaged free surface", fontsize=9)
        row[0].legend(fontsize=7)
        row[1].set_title("time-averaged bed pressure [Pa]", fontsize=9)
        row[1].axhline(
            R.RHO_W * R.G * (R.FALL + 1.5 * yc), color="k", ls=":", lw=0.8, label="rho g (total head)"
        )
        row[1].legend(fontsize=7)
        row[1].set_xlabel("x [m]")
        row[2].set_title("u_x at x = 0.10, 0.15, 0.20 m (offset 1.5 m/s each)", fontsize=9)
        row[2].set_xlabel("u_x [m/s] + offset")
        row[2].set_ylabel("y [m]")
        # first impact on the finest mesh: jet surfaces every 5 ms against ballistics
        early = R.read_csv(data_dir / f"early_{meshes[fine]}.csv")
        for t in np.unique(early[:, 0]):
            e = early[early[:, 0] == t]
            row[3].plot(e[:, 1], e[:, 2], ".", color="C0", ms=2)
            row[3].plot(e[:, 1], e[:, 3], ".", color="C3", ms=2)
        xx = np.linspace(0, R.ballistic_impact_x(q)["lower_surface_x_m"], 50)
        bu, bl = R.ballistic_surfaces(xx, q)
        row[3].plot(xx, bu, "k--", lw=0.8)
        row[3].plot(xx, bl, "k--", lw=0.8)
        row[3].axhline(R.Y_SOIL, color="k", lw=2)
        row[3].set_title(f"first impact, every 5 ms (dx = {fine:.3g} mm); dashed: ballistic", fontsize=9)
        row[3].set_xlim(0, 0.06)
    fig.tight_layout()
    out = data_dir / "overview.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


if __name__ == "__main__":
    print(main(Path(sys.argv[1]) if len(sys.argv) > 1 else R.DATA_DIR))
