"""OpenFOAM (interFoam, laminar two-phase VOF) reference run of the overflow nappe of the
scour set-up (docs/scour_setup.md) falling onto a rigid, non-erodible bed; reduced to
small CSV series (issue 11, item 8).

    python -m reference_cases.openfoam_overflow_nappe.run --q 0.06 --dx-mm 2.5
                                                          [--ranks 1|2] [--tiny] [--out DIR]

Geometry (frame of docs/scour_setup.md, y up): the rigid bed is the unscoured soil
surface y = 0.095 m, from the breakwater's vertical landward face x = 0 to the end of the
soil layer x = 0.25 m. The nappe enters horizontally through x = 0 between the crown
y = 0.105 m (0.01 m above the soil: the seed's fall height) and the crown plus the critical
depth y_c = (q^2/g)^(1/3), with the uniform speed u_c = q / y_c and alpha = 1. Outlet at
x = 0.25 m (zero gradient; the flow there is near critical, see the README); atmosphere
(total pressure 0) on top and above the nappe at x = 0. Water 1000 kg/m3, nu = 1e-6
m2/s; air 1 kg/m3, nu = 1.48e-5 m2/s; sigma = 0.07 N/m; laminar (why: README).

Steps: the dictionaries in case/ are copied into work/<run>/ with the numbers filled in,
then blockMesh, [decomposePar], interFoam stage 1 (0 to 0.05 s, written every 5 ms: the
first impact), interFoam stage 2 (restart to the end time), [reconstructPar],
postProcess -func writeCellCentres. The last time folder's time averages (fieldAverage
over [avg_start, end]) and the stage-1 fields are reduced to

* nappe_<run>.csv: upper and lower alpha = 0.5 surfaces of the averaged flow per cell
  column (lower NaN where no air is under the jet), with the ballistic surfaces of a jet
  leaving the crown at critical depth;
* bed_<run>.csv: time-averaged bed pressure (gauge, on the bed faces) and the
  volume-equivalent water depth sum(alpha dy) along the bed;
* velocity_<run>.csv: time-averaged alpha and velocity profiles at x = 0.10, 0.15, 0.20 m;
* early_<run>.csv: the jet's instantaneous surfaces per column every 5 ms to 0.05 s;
* history_<run>.csv: water discharge through the outlet, inlet and atmosphere and the
  water area per unit width (every 0.01 s), which show when the flow is quasi-steady;

and manifest.json gets the run's record (steadiness, volume balance, first impact against
ballistics, bed-pressure peak) and, for official runs, the mesh study.
"""

from __future__ import annotations

import argparse
import csv
import fcntl
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

G = 9.81
Y_SOIL = 0.095  # soil surface = rigid bed [m] (soil layer 0.095 m deep, seed sec. 3)
FALL = 0.01  # crown above the soil surface [m] (the seed's fall height)
Y_CROWN = Y_SOIL + FALL
LX = 0.25  # length of the soil layer [m] (seed sec. 3)
TOP_MARGIN = 0.04  # air above the nappe's inflow section [m]
STATIONS = (0.10, 0.15, 0.20)  # velocity profile stations [m]
END_TIME = 3.0
AVG_START = 2.0
WRITE_INTERVAL = 0.25
EARLY_END = 0.05  # stage 1: the first impact (the lower surface lands at t = sqrt(2 fall / g) = 0.045 s)
EARLY_WRITE = 0.005
MAX_CO = 0.5
RHO_W = 1000.0
STUDY_Q = (0.06, 0.11)  # the seed's smallest and largest unit discharge
STUDY_DX_MM = (5.0, 10.0 / 3.0, 2.5)  # mesh study: each divides 0.25 m, 0.01 m and 0.04 m
TINY = {"dx_mm": 5.0, "end_time": 0.6, "avg_start": 0.4, "write_interval": 0.2}

FOAM_ENV = {"WM_PROJECT_DIR": "/usr/share/openfoam"}


# ----------------------------------------------------------------------------- hydraulics
def critical_depth(q: float, g: float = G) -> float:
    """y_c = (q^2/g)^(1/3) (e.g. Chow 1959, Open-Channel Hydraulics, eq. 3-9 for a
    rectangular channel); the nappe's thickness at the inflow section."""
    return (q * q / g) ** (1.0 / 3.0)


def ballistic_surfaces(x, q: float, g: float = G) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower surfaces of a free jet leaving x = 0 horizontally with the
    uniform speed u_c over the depth y_c (crown to crown + y_c).

    With the pressure atmospheric inside a thin free jet every fluid particle moves as
    a projectile, y = y0 - g x^2 / (2 u^2) (the nappe trajectory of e.g. Chanson 2004,
    The Hydraulics of Open Channel Flow, 2nd ed., sec. on free-falling nappes; also
    Rajaratnam 1976, Turbulent Jets). The drop below the exit is the same for both
    surfaces because the speed is uniform.
    """
    yc = critical_depth(q, g)
    uc = q / yc
    drop = g * np.asarray(x, float) ** 2 / (2.0 * uc * uc)
    return Y_CROWN + yc - drop, Y_CROWN - drop


def ballistic_impact_x(q: float, g: float = G) -> dict:
    """Where the ballistic lower surface and centre line reach the bed."""
    yc = critical_depth(q, g)
    uc = q / yc
    return {
        "lower_surface_x_m": uc * math.sqrt(2.0 * FALL / g),
        "centre_line_x_m": uc * math.sqrt(2.0 * (FALL + 0.5 * yc) / g),
        "impact_speed_lower_m_s": math.sqrt(uc * uc + 2.0 * g * FALL),
    }


# ----------------------------------------------------------------------------- set-up
def mesh_counts(q: float, dx: float) -> dict:
    yc = critical_depth(q)
    return {
        "NX": int(round(LX / dx)),
        "NA": int(round(FALL / dx)),
        "NB": max(1, int(round(yc / dx))),
        "NC": int(round(TOP_MARGIN / dx)),
    }


def case_values(
    q: float, dx: float, end_time: float, avg_start: float, write_interval: float, ranks: int, stage: int = 1
):
    """Numbers for the dictionaries; stage 1 runs to EARLY_END writing every EARLY_WRITE,
    stage 2 restarts from there to end_time writing every write_interval."""
    yc = critical_depth(q)
    n = mesh_counts(q, dx)
    y_top = Y_CROWN + yc + TOP_MARGIN
    return {
        "LX": C.fmt(LX, 10),
        "YS": C.fmt(Y_SOIL, 10),
        "YC": C.fmt(Y_CROWN, 10),
        "YN": C.fmt(Y_CROWN + yc, 10),
        "YT": C.fmt(y_top, 10),
        "DZ": C.fmt(dx, 10),
        **n,
        "UC": C.fmt(q / yc, 10),
        "START_FROM": "startTime" if stage == 1 else "latestTime",
        "END_TIME": C.fmt(min(EARLY_END, end_time) if stage == 1 else end_time),
        "AVG_START": C.fmt(avg_start),
        "EARLY_WRITE": C.fmt(EARLY_WRITE),
        "WRITE_INTERVAL": C.fmt(write_interval),
        "WRITE_NOW": C.fmt(EARLY_WRITE if stage == 1 else stage2_write_interval(end_time, write_interval)),
        "DELTA_T0": C.fmt(min(1e-4, 0.02 * dx)),
        "MAX_CO": C.fmt(MAX_CO),
        "RANKS": ranks,
    }


def stage2_write_interval(end_time: float, write_interval: float) -> float:
    """Write times of a restart count from its start time, so stage 2 writes every
    (end - EARLY_END)/n with n the nearest whole number of write_interval: the last write,
    which holds the time averages, falls on end_time."""
    n = max(1, round((end_time - EARLY_END) / write_interval))
    return (end_time - EARLY_END) / n


def write_case(work: Path, values: dict, only: str | None = None) -> None:
    """Copy the dictionaries into `work` with the numbers filled in (only one file, the
    path relative to case/, when `only` is given)."""
    if only is not None:
        (work / only).write_text(C.fill_template((TEMPLATE_DIR / only).read_text(), values))
        return
    C.copy_template(TEMPLATE_DIR, work, values)


# ----------------------------------------------------------------------------- reading
def read_patch_field(path: Path, patch: str) -> np.ndarray:
    """The `value` list of one patch in the boundaryField of an ASCII scalar field."""
    text = Path(path).read_text()
    bf = text.index("boundaryField")
    m = re.search(r"\n\s*" + re.escape(patch) + r"\s*\{", text[bf:])
    if m is None:
        raise ValueError(f"{path}: no patch {patch}")
    start = bf + m.end()
    block = text[start : text.index("}", start)]
    v = re.search(r"value\s+nonuniform\s+List<scalar>\s*(\d+)\s*\(([^)]*)\)", block)
    if v is None:
        u = re.search(r"value\s+uniform\s+(\S+);", block)
        if u is None:
            raise ValueError(f"{path}: patch {patch} has no value")
        return np.array([float(u.group(1))])
    arr = np.array(v.group(2).split(), float)
    if len(arr) != int(v.group(1)):
        raise ValueError(f"{path}: patch {patch}: expected {v.group(1)} values, read {len(arr)}")
    return arr


def read_function_object(case: Path, name: str, dz: float = 1.0) -> np.ndarray:
    """(time, value / dz) rows of a function object's .dat files (the stages
    concatenated); dz is the mesh's thickness, so that integrals are per unit width."""
    rows = []
    for f in sorted((case / "postProcessing" / name).rglob("*.dat")):
        for line in f.read_text().splitlines():
            if line.strip() and not line.startswith("#"):
                parts = line.split()
                rows.append((float(parts[0]), float(parts[1]) / dz))
    if not rows:
        raise ValueError(f"no data from function object {name} in {case}")
    return np.array(sorted(rows))


class Columns:
    """The structured mesh as columns: cell indices sorted by y, per column sorted by x."""

    def __init__(self, centres: np.ndarray, dx: float):
        x, y = centres[:, 0], centres[:, 1]
        col = np.round(x / dx - 0.5).astype(int)
        self.x = np.unique(np.round(x, 9))
        self.cells = []
        for i in range(col.max() + 1):
            idx = np.where(col == i)[0]
            self.cells.append(idx[np.argsort(y[idx])])
        self.y = y
        assert len(self.cells) == len(self.x), "columns do not line up"

    def profile(self, field: np.ndarray, i: int) -> tuple[np.ndarray, np.ndarray]:
        c = self.cells[i]
        return self.y[c], field[c]


def alpha_crossings(y: np.ndarray, a: np.ndarray) -> list[tuple[float, int]]:
    """Heights where alpha crosses 0.5 (linear between cell centres), from the top down,
    each with its sign: +1 air above / water below (an upper surface), -1 the reverse."""
    out = []
    for k in range(len(y) - 1, 0, -1):
        hi, lo = a[k], a[k - 1]
        if (hi - 0.5) * (lo - 0.5) < 0.0:
            yy = y[k] + (0.5 - hi) / (lo - hi) * (y[k - 1] - y[k])
            out.append((float(yy), 1 if lo > hi else -1))
    return out


def reduce_fields(case: Path, q: float, dx: float) -> dict:
    """Nappe surfaces, bed pressure, depth and velocity profiles from the time averages
    of the last time folder; outlet discharge and water area from the function objects."""
    centres = read_internal_field(case / "0" / "C")
    cols = Columns(centres, dx)
    n = len(centres)
    t_last, last = time_dirs(case)[-1]
    t_end = float(read_function_object(case, "waterVolume")[-1, 0])
    if abs(t_last - t_end) > 1e-6:
        raise ValueError(f"{case}: last written time {t_last} is not the end time {t_end}")
    alpha = np.clip(read_internal_field(last / "alpha.waterMean", n), 0.0, 1.0)
    umean = read_internal_field(last / "UMean", n)
    p_bed = read_patch_field(last / "pMean", "bed")
    # bed faces are ordered along x like the bottom cells (blockMesh), check it
    bottom = np.array([c[0] for c in cols.cells])
    assert len(p_bed) == len(bottom)

    # nappe: an upper surface, then (if the jet is still free) a lower surface below it
    nappe = []
    for i, xc in enumerate(cols.x):
        yy, aa = cols.profile(alpha, i)
        cr = alpha_crossings(yy, aa)
        if not cr or cr[0][1] != 1:
            continue
        upper = cr[0][0]
        lower = cr[1][0] if len(cr) > 1 and cr[1][1] == -1 else float("nan")
        nappe.append((float(xc), upper, lower))
    nappe = np.array(nappe) if nappe else np.zeros((0, 3))

    depth = np.array(
        [
            float(np.sum(cols.profile(alpha, i)[1] * _dy(cols.profile(alpha, i)[0])))
            for i in range(len(cols.x))
        ]
    )
    i_max = int(np.argmax(p_bed))
    # the free lower surface ends where the jet lands: the last column of the run of
    # columns from x = 0 that still have a lower surface above the bed
    free = np.isfinite(nappe[:, 2]) if len(nappe) else np.zeros(0, bool)
    n_free = int(np.argmin(free)) if len(free) and not free.all() else len(free)
    x_land = float(nappe[n_free - 1, 0] + 0.5 * dx) if n_free else float("nan")

    velocity = {}
    for xs in STATIONS:
        i = int(np.argmin(np.abs(cols.x - xs)))
        c = cols.cells[i]
        velocity[xs] = np.column_stack([cols.y[c], alpha[c], umean[c, 0], umean[c, 1]])

    out_q = read_function_object(case, "outflow", dx)
    in_q = read_function_object(case, "inflow", dx)
    atm_q = read_function_object(case, "atmosphereFlux", dx)
    vol = read_function_object(case, "waterVolume", dx)
    return {
        "t_last": t_last,
        "x": cols.x,
        "nappe": nappe,
        "n_free": n_free,
        "x_land": x_land,
        "p_bed": p_bed,
        "depth": depth,
        "x_pmax": float(cols.x[i_max]),
        "p_max": float(p_bed[i_max]),
        "velocity": velocity,
        "outflow": out_q,
        "inflow": in_q,
        "atmosphere": atm_q,
        "water_area": vol,
    }


def reduce_early(case: Path, q: float, dx: float) -> dict:
    """The first impact (stage 1): per written time, the jet's upper and lower alpha = 0.5
    surfaces per column, its leading edge (the largest x of a cell with alpha > 0.5 above
    the crown level, plus half a cell) and its lowest point (the lowest lower surface)."""
    centres = read_internal_field(case / "0" / "C")
    cols = Columns(centres, dx)
    n = len(centres)
    rows, head = [], []
    for t, d in time_dirs(case):
        if t <= 0.0 or t > EARLY_END + 1e-9 or not (d / "alpha.water").exists():
            continue
        alpha = read_internal_field(d / "alpha.water", n)
        wet = np.where((alpha > 0.5) & (cols.y > Y_CROWN))[0]
        x_front = float(centres[wet, 0].max() + 0.5 * dx) if len(wet) else 0.0
        lows = []
        for i, xc in enumerate(cols.x):
            if xc > x_front:
                break
            yy, aa = cols.profile(alpha, i)
            cr = alpha_crossings(yy, aa)
            if len(cr) >= 2 and cr[0][1] == 1 and cr[1][1] == -1:
                rows.append((t, float(xc), cr[0][0], cr[1][0]))
                lows.append(cr[1][0])
        head.append((t, x_front, min(lows) if lows else float("nan")))
    return {"rows": np.array(rows) if rows else np.zeros((0, 4)), "head": np.array(head)}


def early_check(early: dict, q: float) -> dict:
    """The first impact against ballistics, before the jet lands (t < sqrt(2 fall/g)):
    the leading edge moves at u_c (x = u_c t) and the lowest water, which left the crown
    edge at t = 0, falls freely (y = crown - g t^2 / 2). The jet is shorter than its
    thickness y_c until it lands, so there is no steady free nappe to compare."""
    uc = q / critical_depth(q)
    h = early["head"]
    land = math.sqrt(2.0 * FALL / G)
    pre = h[(h[:, 0] < land) & np.isfinite(h[:, 2])]
    out: dict = {"landing_time_s": land, "times": int(len(pre))}
    if len(pre):
        out["t_s"] = [round(float(v), 4) for v in pre[:, 0]]
        out["front_x_m"] = [round(float(v), 5) for v in pre[:, 1]]
        out["lowest_y_m"] = [round(float(v), 5) for v in pre[:, 2]]
        out["front_minus_uc_t_max_abs_m"] = float(np.max(np.abs(pre[:, 1] - uc * pre[:, 0])))
        fall = Y_CROWN - 0.5 * G * pre[:, 0] ** 2
        out["lowest_minus_free_fall_max_abs_m"] = float(np.max(np.abs(pre[:, 2] - fall)))
    return out


def _dy(y: np.ndarray) -> np.ndarray:
    """Cell heights of a column from its cell-centre heights (cells share faces)."""
    faces = np.empty(len(y) + 1)
    faces[1:-1] = 0.5 * (y[1:] + y[:-1])
    faces[0] = 2 * y[0] - faces[1]
    faces[-1] = 2 * y[-1] - faces[-2]
    return np.diff(faces)


# ----------------------------------------------------------------------------- checks
def steadiness(series: dict, q: float, avg_start: float) -> dict:
    """Outlet discharge against the inflow q over the averaging window, and the drift of
    the stored water area between the window's halves."""
    oq = series["outflow"]
    wa = series["water_area"]
    t_end = oq[-1, 0]
    w = oq[:, 0] >= avg_start
    mid = 0.5 * (avg_start + t_end)
    a1 = wa[(wa[:, 0] >= avg_start) & (wa[:, 0] < mid), 1].mean()
    a2 = wa[wa[:, 0] >= mid, 1].mean()
    # time-weighted mean of the per-step outlet discharge
    tt, qq = oq[w, 0], oq[w, 1]
    q_mean = float(np.trapezoid(qq, tt) / (tt[-1] - tt[0])) if len(tt) > 1 else float("nan")
    return {
        "outflow_mean_m2_s": q_mean,
        "outflow_over_q": q_mean / q,
        "outflow_min_max_m2_s": [float(qq.min()), float(qq.max())],
        "water_area_halves_m2": [float(a1), float(a2)],
        "water_area_rel_change": float((a2 - a1) / a1),
    }


def volume_balance(series: dict) -> dict:
    """Water area per unit width against the time integral of the patch fluxes (outward
    positive, so the inlet's is negative): A(t) - A(t0) + int(outlet + inlet + atmosphere)
    dt = 0 up to the solver's volume error. The records are per step, written at the end
    of each step; each step's flux is applied over that step (right-point rule), which
    closes the balance best (the trapezoid rule leaves a lag error of about half the rise of
    the outflow times a step). The residual left is the difference between alpha_face phi
    and MULES's limited flux at the outlet (measured about 0.1 % of the inflow, tiny run)."""
    t = series["water_area"][:, 0]
    a = series["water_area"][:, 1]
    if not (len(series["outflow"]) == len(series["inflow"]) == len(series["atmosphere"]) == len(t)):
        raise ValueError("function-object records of different lengths")
    net = series["outflow"][:, 1] + series["inflow"][:, 1] + series["atmosphere"][:, 1]
    cum = np.concatenate([[0.0], np.cumsum(net[1:] * np.diff(t))])
    resid = a - a[0] + cum
    inflow_volume = float(-np.sum(series["inflow"][1:, 1] * np.diff(t)))
    return {
        "inflow_mean_m2_s": inflow_volume / (t[-1] - t[0]),
        "atmosphere_outflow_total_m2": float(np.sum(series["atmosphere"][1:, 1] * np.diff(t))),
        "residual_max_abs_m2": float(np.max(np.abs(resid))),
        "residual_over_inflow_volume": float(np.max(np.abs(resid)) / inflow_volume),
    }


def trajectory_check(series: dict, q: float, dx: float) -> dict:
    """The time-averaged upper surface against the ballistic one, from x = 0 to where the
    ballistic lower surface would land. Where the pocket under the nappe is flooded
    (lower surface absent) the jet is supported from below and falls less than a
    projectile: this measures by how much."""
    nap = series["nappe"]
    x_land = ballistic_impact_x(q)["lower_surface_x_m"]
    sel = nap[nap[:, 0] <= x_land]
    if len(sel) == 0:
        return {"columns": 0}
    up, _ = ballistic_surfaces(sel[:, 0], q)
    return {
        "columns": int(len(sel)),
        "x_range_m": [float(sel[0, 0]), float(sel[-1, 0])],
        "free_lower_surface_columns": int(np.isfinite(sel[:, 2]).sum()),
        "upper_max_abs_dev_m": float(np.max(np.abs(sel[:, 1] - up))),
        "upper_drop_at_x_land_m": [
            float(Y_CROWN + critical_depth(q) - sel[-1, 1]),
            float(Y_CROWN + critical_depth(q) - up[-1]),
        ],
    }


# ----------------------------------------------------------------------------- writing
def _label(q: float, dx: float, ranks: int, tiny: bool) -> str:
    s = f"q{q:.2f}_dx{dx * 1000:g}mm".replace(".", "p")
    return s + ("" if ranks == 1 else f"_np{ranks}") + ("_tiny" if tiny else "")


def write_csvs(out: Path, label: str, header: str, q: float, series: dict, early: dict) -> dict:
    paths = {}
    nap = series["nappe"]
    up, lo = ballistic_surfaces(nap[:, 0], q) if len(nap) else (np.zeros(0), np.zeros(0))
    paths["nappe"] = out / f"nappe_{label}.csv"
    with open(paths["nappe"], "w", newline="") as fh:
        fh.write(
            header + "; upper/lower = alpha.waterMean 0.5 contours per cell column (lower nan: no air "
            "under the jet); ballistic = free jet leaving the crown at critical depth\n"
        )
        w = csv.writer(fh)
        w.writerow(["x_m", "upper_m", "lower_m", "upper_ballistic_m", "lower_ballistic_m"])
        for row, u, lw in zip(nap, up, lo):
            w.writerow([f"{row[0]:.6g}", f"{row[1]:.6g}", f"{row[2]:.6g}", f"{u:.6g}", f"{lw:.6g}"])
    paths["bed"] = out / f"bed_{label}.csv"
    with open(paths["bed"], "w", newline="") as fh:
        fh.write(header + "; p = time-averaged gauge pressure on the bed faces; depth = sum(alpha dy)\n")
        w = csv.writer(fh)
        w.writerow(["x_m", "p_bed_Pa", "depth_m"])
        for x, p, d in zip(series["x"], series["p_bed"], series["depth"]):
            w.writerow([f"{x:.6g}", f"{p:.6g}", f"{d:.6g}"])
    paths["velocity"] = out / f"velocity_{label}.csv"
    with open(paths["velocity"], "w", newline="") as fh:
        fh.write(header + "; time-averaged alpha and velocity in the cell column nearest each station\n")
        w = csv.writer(fh)
        w.writerow(["station_x_m", "y_m", "alpha_mean", "ux_m_s", "uy_m_s"])
        for xs, arr in series["velocity"].items():
            for r in arr:
                w.writerow([f"{xs:g}", f"{r[0]:.6g}", f"{r[1]:.4g}", f"{r[2]:.5g}", f"{r[3]:.5g}"])
    paths["early"] = out / f"early_{label}.csv"
    with open(paths["early"], "w", newline="") as fh:
        fh.write(header + "; first impact: instantaneous alpha.water 0.5 surfaces of the free jet\n")
        w = csv.writer(fh)
        w.writerow(["t_s", "x_m", "upper_m", "lower_m", "upper_ballistic_m", "lower_ballistic_m"])
        er = early["rows"]
        eu, el = ballistic_surfaces(er[:, 1], q) if len(er) else (np.zeros(0), np.zeros(0))
        for row, u, lw in zip(er, eu, el):
            w.writerow(
                [f"{row[0]:.4g}", f"{row[1]:.6g}", f"{row[2]:.6g}", f"{row[3]:.6g}", f"{u:.6g}", f"{lw:.6g}"]
            )
    paths["history"] = out / f"history_{label}.csv"
    oq, wa = series["outflow"], series["water_area"]
    iq, aq = series["inflow"], series["atmosphere"]
    grid = np.arange(0.0, oq[-1, 0] + 1e-9, 0.01)
    with open(paths["history"], "w", newline="") as fh:
        fh.write(
            header + "; water discharge sum(alpha phi) through the outlet, the inlet (inward positive) "
            "and the atmosphere, and the water area sum(alpha V)/dz, sampled every 0.01 s\n"
        )
        w = csv.writer(fh)
        w.writerow(["t_s", "outflow_m2_s", "inflow_m2_s", "atmosphere_outflow_m2_s", "water_area_m2"])
        for t in grid:
            w.writerow(
                [
                    f"{t:.4g}",
                    f"{np.interp(t, oq[:, 0], oq[:, 1]):.6g}",
                    f"{-np.interp(t, iq[:, 0], iq[:, 1]):.6g}",
                    f"{np.interp(t, aq[:, 0], aq[:, 1]):.6g}",
                    f"{np.interp(t, wa[:, 0], wa[:, 1]):.6g}",
                ]
            )
    return paths


# ----------------------------------------------------------------------------- pipeline
def run_case(
    q: float = 0.06,
    dx_mm: float = 2.5,
    ranks: int = 1,
    tiny: bool = False,
    out: Path | None = None,
    end_time: float | None = None,
    avg_start: float | None = None,
    keep_fields: bool = True,
) -> dict:
    C.require("blockMesh", "interFoam", "postProcess")
    if ranks > 1:
        C.require("decomposePar", "reconstructPar", "mpirun")
    write_interval = WRITE_INTERVAL
    if tiny:
        dx_mm = TINY["dx_mm"]
        end_time = end_time or TINY["end_time"]
        avg_start = avg_start or TINY["avg_start"]
        write_interval = TINY["write_interval"]
    end_time = end_time or END_TIME
    avg_start = avg_start if avg_start is not None else AVG_START
    dx = dx_mm / 1000.0
    label = _label(q, dx, ranks, tiny)
    work = WORK_DIR / label
    official = out is None and not tiny
    out = Path(out) if out is not None else (DATA_DIR if not tiny else work / "reduced")
    values = case_values(q, dx, end_time, avg_start, write_interval, ranks)
    write_case(work, values)
    out.mkdir(parents=True, exist_ok=True)
    cmds: list = []
    t0 = time.perf_counter()
    logs = work / "logs"
    logs.mkdir()
    env = FOAM_ENV
    C.run(["blockMesh"], work, logs / "blockMesh.log", env, cmds)
    solver_wall = 0.0
    par = ["-parallel"] if ranks > 1 else []
    if ranks > 1:
        C.run(["decomposePar", "-force"], work, logs / "decomposePar.log", env, cmds)
    for stage in (1, 2):
        if stage == 2:
            if end_time <= EARLY_END:
                break
            vals2 = case_values(q, dx, end_time, avg_start, write_interval, ranks, stage=2)
            write_case(work, vals2, only="system/controlDict")
        prefix = C.mpirun_prefix(ranks) if ranks > 1 else []
        solver_wall += C.run(
            prefix + ["interFoam"] + par, work, logs / f"interFoam_stage{stage}.log", env, cmds
        )
    if ranks > 1:
        C.run(["reconstructPar"], work, logs / "reconstructPar.log", env, cmds)
    C.run(
        ["postProcess", "-func", "writeCellCentres", "-time", "0"],
        work,
        logs / "writeCellCentres.log",
        env,
        cmds,
    )
    t_red = time.perf_counter()
    series = reduce_fields(work, q, dx)
    steady = steadiness(series, q, avg_start)
    balance = volume_balance(series)
    traj = trajectory_check(series, q, dx)
    early = reduce_early(work, q, dx)
    first = early_check(early, q)
    total_wall = time.perf_counter() - t0

    version = foam_version(logs / "interFoam_stage1.log")
    yc = critical_depth(q)
    nc = mesh_counts(q, dx)
    n_cells = nc["NX"] * (nc["NA"] + nc["NB"] + nc["NC"])
    header = (
        f"# tool=OpenFOAM {version} interFoam (laminar VOF), Debian package openfoam "
        f"{C.debian_package_version('openfoam')}; q={q} m2/s; y_c={yc:.6g} m; u_c={q / yc:.6g} m/s; "
        f"crown y={Y_CROWN} m; bed y={Y_SOIL} m; x=0..{LX} m; dx={dx:.6g} m ({n_cells} cells); "
        f"ranks={ranks}; averaged over t={avg_start}..{end_time} s"
    )
    paths = write_csvs(out, label, header, q, series, early)
    entry = {
        "date_utc": C.now_iso(),
        "q_m2_s": q,
        "critical_depth_m": yc,
        "inflow_speed_m_s": q / yc,
        "dx_m": dx,
        "mesh": f"{nc['NX']} x ({nc['NA']} + {nc['NB']} + {nc['NC']}) x 1",
        "n_cells": n_cells,
        "ranks": ranks,
        "end_time_s": end_time,
        "average_window_s": [avg_start, end_time],
        "tiny": tiny,
        "wall_time_total_s": round(total_wall, 1),
        "wall_time_solver_s": round(solver_wall, 1),
        "wall_time_reduction_s": round(time.perf_counter() - t_red, 1),
        "solver": {
            f"stage{k}": solver_stats(f)
            for k, f in ((1, logs / "interFoam_stage1.log"), (2, logs / "interFoam_stage2.log"))
            if f.exists()
        },
        "results": {
            "bed_pressure_max_Pa": series["p_max"],
            "x_bed_pressure_max_m": series["x_pmax"],
            "x_jet_lands_m": series["x_land"],
            "ballistic": ballistic_impact_x(q),
            "steady_upper_surface_vs_ballistic": traj,
            "first_impact_vs_ballistic": first,
            "depth_at_stations_m": {
                str(xs): float(np.interp(xs, series["x"], series["depth"])) for xs in STATIONS
            },
            "steadiness": steady,
            "volume_balance": balance,
        },
        "output_csv": {k: str(C._rel(v)) for k, v in paths.items()},
        "commands": cmds,
        "host": C.host_facts(),
    }
    top = {
        "case": "Overflow nappe of the scour set-up onto a rigid bed, interFoam laminar VOF "
        "(issue 11 item 8)",
        "tool": {
            "name": "OpenFOAM (interFoam)",
            "version": version,
            "debian_package": f"openfoam {C.debian_package_version('openfoam')}",
            "mpi": f"openmpi-bin {C.debian_package_version('openmpi-bin')}",
        },
        "reproduce": "python -m reference_cases.openfoam_overflow_nappe.run --q Q --dx-mm DX [--ranks 2]",
        "parameters": {
            "bed_y_m": Y_SOIL,
            "crown_y_m": Y_CROWN,
            "fall_m": FALL,
            "bed_length_m": LX,
            "air_above_nappe_m": TOP_MARGIN,
            "stations_m": list(STATIONS),
            "water": {"rho": RHO_W, "nu": 1e-6},
            "air": {"rho": 1, "nu": 1.48e-5},
            "sigma_N_per_m": 0.07,
            "g": G,
            "inlet": "fixedValue U = (q/y_c, 0), alpha = 1 over y_c; fixedFluxPressure p_rgh",
            "outlet": "zeroGradient U, alpha, p_rgh",
            "atmosphere": "totalPressure p_rgh p0 = 0 (hRef = top), pressureInletOutletVelocity, "
            "inletOutlet alpha 0",
            "walls": "noSlip U, fixedFluxPressure p_rgh, zeroGradient alpha",
            "turbulence": "laminar",
            "numerics": "Euler, MULES with cAlpha 1, PIMPLE 1 outer / 3 p corrections, "
            f"maxCo = maxAlphaCo = {MAX_CO}",
        },
        "environment": FOAM_ENV,
        "set_up": "docs/scour_setup.md",
    }
    if official:
        # runs of the mesh study may finish concurrently: one writer at a time
        with open(CASE_DIR / ".manifest.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            C.update_manifest(MANIFEST, label, entry, top)
            conv = mesh_comparison(DATA_DIR)
            if conv:
                C.set_manifest_section(MANIFEST, "mesh_convergence", conv)
            C.set_manifest_section(MANIFEST, "first_impact_vs_ballistic", first_impact_summary(DATA_DIR))
    else:
        (out / "manifest.json").write_text(json.dumps({**top, "runs": {label: entry}}, indent=2) + "\n")
    if not keep_fields:
        for t, d in time_dirs(work):
            if t > 0:
                shutil.rmtree(d)
    return {"label": label, "paths": paths, "work": work, "series": series, "entry": entry}


# ----------------------------------------------------------------------------- mesh study
def read_csv(path: Path) -> np.ndarray:
    return np.loadtxt(path, delimiter=",", comments="#", skiprows=2, ndmin=2)


def mesh_comparison(data_dir: Path) -> dict | None:
    """Per q: the results of every serial mesh against the finest one."""
    runs: dict = {}
    for p in sorted(Path(data_dir).glob("bed_q*_dx*mm.csv")):
        m = re.fullmatch(r"bed_q(\d+p\d+)_dx([\dp]+)mm\.csv", p.name)
        if m:
            q = float(m.group(1).replace("p", "."))
            dxmm = float(m.group(2).replace("p", "."))
            runs.setdefault(q, {})[dxmm] = p.name[len("bed_") : -len(".csv")]
    out = {}
    for q, meshes in sorted(runs.items()):
        if len(meshes) < 2:
            continue
        fine = min(meshes)
        ref = _load(data_dir, meshes[fine])
        pairs = {}
        for dxmm, label in sorted(meshes.items()):
            if dxmm == fine:
                continue
            s = _load(data_dir, label)
            pairs[f"dx{dxmm:g}mm_vs_dx{fine:g}mm"] = _compare(s, ref)
        out[f"q{q:.2f}"] = {"finest_dx_mm": fine, "pairs": pairs}
    return out or None


def first_impact_summary(data_dir: Path) -> dict:
    """Per run: the free jet of the first impact against the ballistic jet, from the early
    CSVs, before the jet lands (t < sqrt(2 fall / g)) and at least two cells behind its
    leading edge (x <= u_c t - 2 dx), where the blunt head no longer matters."""
    out = {}
    land = math.sqrt(2.0 * FALL / G)
    for p in sorted(Path(data_dir).glob("early_q*_dx*mm.csv")):
        m = re.fullmatch(r"early_q(\d+p\d+)_dx([\dp]+)mm\.csv", p.name)
        if not m:
            continue
        q = float(m.group(1).replace("p", "."))
        dx = float(m.group(2).replace("p", ".")) / 1000.0
        e = read_csv(p)
        uc = q / critical_depth(q)
        sel = e[(e[:, 0] < land) & (e[:, 1] <= uc * e[:, 0] - 2.0 * dx)]
        if len(sel) == 0:
            continue
        up, lo = ballistic_surfaces(sel[:, 1], q)
        out[p.stem[len("early_") :]] = {
            "points": int(len(sel)),
            "upper_max_abs_dev_mm": round(1000 * float(np.max(np.abs(sel[:, 2] - up))), 2),
            "upper_rms_dev_mm": round(1000 * float(np.sqrt(np.mean((sel[:, 2] - up) ** 2))), 2),
            "lower_max_abs_dev_mm": round(1000 * float(np.max(np.abs(sel[:, 3] - lo))), 2),
            "lower_rms_dev_mm": round(1000 * float(np.sqrt(np.mean((sel[:, 3] - lo) ** 2))), 2),
        }
    return out


def _load(data_dir: Path, label: str) -> dict:
    return {
        "bed": read_csv(data_dir / f"bed_{label}.csv"),
        "nappe": read_csv(data_dir / f"nappe_{label}.csv"),
        "vel": read_csv(data_dir / f"velocity_{label}.csv"),
    }


def _compare(s: dict, ref: dict) -> dict:
    xb = ref["bed"][:, 0]
    p_s = np.interp(xb, s["bed"][:, 0], s["bed"][:, 1])
    d_s = np.interp(xb, s["bed"][:, 0], s["bed"][:, 2])
    pmax_ref = ref["bed"][:, 1].max()
    res = {
        "bed_pressure_max_Pa": [float(s["bed"][:, 1].max()), float(pmax_ref)],
        "x_bed_pressure_max_m": [
            float(s["bed"][np.argmax(s["bed"][:, 1]), 0]),
            float(xb[np.argmax(ref["bed"][:, 1])]),
        ],
        "bed_pressure_rms_diff_over_max": float(np.sqrt(np.mean((p_s - ref["bed"][:, 1]) ** 2)) / pmax_ref),
        "depth_max_abs_diff_m": float(np.max(np.abs(d_s - ref["bed"][:, 2]))),
    }
    # nappe surfaces on the common x range of the free jet
    if len(s["nappe"]) and len(ref["nappe"]):
        lo_x = max(s["nappe"][0, 0], ref["nappe"][0, 0])
        hi_x = min(s["nappe"][-1, 0], ref["nappe"][-1, 0])
        xx = ref["nappe"][(ref["nappe"][:, 0] >= lo_x) & (ref["nappe"][:, 0] <= hi_x), 0]
        if len(xx):
            for k, name in ((1, "upper"), (2, "lower")):
                a = np.interp(xx, s["nappe"][:, 0], s["nappe"][:, k])
                b = np.interp(xx, ref["nappe"][:, 0], ref["nappe"][:, k])
                res[f"nappe_{name}_max_abs_diff_m"] = float(np.max(np.abs(a - b)))
    # velocity profiles: water part (alpha_mean > 0.5) of each station
    diffs = []
    for xs in np.unique(ref["vel"][:, 0]):
        r = ref["vel"][(ref["vel"][:, 0] == xs) & (ref["vel"][:, 2] > 0.5)]
        c = s["vel"][s["vel"][:, 0] == xs]
        if len(r) and len(c):
            u = np.interp(r[:, 1], c[:, 1], c[:, 3])
            diffs.append(np.sqrt(np.mean((u - r[:, 3]) ** 2)) / np.max(np.abs(r[:, 3])))
    if diffs:
        res["velocity_rms_diff_over_max"] = [round(float(d), 4) for d in diffs]
    return res


def summary_table(manifest: Path = MANIFEST) -> str:
    """Markdown table of the official runs in manifest.json (for the README)."""
    runs = json.loads(Path(manifest).read_text())["runs"]
    head = (
        "| q | dx [mm] | cells | steps | wall [s] | outflow/q | area drift | balance resid. | "
        "p_bed max [Pa] | x(p max) [m] | depth 0.10 / 0.15 / 0.20 m [mm] | front - u_c t [mm] | "
        "lowest - free fall [mm] |"
    )
    rows = [head, "|" + "---|" * (head.count("|") - 1)]
    for e in sorted(runs.values(), key=lambda e: (e["q_m2_s"], -e["dx_m"])):
        r = e["results"]
        st, vb, fi = r["steadiness"], r["volume_balance"], r["first_impact_vs_ballistic"]
        depths = " / ".join(f"{1000 * v:.1f}" for v in r["depth_at_stations_m"].values())
        steps = sum(s["time_steps"] for s in e["solver"].values())
        rows.append(
            f"| {e['q_m2_s']} | {1000 * e['dx_m']:.3g} | {e['n_cells']} | {steps} | "
            f"{e['wall_time_total_s']} | "
            f"{st['outflow_over_q']:.4f} | {100 * st['water_area_rel_change']:.2f} % | "
            f"{100 * vb['residual_over_inflow_volume']:.3f} % | {r['bed_pressure_max_Pa']:.0f} | "
            f"{r['x_bed_pressure_max_m']:.4f} | {depths} | {1000 * fi['front_minus_uc_t_max_abs_m']:.2f} | "
            f"{1000 * fi['lowest_minus_free_fall_max_abs_m']:.2f} |"
        )
    return "\n".join(rows)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--q", type=float, default=0.06, help="unit discharge [m2/s]")
    p.add_argument("--dx-mm", type=float, default=2.5, help="cell size [mm]")
    p.add_argument("--ranks", type=int, default=1, choices=[1, 2])
    p.add_argument("--tiny", action="store_true", help="5 mm cells to t = 0.6 s (seconds)")
    p.add_argument("--out", type=Path, default=None)
    p.add_argument("--end-time", type=float, default=None)
    p.add_argument("--avg-start", type=float, default=None)
    p.add_argument("--nice", type=int, default=0, help="raise the niceness of the tool runs")
    p.add_argument("--drop-fields", action="store_true", help="delete the time folders after the reduction")
    p.add_argument(
        "--summary", action="store_true", help="print the Markdown table of manifest.json and exit"
    )
    a = p.parse_args(argv)
    if a.summary:
        print(summary_table())
        return 0
    if a.nice:
        os.nice(a.nice)
    res = run_case(
        a.q, a.dx_mm, a.ranks, a.tiny, a.out, a.end_time, a.avg_start, keep_fields=not a.drop_fields
    )
    e = res["entry"]
    steps = sum(s["time_steps"] for s in e["solver"].values())
    print(f"{res['label']}: {e['n_cells']} cells, {steps} steps, wall {e['wall_time_total_s']} s")
    print(json.dumps(e["results"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
