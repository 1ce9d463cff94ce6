"""OpenFOAM (interFoam, laminar two-phase VOF) reference of the Lobovsky et al. (2014) dam break,
H = 0.3 m: pressure on the far wall at the four sensors, for the impact case
(verification/impact_pressure.py) -- an independent 2D solver that separates what the 2D model
gives from what SPH adds.

    python -m reference_cases.openfoam_lobovsky_impact.run --cells-per-H N [--tiny] [--out DIR]
    python -m reference_cases.openfoam_lobovsky_impact.run --summary   # manifest runs + comparison

Geometry (the SPH scene's, verification/impact_pressure.py): tank 1.61 m long and 0.6 m high (the
experiment's tank height), open at the top (atmosphere patch, p = 0); water column 0.6 m long and
H = 0.3 m high against the upstream wall x = 0, released at t = 0 (no gate). Water rho = 1000 kg/m3,
nu = 1e-6 m2/s; air rho = 1 kg/m3, nu = 1.48e-5 m2/s; sigma = 0.07 N/m; g = 9.81 m/s2; walls noSlip
with fixedFluxPressure and zero-gradient alpha (90 degree contact angle). t_end = 5.6 sqrt(H/g).
Numerics as the dam-break reference (reference_cases/openfoam_dam_break_2d): Euler, MULES cAlpha 1,
PIMPLE 1 outer / 3 pressure correctors, maxCo = maxAlphaCo = 0.5, and maxDeltaT = 0.5 ms.

Sensors (what the experiment measures): a patchProbes function object writes p (gauge, the
atmosphere at 0) on every face of the downstream wall at every time step (>= 2 kHz by maxDeltaT).
Each sensor is the face average of p over a 4.2 mm segment centred at 3, 15, 30 and 80 mm (the
sensor face diameter seen edge-on in 2D; verification/data/README.md): the finite-volume face
values weighted by their overlap with the segment. The run-up height on the wall is
sum(alpha.water * dy) over the wall's faces.

Outputs (data/): openfoam_h{N}_sensors.csv (t_s, t_star, p_star_s1..s4, wall_depth_m),
openfoam_h{N}_wall_profile.csv (the wall pressure and alpha profile averaged over the plateau window
t* 3-5.5) and openfoam_h{N}_strip.csv (every 0.05 s: mean depth and velocity of the water within
0.1 m of the far wall); the run's metrics (reference_cases/lobovsky_measurement.py, the same functions as
SPH) in manifest.json. Fields are written every 0.05 s into work/ (kept for analysis; not in git).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from reference_cases import _common as C
from reference_cases.openfoam_dam_break_2d.run import (
    foam_version,
    read_internal_field,
    solver_stats,
    time_dirs,
)

CASE_DIR = Path(__file__).resolve().parent
TEMPLATE_DIR = CASE_DIR / "case"
DATA_DIR = CASE_DIR / "data"
WORK_DIR = CASE_DIR / "work"
MANIFEST = CASE_DIR / "manifest.json"

H = 0.3  # water column height [m]
XC = 0.6  # column length [m]
LX, LY = 1.61, 0.6  # tank [m] (Lobovsky et al. 2014; the SPH scene's)
G = 9.81
RHO_W = 1000.0
TIME_SCALE = math.sqrt(H / G)
T_END_STAR = 5.6
SENSORS_Y = (0.003, 0.015, 0.030, 0.080)  # m (verification/data/README.md)
SENSOR_DIAMETER = 0.0042  # m, second-hand (verification/data/README.md)
PLATEAU = (3.0, 5.5)  # t*, the impact case's plateau window
STRIP = 0.1  # m, the strip next to the far wall whose depth and velocity are recorded
WRITE_INTERVAL = 0.05  # s, full fields (for analysis)
MAX_CO = 0.5
MAX_DT = 5.0e-4  # s: wall probes every step => >= 2 kHz
TINY = {"cells_per_H": 8, "end_star": 2.9}  # past the impact (t* ~ 2.4) in a few seconds

FOAM_ENV = {"WM_PROJECT_DIR": "/usr/share/openfoam"}

# Boundary conditions of the tank's top: open (the default: the jet that runs up the far wall
# can leave, as over the experiment's open tank) or closed by a lid (the SPH scene's y_max wall).
TOP = {
    "open": {
        "TOP_PATCH": "patch",
        "TOP_U": "        type            pressureInletOutletVelocity;\n"
        "        value           uniform (0 0 0);",
        "TOP_P": "        type            totalPressure;\n        p0              uniform 0;\n"
        "        value           uniform 0;",
        "TOP_ALPHA": "        type            inletOutlet;\n        inletValue      uniform 0;\n"
        "        value           uniform 0;",
    },
    "closed": {
        "TOP_PATCH": "wall",
        "TOP_U": "        type            @WALL_U@;",
        "TOP_P": "        type            fixedFluxPressure;\n        value           uniform 0;",
        "TOP_ALPHA": "        type            zeroGradient;",
    },
}
WALLS = ("noSlip", "slip")  # noSlip: the physical wall (default); slip: the SPH scene's free slip
# the committed runs (cells per H, top, walls): the mesh study, then the SPH scene's lid and free slip
STUDY = [(20, "open", "noSlip"), (40, "open", "noSlip"), (60, "open", "noSlip"), (20, "closed", "noSlip"),
         (20, "open", "slip"), (40, "closed", "noSlip"), (40, "open", "slip")]  # fmt: skip


# ----------------------------------------------------------------------------- set-up
def mesh(cells_per_h: int) -> dict:
    dy = H / cells_per_h
    nx2 = int(round((LX - XC) / dy))
    return {"dy": dy, "nx1": 2 * cells_per_h, "nx2": nx2, "ny": int(round(LY / dy)), "dx2": (LX - XC) / nx2}


def wall_faces_y(cells_per_h: int) -> np.ndarray:
    m = mesh(cells_per_h)
    return (np.arange(m["ny"]) + 0.5) * m["dy"]


def case_values(
    cells_per_h: int, end_time: float, ranks: int = 1, top: str = "open", walls: str = "noSlip"
) -> dict:
    m = mesh(cells_per_h)
    bcs = {k: v.replace("@WALL_U@", walls) for k, v in TOP[top].items()}
    probes = "\n".join(
        f"            ({C.fmt(LX, 10)} {C.fmt(y, 10)} {C.fmt(0.5 * m['dy'], 10)})"
        for y in wall_faces_y(cells_per_h)
    )
    return {
        "LX": C.fmt(LX, 10),
        "LY": C.fmt(LY, 10),
        "XC": C.fmt(XC, 10),
        "H": C.fmt(H, 10),
        "YT": C.fmt(LY, 10),
        "DZ": C.fmt(m["dy"], 10),
        "NX1": m["nx1"],
        "NX2": m["nx2"],
        "NY": m["ny"],
        "END_TIME": C.fmt(end_time, 10),
        "WRITE_INTERVAL": C.fmt(WRITE_INTERVAL),
        "DELTA_T0": C.fmt(min(1e-4, 0.01 * m["dy"])),
        "MAX_CO": C.fmt(MAX_CO),
        "MAX_DT": C.fmt(MAX_DT),
        "PROBES": probes,
        "RANKS": ranks,
        "WALL_U": walls,
        # pressure reference for the closed top: in the air under the lid above the upstream wall
        "PREF_X": C.fmt(0.5 * m["dy"], 10),
        "PREF_Y": C.fmt(LY - 0.5 * m["dy"], 10),
        "PREF_Z": C.fmt(0.5 * m["dy"], 10),
        **bcs,
    }


def write_case(work: Path, values: dict) -> None:
    C.copy_template(TEMPLATE_DIR, work, values)
    shutil.copy(work / "0" / "alpha.water.orig", work / "0" / "alpha.water")


# ----------------------------------------------------------------------------- reduction
def read_probes(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A patchProbes scalar file: (times, values[n_times, n_probes])."""
    rows = []
    for line in Path(path).read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        rows.append([float(v) for v in line.split()])
    arr = np.array(rows)
    # a restarted or adjusted step can repeat a time: keep the last value written for it
    _, last = np.unique(arr[::-1, 0], return_index=True)
    arr = arr[::-1][np.sort(last)]
    arr = arr[np.argsort(arr[:, 0])]
    return arr[:, 0], arr[:, 1:]


def segment_weights(face_y: np.ndarray, dy: float, yc: float, width: float = SENSOR_DIAMETER) -> np.ndarray:
    """Overlap of each wall face [y - dy/2, y + dy/2] with the sensor segment, normalised to 1."""
    lo, hi = yc - 0.5 * width, yc + 0.5 * width
    w = np.clip(np.minimum(face_y + 0.5 * dy, hi) - np.maximum(face_y - 0.5 * dy, lo), 0.0, None)
    return w / w.sum()


def reduce_probes(case: Path, cells_per_h: int) -> dict:
    root = case / "postProcessing" / "wallFaces"
    start = sorted(root.iterdir(), key=lambda p: float(p.name))[0]
    t, p = read_probes(start / "p")
    _, alpha = read_probes(start / "alpha.water")
    face_y = wall_faces_y(cells_per_h)
    assert p.shape[1] == len(face_y), "one probe per wall face expected"
    dy = mesh(cells_per_h)["dy"]
    sensors = np.stack([p @ segment_weights(face_y, dy, yc) for yc in SENSORS_Y], axis=1)
    return {
        "t": t,
        "p_star": sensors / (RHO_W * G * H),
        "wall_depth": np.clip(alpha, 0.0, 1.0).sum(axis=1) * dy,
        "face_y": face_y,
        "p_faces": p,
        "alpha_faces": alpha,
    }


def water_area(case: Path, cells_per_h: int) -> np.ndarray:
    """Water area (sum alpha * cell area) at every written time."""
    m = mesh(cells_per_h)
    n = m["ny"] * (m["nx1"] + m["nx2"])
    centres = read_internal_field(case / "0" / "C")
    cell_dx = np.where(centres[:, 0] < XC, XC / m["nx1"], m["dx2"])
    out = []
    for _, d in time_dirs(case):
        f = d / "alpha.water"
        if f.exists():
            out.append(float((read_internal_field(f, n) * cell_dx).sum() * m["dy"]))
    return np.array(out)


def strip_series(case: Path, cells_per_h: int) -> dict:
    """At every written time, over the strip within STRIP of the far wall: the water area per unit
    strip width (a mean depth) and the water's mean velocity (alpha-weighted)."""
    m = mesh(cells_per_h)
    n = m["ny"] * (m["nx1"] + m["nx2"])
    xc = read_internal_field(case / "0" / "C")[:, 0]
    s = xc > LX - STRIP
    out = {"t": [], "depth": [], "u": [], "v": []}
    for t, d in time_dirs(case):
        if not (d / "U").exists() or not (d / "alpha.water").exists():
            continue
        a = np.clip(read_internal_field(d / "alpha.water", n)[s], 0.0, 1.0)
        a[a < 1e-6] = 0.0  # no velocity of an empty strip
        u = read_internal_field(d / "U", n)[s]
        area = a.sum() * m["dx2"] * m["dy"]
        out["t"].append(t)
        out["depth"].append(area / STRIP)
        out["u"].append(float((a * u[:, 0]).sum() / a.sum()) if a.sum() > 0 else 0.0)
        out["v"].append(float((a * u[:, 1]).sum() / a.sum()) if a.sum() > 0 else 0.0)
    return {k: np.array(v) for k, v in out.items()}


def write_strip(path: Path, case: Path, cells_per_h: int, header: str) -> Path:
    st = strip_series(case, cells_per_h)
    with open(path, "w", newline="") as fh:
        fh.write(
            header + f"; strip x > {LX - STRIP:g} m: depth = water area / {STRIP} m, u and v alpha-weighted\n"
        )
        w = csv.writer(fh)
        w.writerow(["t_s", "t_star", "depth_m", "u_m_s", "v_m_s"])
        for t, d, u, v in zip(st["t"], st["depth"], st["u"], st["v"]):
            w.writerow([f"{t:.6g}", f"{t / TIME_SCALE:.6g}", f"{d:.6g}", f"{u:.6g}", f"{v:.6g}"])
    return path


def impact_metrics(t_star: np.ndarray, p_star: np.ndarray) -> dict:
    """The impact case's metrics (lobovsky_measurement.metrics, the same code as for SPH).
    The plateau's moving average is the SPH scene's tau_ac = 4 H / c0 (c0 = 10 sqrt(2 g H)), so
    that SPH, experiment and this reference pass through the same filter."""
    from reference_cases.lobovsky_measurement import metrics

    c0 = 10.0 * math.sqrt(2.0 * G * H)
    m = metrics({"t_star": t_star, "p_star": p_star, "status": "completed", "reflections": 0, "c0": c0})
    return {k: (round(v, 5) if isinstance(v, float) else v) for k, v in m.items()}


def write_outputs(out: Path, label: str, red: dict, header: str) -> dict:
    paths = {
        "sensors": out / f"openfoam_{label}_sensors.csv",
        "profile": out / f"openfoam_{label}_wall_profile.csv",
    }
    with open(paths["sensors"], "w", newline="") as fh:
        fh.write(header + "; p_star = face-averaged p / (rho g H) over 4.2 mm; wall_depth = sum(alpha dy)\n")
        w = csv.writer(fh)
        w.writerow(["t_s", "t_star", "p_star_s1", "p_star_s2", "p_star_s3", "p_star_s4", "wall_depth_m"])
        for t, ps, d in zip(red["t"], red["p_star"], red["wall_depth"]):
            w.writerow([f"{t:.7g}", f"{t / TIME_SCALE:.7g}"] + [f"{v:.6g}" for v in ps] + [f"{d:.6g}"])
    ts = red["t"] / TIME_SCALE
    win = (ts >= PLATEAU[0]) & (ts <= PLATEAU[1])
    with open(paths["profile"], "w", newline="") as fh:
        fh.write(header + "; time means over t* 3-5.5 of the wall-face values (every step)\n")
        w = csv.writer(fh)
        w.writerow(["y_m", "p_star_mean", "alpha_mean"])
        if win.any():
            pm = red["p_faces"][win].mean(axis=0) / (RHO_W * G * H)
            am = red["alpha_faces"][win].mean(axis=0)
            for y, a, b in zip(red["face_y"], pm, am):
                w.writerow([f"{y:.6g}", f"{a:.6g}", f"{b:.6g}"])
    return paths


def read_sensors(path: Path) -> dict:
    arr = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
    return {"t_star": arr[:, 1], "p_star": arr[:, 2:6], "wall_depth": arr[:, 6]}


# ----------------------------------------------------------------------------- pipeline
def variant(top: str = "open", walls: str = "noSlip") -> str:
    """'' for the reference set-up (open top, noSlip walls), else the label's suffix."""
    return ("" if top == "open" else f"_{top}") + ("" if walls == "noSlip" else f"_{walls}")


def run_case(
    cells_per_h: int = 40,
    tiny: bool = False,
    out: Path | None = None,
    end_star: float | None = None,
    top: str = "open",
    walls: str = "noSlip",
) -> dict:
    C.require("blockMesh", "setFields", "interFoam", "postProcess")
    if tiny:
        cells_per_h = TINY["cells_per_H"]
        end_star = end_star or TINY["end_star"]
    end_star = end_star or T_END_STAR
    end_time = end_star * TIME_SCALE
    label = f"h{cells_per_h}" + variant(top, walls) + ("_tiny" if tiny else "")
    work = WORK_DIR / label
    official = out is None and not tiny
    out = Path(out) if out is not None else (DATA_DIR if not tiny else work / "reduced")
    write_case(work, case_values(cells_per_h, end_time, top=top, walls=walls))
    out.mkdir(parents=True, exist_ok=True)
    cmds: list = []
    t0 = time.perf_counter()
    cpu0 = os.times()
    logs = work / "logs"
    logs.mkdir()
    env = FOAM_ENV
    C.run(["blockMesh"], work, logs / "blockMesh.log", env, cmds)
    C.run(["setFields"], work, logs / "setFields.log", env, cmds)
    solver_wall = C.run(["interFoam"], work, logs / "interFoam.log", env, cmds)
    cpu1 = os.times()
    C.run(
        ["postProcess", "-func", "writeCellCentres", "-time", "0"], work, logs / "cellCentres.log", env, cmds
    )
    red = reduce_probes(work, cells_per_h)
    area = water_area(work, cells_per_h)
    total_wall = time.perf_counter() - t0

    version = foam_version(logs / "interFoam.log")
    m = mesh(cells_per_h)
    n_cells = m["ny"] * (m["nx1"] + m["nx2"])
    header = (
        f"# tool=OpenFOAM {version} interFoam (laminar VOF), Debian package openfoam "
        f"{C.debian_package_version('openfoam')}; mesh=({m['nx1']}+{m['nx2']})x{m['ny']}x1, "
        f"dy=H/{cells_per_h}; "
        f"Lobovsky 2014 H={H} m, tank {LX} x {LY} m {top} top, column {XC} x {H} m, no gate, {walls} walls"
    )
    paths = write_outputs(out, label.removesuffix("_tiny"), red, header)
    paths["strip"] = write_strip(
        out / f"openfoam_{label.removesuffix('_tiny')}_strip.csv", work, cells_per_h, header
    )
    ts = red["t"] / TIME_SCALE
    dt_samples = np.diff(red["t"])
    entry = {
        "date_utc": C.now_iso(),
        "cells_per_H": cells_per_h,
        "top": top,
        "walls": walls,
        "dy_m": m["dy"],
        "dx_downstream_m": m["dx2"],
        "mesh": f"({m['nx1']} + {m['nx2']}) x {m['ny']} x 1",
        "n_cells": n_cells,
        "end_time_s": end_time,
        "end_t_star": end_star,
        "tiny": tiny,
        "wall_time_total_s": round(total_wall, 1),
        "wall_time_solver_s": round(solver_wall, 1),
        "cpu_time_solver_s": round(
            cpu1.children_user - cpu0.children_user + cpu1.children_system - cpu0.children_system, 1
        ),  # fmt: skip
        "solver": solver_stats(logs / "interFoam.log"),
        "wall_samples": len(ts),
        "wall_sample_interval_max_s": float(dt_samples.max()) if len(dt_samples) else None,
        "water_area_initial_m2": XC * H,
        "water_area_max_rel_change": float(np.max(np.abs(area - XC * H)) / (XC * H)) if len(area) else None,
        "metrics": impact_metrics(ts, red["p_star"]),
        "outputs": {k: str(C._rel(v)) for k, v in paths.items()},
        "commands": cmds,
        "host": C.host_facts(),
    }
    top = {
        "case": "Lobovsky et al. (2014) dam break H = 0.3 m, far-wall pressure; interFoam laminar VOF, 2D",
        "tool": {
            "name": "OpenFOAM (interFoam)",
            "version": version,
            "debian_package": f"openfoam {C.debian_package_version('openfoam')}",
        },
        "reproduce": "python -m reference_cases.openfoam_lobovsky_impact.run --cells-per-H N",
        "parameters": {
            "H_m": H,
            "column_m": [XC, H],
            "tank_m": [LX, LY],
            "top": "open (atmosphere patch: totalPressure p0 = 0, pressureInletOutletVelocity); "
            "variant closed (a wall, pRefPoint under the lid): label suffix _closed",
            "gate": "none (released at t = 0, as the SPH scene)",
            "water": {"rho": RHO_W, "nu": 1e-6},
            "air": {"rho": 1, "nu": 1.48e-5},
            "sigma_N_per_m": 0.07,
            "g": G,
            "t_end_star": T_END_STAR,
            "walls": "noSlip U, fixedFluxPressure p_rgh, zeroGradient alpha (90 deg contact); "
            "variant slip (the SPH scene's free slip): label suffix _slip",
            "numerics": "Euler, MULES cAlpha 1, PIMPLE 1 outer / 3 p correctors, "
            f"maxCo = maxAlphaCo = {MAX_CO}, maxDeltaT = {MAX_DT} s",
            "sensors_y_m": list(SENSORS_Y),
            "sensor_segment_m": SENSOR_DIAMETER,
            "sensor_value": "overlap-weighted mean of the wall-face p over the segment, every time step",
        },
        "environment": FOAM_ENV,
        "source": "Lobovsky, L., Botia-Vera, E., Castellana, F., Mas-Soler, J. & Souto-Iglesias, A. "
        "(2014). Experimental investigation of dynamic pressure loads during dam break. "
        "J. Fluids Struct. 48, 407-434.",
    }
    if official:
        C.update_manifest(MANIFEST, label, entry, top)
    else:
        (out / "manifest.json").write_text(json.dumps({**top, "runs": {label: entry}}, indent=2) + "\n")
    return {"label": label, "paths": paths, "work": work, "reduced": red, "entry": entry, "area": area}


def summary() -> str:
    data = json.loads(MANIFEST.read_text())
    lines = [
        "| run | cells | steps | wall s (CPU s) | load | impact t* s2 | plateau mean s2 | sd s2 "
        "| peak s1/s2 |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for key, e in data["runs"].items():
        mt = e["metrics"]
        lines.append(
            f"| {key} | {e['n_cells']} | {e['solver']['time_steps']} | {e['wall_time_total_s']} "
            f"({e.get('cpu_time_solver_s')}) | {e['host']['load_avg_at_end']} | {mt.get('impact_s2')} | "
            f"{mt.get('plateau_mean_s2')} | {mt.get('plateau_sd_s2')} | "
            f"{mt.get('peak_s1')}/{mt.get('peak_s2')} |"
        )
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cells-per-H", type=int, default=40, help="cells per water height H")
    p.add_argument("--tiny", action="store_true", help="H/8 to t* = 2.9 (seconds)")
    p.add_argument("--out", type=Path, default=None, help="output dir (default data/, or work/ for --tiny)")
    p.add_argument("--end-star", type=float, default=None)
    p.add_argument("--top", choices=sorted(TOP), default="open", help="open top (default) or a lid")
    p.add_argument("--walls", choices=WALLS, default="noSlip", help="noSlip (default) or slip walls")
    p.add_argument("--nice", type=int, default=0, help="raise the niceness of the tool runs")
    p.add_argument("--summary", action="store_true", help="print the manifest's runs as a table")
    p.add_argument("--strip-only", action="store_true", help="(re)write the strip series of an existing run")
    a = p.parse_args(argv)
    if a.summary:
        print(summary())
        return 0
    if a.strip_only:
        # the strip series of an existing official run (work/h{N}), e.g. one made before it existed
        label = f"h{a.cells_per_H}" + variant(a.top, a.walls)
        head = (DATA_DIR / f"openfoam_{label}_sensors.csv").read_text().splitlines()[0].split("; p_star")[0]
        path = write_strip(DATA_DIR / f"openfoam_{label}_strip.csv", WORK_DIR / label, a.cells_per_H, head)
        entry = json.loads(MANIFEST.read_text())["runs"][label]
        entry["outputs"]["strip"] = str(C._rel(path))
        C.update_manifest(MANIFEST, label, entry, {})
        print("wrote", path)
        return 0
    if a.nice:
        os.nice(a.nice)
    res = run_case(a.cells_per_H, a.tiny, a.out, a.end_star, a.top, a.walls)
    e = res["entry"]
    print(
        f"{res['label']}: {e['n_cells']} cells, {e['solver']['time_steps']} steps, "
        f"wall {e['wall_time_total_s']} s "
        f"(solver {e['wall_time_solver_s']} s, CPU {e['cpu_time_solver_s']} s), water area drift "
        f"{e['water_area_max_rel_change']:.2e}; metrics {e['metrics']}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
