"""Plateau means of published 2D computations of the Lobovsky tank, from TrixiParticles' validation files.

    python -m reference_cases.openfoam_lobovsky_impact.published DIR

DIR holds the files of `validation/dam_break_2d/` of trixi-framework/TrixiParticles.jl (MIT; read at commit
a720b1d5, not copied into this repository):
  * decourcy_pressure_sensor_P{1..4}.csv: De Courcy et al. (2024), CMAME 420:116700, their 2D delta-SPH wall
    pressure at P1-P4, digitised by the TrixiParticles developers (PR #934; P1 corrected to the delta-SPH
    curve in PR #945). Columns: t sqrt(g/H), p/(rho g H).
  * validation_reference_{wcsph,edac}_{40,80,400}.json: TrixiParticles' own reference runs of the same set-up
    (H = 0.6 m, H/dx = 40, 80, 400; WCSPH with density diffusion, or EDAC; free-slip walls; c0 = 50 sqrt(gH),
    alpha = 0.01 as De Courcy et al.). Keys pressure_P{i}_fluid_1 -> time (s), values (Pa).
  * optionally, from the repository's history (commit b13455d4, deleted since), sim_pressure_sensor_P1.csv
    (Marrone et al. 2011, CMAME 200:1526, delta-SPH at H/dx = 40, 80, 320; columns time, exp, 40, 320, 80)
    and exp_pressure_sensor_P1.csv (Buchner 2002's experiment), sensor P1 centred at 160 mm (0.267 H).
Their tank is Lobovsky's scaled by 2 (H = 0.6 m, 5.366 H long) and P1-P4 are centred 6, 30, 60, 160 mm above
the floor, 8.4 mm tall: Lobovsky's sensors 1-4 (3, 15, 30, 80 mm; 4.2 mm) at twice the scale. The models are
inviscid apart from artificial viscosity, so p* against t* carries over to H = 0.3 m unchanged.

The mean is over the plateau window of the impact case (t* 3-5.5), by linear interpolation on a uniform grid
(the digitised curves are unevenly sampled). The impact case's acoustic filter (a moving average) is not
applied: it changes a window mean only through the window's ends.
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path

import numpy as np

PLATEAU = (3.0, 5.5)  # t*, as verification.impact_pressure.PLATEAU
H_TRIXI = 0.6  # m, their column height
G = 9.81
RHO = 1000.0


def window_mean(t: np.ndarray, p: np.ndarray, window=PLATEAU, n: int = 2501) -> float:
    """Mean of the piecewise-linear curve p(t) over `window` (samples need not be sorted or uniform)."""
    order = np.argsort(t, kind="stable")
    grid = np.linspace(window[0], window[1], n)
    return float(np.mean(np.interp(grid, np.asarray(t)[order], np.asarray(p)[order])))


def decourcy(folder: Path) -> list[float]:
    out = []
    for i in range(1, 5):
        with open(folder / f"decourcy_pressure_sensor_P{i}.csv") as fh:
            rows = [r for r in csv.reader(fh)][1:]
        out.append(window_mean(np.array([float(r[0]) for r in rows]), np.array([float(r[1]) for r in rows])))
    return out


def trixi(folder: Path, method: str, resolution: int) -> list[float]:
    data = json.loads((folder / f"validation_reference_{method}_{resolution}.json").read_text())
    out = []
    for i in range(1, 5):
        d = data[f"pressure_P{i}_fluid_1"]
        t = np.asarray(d["time"], float) * np.sqrt(G / H_TRIXI)
        out.append(window_mean(t, np.asarray(d["values"], float) / (RHO * G * H_TRIXI)))
    return out


def marrone_buchner(folder: Path) -> dict[str, float] | None:
    """Window means at Buchner's P1 of Marrone et al.'s curves and of the experiment (if the files exist)."""
    sim, exp = folder / "sim_pressure_sensor_P1.csv", folder / "exp_pressure_sensor_P1.csv"
    if not (sim.is_file() and exp.is_file()):
        return None
    data = np.genfromtxt(sim, delimiter=",", names=True)
    out = {
        f"Marrone et al. 2011 H/{c.lstrip('h')}": window_mean(data["time"], data[c])
        for c in data.dtype.names[2:]
    }
    e = np.genfromtxt(exp, delimiter=",", names=True)
    out["Buchner 2002 (experiment)"] = window_mean(e["time"], e[e.dtype.names[1]])
    return out


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1 or not Path(argv[0]).is_dir():
        print("usage: python -m reference_cases.openfoam_lobovsky_impact.published DIR", file=sys.stderr)
        return 2
    folder = Path(argv[0])
    print("| source | P1 (3 mm) | P2 (15 mm) | P3 (30 mm) | P4 (80 mm) |")
    print("|---|---|---|---|---|")
    print("| De Courcy et al. 2024, delta-SPH | " + " | ".join(f"{v:.3f}" for v in decourcy(folder)) + " |")
    for method in ("wcsph", "edac"):
        for res in (40, 80, 400):
            vals = " | ".join(f"{v:.3f}" for v in trixi(folder, method, res))
            print(f"| TrixiParticles {method.upper()} H/{res} | {vals} |")
    extra = marrone_buchner(folder)
    if extra:
        print("\nBuchner's P1 (160 mm of H = 0.6 m, Lobovsky's sensor-4 height):")
        for k, v in extra.items():
            print(f"  {k}: {v:.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
