"""OpenFOAM (interFoam, laminar two-phase VOF) reference run of the Martin & Moyce
(1952) dam break, reduced to small CSV series.

    python -m reference_cases.openfoam_dam_break_2d.run [--cells-per-a N] [--ranks 1|2]
                                                        [--tiny] [--out DIR]

Geometry (the same as the SPH verification case): water column a wide and
H0 = 2a high against the left wall x = 0 of a closed tank 8a long and 3a high,
a = 0.05715 m (2.25 in, the column of Martin & Moyce 1952, Phil. Trans. R. Soc.
A 244, 312-324). Water rho = 1000 kg/m3, nu = 1e-6 m2/s; air rho = 1 kg/m3,
nu = 1.48e-5 m2/s; sigma = 0.07 N/m; g = 9.81 m/s2; t_end = 0.33 s
(T = t sqrt(2g/a) = 6.1).

Steps: the dictionaries in case/ are copied into work/<run>/ with the mesh
filled in, then blockMesh, setFields, [decomposePar], interFoam, [reconstructPar],
postProcess -func writeCellCentres, and the ASCII fields written every 0.005 s
are reduced to

* front_x_m: surge front on the floor, the largest x where alpha.water > 0.5 in
  the bottom cell row, refined by linear interpolation of alpha = 0.5 between
  that cell centre and the next one (x = 8a once the water touches the far wall);
* wall_height_m: water height at the left wall, sum of alpha.water * dy over the
  first cell column (volume-equivalent height, includes any spray in the column);

plus the water area (sum alpha dx dy, per unit depth) to check conservation.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import re
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from reference_cases import _common as C

CASE_DIR = Path(__file__).resolve().parent
TEMPLATE_DIR = CASE_DIR / "case"
DATA_DIR = CASE_DIR / "data"
WORK_DIR = CASE_DIR / "work"
MANIFEST = CASE_DIR / "manifest.json"

A = 0.05715  # column width a [m] (2.25 in)
H0 = 2.0 * A  # column height [m]
LX = 8.0 * A  # tank length [m]
LY = 3.0 * A  # tank height [m]
G = 9.81
T_END = 0.33
WRITE_INTERVAL = 0.005
MAX_CO = 0.5
TINY = {"cells_per_a": 10, "end_time": 0.1}

FOAM_ENV = {"WM_PROJECT_DIR": "/usr/share/openfoam"}


# ----------------------------------------------------------------------------- set-up
def case_values(cells_per_a: int, end_time: float, ranks: int) -> dict:
    dx = A / cells_per_a
    return {
        "LX": C.fmt(LX, 10),
        "LY": C.fmt(LY, 10),
        "DZ": C.fmt(dx, 10),
        "NX": 8 * cells_per_a,
        "NY": 3 * cells_per_a,
        "A": C.fmt(A, 10),
        "H0": C.fmt(H0, 10),
        "END_TIME": C.fmt(end_time),
        "WRITE_INTERVAL": C.fmt(WRITE_INTERVAL),
        "DELTA_T0": C.fmt(min(1e-4, 0.05 * dx)),
        "MAX_CO": C.fmt(MAX_CO),
        # pressure reference: in the air, half a cell under the lid near the right wall
        "PREF_X": C.fmt(LX - 0.5 * dx, 10),
        "PREF_Y": C.fmt(LY - 0.5 * dx, 10),
        "PREF_Z": C.fmt(0.5 * dx, 10),
        "RANKS": ranks,
    }


def write_case(work: Path, values: dict) -> None:
    C.copy_template(TEMPLATE_DIR, work, values)
    shutil.copy(work / "0" / "alpha.water.orig", work / "0" / "alpha.water")


# ----------------------------------------------------------------------------- reading
_LIST_RE = re.compile(r"internalField\s+nonuniform\s+List<(scalar|vector)>\s*(\d+)\s*\(")
_UNIFORM_RE = re.compile(r"internalField\s+uniform\s+([^;]+);")


def read_internal_field(path: Path, n_cells: int | None = None) -> np.ndarray:
    """internalField of an ASCII OpenFOAM volScalarField/volVectorField."""
    text = Path(path).read_text()
    m = _LIST_RE.search(text)
    if m is None:
        u = _UNIFORM_RE.search(text)
        if u is None or n_cells is None:
            raise ValueError(f"cannot read internalField of {path}")
        val = np.array(u.group(1).strip("() ").split(), float)
        return np.tile(val, (n_cells, 1)).squeeze()
    kind, n = m.group(1), int(m.group(2))
    body = text[m.end() : text.index(")\n;", m.end()) if kind == "scalar" else None]
    if kind == "vector":
        end = text.index("\n)\n", m.end())
        body = text[m.end() : end].replace("(", " ").replace(")", " ")
        arr = np.array(body.split(), float).reshape(n, 3)
    else:
        arr = np.array(body.split(), float)
    if arr.shape[0] != n:
        raise ValueError(f"{path}: expected {n} values, read {arr.shape[0]}")
    return arr


def time_dirs(case: Path) -> list[tuple[float, Path]]:
    out = []
    for p in case.iterdir():
        if p.is_dir():
            try:
                out.append((float(p.name), p))
            except ValueError:
                pass
    return sorted(out)


def reduce_fields(case: Path, cells_per_a: int) -> dict:
    """Front position, wall height and water area at every written time."""
    dx = A / cells_per_a
    centres = read_internal_field(case / "0" / "C")
    xc, yc = centres[:, 0], centres[:, 1]
    n = len(xc)
    bottom = np.where(yc < yc.min() + 0.5 * dx)[0]
    bottom = bottom[np.argsort(xc[bottom])]
    wall = np.where(xc < xc.min() + 0.5 * dx)[0]
    assert len(bottom) == 8 * cells_per_a and len(wall) == 3 * cells_per_a, "unexpected mesh"
    t_list, front, hwall, area = [], [], [], []
    for t, d in time_dirs(case):
        f = d / "alpha.water"
        if not f.exists():
            continue
        alpha = read_internal_field(f, n)
        ab = alpha[bottom]
        wet = np.where(ab > 0.5)[0]
        if len(wet) == 0:
            x_front = 0.0
        else:
            i = wet[-1]
            if i == len(ab) - 1:
                x_front = LX
            else:
                x0 = xc[bottom[i]]
                x_front = x0 + (ab[i] - 0.5) / (ab[i] - ab[i + 1]) * dx
        t_list.append(t)
        front.append(x_front)
        hwall.append(float(np.clip(alpha[wall], 0.0, 1.0).sum() * dx))
        area.append(float(alpha.sum() * dx * dx))
    return {"t": np.array(t_list), "front": np.array(front), "wall": np.array(hwall), "area": np.array(area)}


def foam_version(log: Path) -> str:
    m = re.search(r"^Build\s*:\s*OPENFOAM=(\d+)(?:\s+patch=(\d+))?", log.read_text(errors="replace"), re.M)
    if not m:
        return "unknown"
    return f"v{m.group(1)}" + (f" (patch {m.group(2)})" if m.group(2) else "")


def solver_stats(log: Path) -> dict:
    text = log.read_text(errors="replace")
    dts = [float(x) for x in re.findall(r"^deltaT = (\S+)", text, re.M)]
    cos = [float(x) for x in re.findall(r"^Courant Number mean: \S+ max: (\S+)", text, re.M)]
    return {
        "time_steps": len(re.findall(r"^Time = ", text, re.M)),
        "deltaT_min_s": min(dts) if dts else None,
        "deltaT_max_s": max(dts) if dts else None,
        "courant_max_seen": max(cos) if cos else None,
    }


# ----------------------------------------------------------------------------- pipeline
def run_case(
    cells_per_a: int = 20,
    ranks: int = 1,
    tiny: bool = False,
    out: Path | None = None,
    end_time: float | None = None,
    keep_fields: bool = True,
) -> dict:
    C.require("blockMesh", "setFields", "interFoam", "postProcess")
    if ranks > 1:
        C.require("decomposePar", "reconstructPar", "mpirun")
    if tiny:
        cells_per_a = TINY["cells_per_a"]
        end_time = end_time or TINY["end_time"]
    end_time = end_time or T_END
    label = f"dx{cells_per_a}" + ("" if ranks == 1 else f"_np{ranks}") + ("_tiny" if tiny else "")
    work = WORK_DIR / label
    official = out is None and not tiny
    out = Path(out) if out is not None else (DATA_DIR if not tiny else work / "reduced")
    values = case_values(cells_per_a, end_time, ranks)
    write_case(work, values)
    out.mkdir(parents=True, exist_ok=True)
    cmds: list = []
    t0 = time.perf_counter()
    logs = work / "logs"
    logs.mkdir()
    env = FOAM_ENV
    C.run(["blockMesh"], work, logs / "blockMesh.log", env, cmds)
    C.run(["setFields"], work, logs / "setFields.log", env, cmds)
    if ranks == 1:
        solver_wall = C.run(["interFoam"], work, logs / "interFoam.log", env, cmds)
    else:
        C.run(["decomposePar", "-force"], work, logs / "decomposePar.log", env, cmds)
        solver_wall = C.run(
            C.mpirun_prefix(ranks) + ["interFoam", "-parallel"], work, logs / "interFoam.log", env, cmds
        )
        C.run(["reconstructPar"], work, logs / "reconstructPar.log", env, cmds)
    C.run(
        ["postProcess", "-func", "writeCellCentres", "-time", "0"],
        work,
        logs / "writeCellCentres.log",
        env,
        cmds,
    )
    t_red = time.perf_counter()
    series = reduce_fields(work, cells_per_a)
    total_wall = time.perf_counter() - t0

    version = foam_version(logs / "interFoam.log")
    n_cells = 8 * cells_per_a * 3 * cells_per_a
    csv_path = out / (f"openfoam_dx{cells_per_a}" + ("" if ranks == 1 else f"_np{ranks}") + ".csv")
    with open(csv_path, "w", newline="") as fh:
        fh.write(
            f"# tool=OpenFOAM {version} interFoam (laminar VOF), Debian package openfoam "
            f"{C.debian_package_version('openfoam')}; mesh={8 * cells_per_a}x{3 * cells_per_a}x1 "
            f"uniform cells, dx=a/{cells_per_a}={A / cells_per_a:.6g} m; ranks={ranks}; "
            f"a={A} m; H0={H0} m; tank {LX:.5g} x {LY:.5g} m closed; "
            f"front=largest x with alpha.water>0.5 in bottom cell row (interpolated); "
            f"wall_height=sum(alpha.water*dy) over first cell column\n"
        )
        w = csv.writer(fh)
        w.writerow(["t_s", "front_x_m", "wall_height_m"])
        for t, xf, hw in zip(series["t"], series["front"], series["wall"]):
            w.writerow([f"{t:.6g}", f"{xf:.6g}", f"{hw:.6g}"])

    area0 = A * H0
    drift = float(np.max(np.abs(series["area"] - area0)) / area0)
    entry = {
        "date_utc": C.now_iso(),
        "cells_per_a": cells_per_a,
        "dx_m": A / cells_per_a,
        "mesh": f"{8 * cells_per_a} x {3 * cells_per_a} x 1",
        "n_cells": n_cells,
        "ranks": ranks,
        "end_time_s": end_time,
        "write_interval_s": WRITE_INTERVAL,
        "max_courant": MAX_CO,
        "tiny": tiny,
        "wall_time_total_s": round(total_wall, 1),
        "wall_time_solver_s": round(solver_wall, 1),
        "wall_time_reduction_s": round(time.perf_counter() - t_red, 1),
        "solver": solver_stats(logs / "interFoam.log"),
        "water_area_initial_m2": area0,
        "water_area_max_rel_change": drift,
        "output_csv": str(C._rel(csv_path)),
        "commands": cmds,
        "host": C.host_facts(),
    }
    top = {
        "case": "Martin & Moyce (1952) 2D dam break, interFoam laminar VOF",
        "tool": {
            "name": "OpenFOAM (interFoam)",
            "version": version,
            "debian_package": f"openfoam {C.debian_package_version('openfoam')}",
            "mpi": f"openmpi-bin {C.debian_package_version('openmpi-bin')}",
        },
        "reproduce": "python -m reference_cases.openfoam_dam_break_2d.run --cells-per-a N [--ranks 2]",
        "parameters": {
            "a_m": A,
            "H0_m": H0,
            "tank_m": [LX, LY],
            "closed_tank": True,
            "water": {"rho": 1000, "nu": 1e-6},
            "air": {"rho": 1, "nu": 1.48e-5},
            "sigma_N_per_m": 0.07,
            "g": G,
            "t_end_s": T_END,
            "T_end_dimensionless": T_END * math.sqrt(2 * G / A),
            "walls": "noSlip U, fixedFluxPressure p_rgh, zeroGradient alpha (90 deg contact)",
            "numerics": "Euler, MULES with cAlpha 1, PIMPLE 1 outer / 3 p corrections, "
            f"maxCo = maxAlphaCo = {MAX_CO}",
        },
        "environment": FOAM_ENV,
        "source": "Martin, J.C. & Moyce, W.J. (1952) Part IV. An experimental study of the "
        "collapse of liquid columns on a rigid horizontal plane. Phil. Trans. R. Soc. "
        "Lond. A 244, 312-324.",
    }
    if official:
        C.update_manifest(MANIFEST, label, entry, top)
        conv = mesh_comparison(DATA_DIR)
        if conv:
            C.set_manifest_section(MANIFEST, "mesh_convergence", conv)
    else:
        (out / "manifest.json").write_text(json.dumps({**top, "runs": {label: entry}}, indent=2) + "\n")
    if not keep_fields:
        for t, d in time_dirs(work):
            if t > 0:
                shutil.rmtree(d)
    return {"label": label, "csv": csv_path, "work": work, "series": series, "entry": entry}


# ----------------------------------------------------------------------------- convergence
def read_series(path: Path) -> dict:
    arr = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
    return {"t": arr[:, 0], "front": arr[:, 1], "wall": arr[:, 2]}


def mesh_comparison(data_dir: Path) -> dict | None:
    """Differences of every serial mesh from the finest, on the common output times.

    The front is compared only while it is short of the far wall (front < 7.9 a),
    the wall height over the whole run. Differences are in units of a.
    """
    files = {}
    for p in sorted(Path(data_dir).glob("openfoam_dx*.csv")):
        m = re.fullmatch(r"openfoam_dx(\d+)\.csv", p.name)
        if m:
            files[int(m.group(1))] = read_series(p)
    if len(files) < 2:
        return None
    finest = max(files)
    ref = files[finest]
    out = {"finest_cells_per_a": finest, "units": "a = 0.05715 m", "pairs": {}}
    for n, s in sorted(files.items()):
        if n == finest:
            continue
        tt = np.intersect1d(np.round(s["t"], 6), np.round(ref["t"], 6))
        a_i = np.isin(np.round(s["t"], 6), tt)
        b_i = np.isin(np.round(ref["t"], 6), tt)
        fa, fb = s["front"][a_i], ref["front"][b_i]
        ok = (fa < 7.9 * A) & (fb < 7.9 * A)
        d_front = np.abs(fa - fb)[ok] / A
        d_wall = np.abs(s["wall"][a_i] - ref["wall"][b_i]) / A
        # time at which the front reaches x = 4a (Z = 4), a robust scalar
        out["pairs"][f"dx{n}_vs_dx{finest}"] = {
            "front_max_abs_diff_over_a": round(float(d_front.max()), 4),
            "front_rms_diff_over_a": round(float(np.sqrt(np.mean(d_front**2))), 4),
            "wall_height_max_abs_diff_over_a": round(float(d_wall.max()), 4),
            "wall_height_rms_diff_over_a": round(float(np.sqrt(np.mean(d_wall**2))), 4),
            "T_at_Z4": [round(_t_at(s, 4 * A), 3), round(_t_at(ref, 4 * A), 3)],
            "compared_times": int(ok.sum()),
        }
    return out


def _t_at(s: dict, x: float) -> float:
    """Dimensionless time T = t sqrt(2g/a) when the front first reaches x."""
    idx = np.where(s["front"] >= x)[0]
    if len(idx) == 0:
        return float("nan")
    i = idx[0]
    if i == 0:
        return 0.0
    t = np.interp(x, [s["front"][i - 1], s["front"][i]], [s["t"][i - 1], s["t"][i]])
    return float(t * math.sqrt(2 * G / A))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cells-per-a", type=int, default=20, help="cells per column width a")
    p.add_argument("--ranks", type=int, default=1, choices=[1, 2])
    p.add_argument("--tiny", action="store_true", help="a/10 mesh to t = 0.1 s (seconds)")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="output dir for the CSV (default: data/, or work/<run>/reduced for --tiny)",
    )
    p.add_argument("--end-time", type=float, default=None)
    p.add_argument("--nice", type=int, default=0, help="raise the niceness of the tool runs")
    p.add_argument(
        "--drop-fields", action="store_true", help="delete the written time folders after the reduction"
    )
    a = p.parse_args(argv)
    if a.nice:
        os.nice(a.nice)
    res = run_case(a.cells_per_a, a.ranks, a.tiny, a.out, a.end_time, keep_fields=not a.drop_fields)
    e = res["entry"]
    print(
        f"{res['label']}: {e['n_cells']} cells, {e['solver']['time_steps']} steps, "
        f"wall {e['wall_time_total_s']} s (solver {e['wall_time_solver_s']} s), "
        f"water area drift {e['water_area_max_rel_change']:.2e}; wrote {res['csv']}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
