"""The scour set-up's overflow nappe onto a rigid, non-erodible bed, SPH against OpenFOAM (issue 11 item 8).

    python -m verification.overflow_nappe_rigid_bed                 # q = 0.06 and 0.11 at 5 mm, 3 s each
    python -m verification.overflow_nappe_rigid_bed run 0.11 --dx 0.0025
    python -m verification.overflow_nappe_rigid_bed report          # tables and figure from the saved runs
    scoursph verify overflow_nappe_rigid_bed

The flow of the scour scene before the soil moves, so that errors of the inflow and of the impact
flow can be told apart from those of the soil model. The SPH scene is solver/scenes/scour_dry.toml
with q, dx and the end time set, and the soil replaced by a rigid bed: the sand block is removed and
the caisson, the bed (the unscoured soil surface z = 0.095 m, 0 <= x <= 0.25 m) and the end wall
become one polygon body (free-slip mirror images and the leak guard, solver/physics/bodies.py; no new
physics). The inlet starts from an empty flume (prefill_time = 0), as the OpenFOAM run does, so the
two clocks agree. The reference is reference_cases/openfoam_overflow_nappe/ (interFoam, laminar VOF,
5 / 3.33 / 2.5 mm meshes, 3 s, averages over 2-3 s; its README sec. 4). SPH runs the same 3 s and
averages over the same window (it is cheap: water only, no soil P-wave time step).

How each quantity is measured, the OpenFOAM rule applied to SPH (reference_cases/openfoam_overflow_nappe/
run.py, reduce_fields / reduce_early), on the cells of the OpenFOAM 2.5 mm mesh (centres x = 1.25,
3.75, ... mm, y = 0.09625, 0.09875, ... m):
  * water fraction phi (the VOF alpha): phi(r) = sum_j (m_j / rho_j) W(r - r_j, h) over the water
    particles and their mirror images across the bed line (x >= 0) and the caisson face (y < crown),
    the images the solver itself uses (bodies.py), so phi -> 1 at a wetted wall instead of 1/2.
    phi = 1/2 lies half a spacing outside the last particle row: the volume-equivalent surface, as
    alpha = 1/2 of a VOF. Time average over 2-3 s from samples every SAMPLE_EVERY.
  * nappe surfaces: per column the topmost phi_mean = 1/2 crossing (air above: upper surface), and a
    lower surface if the next crossing below it has air below (run.py alpha_crossings, the same code).
  * bed pressure: p_bed(x) = sum_j W_j (p_j + rho0 g (y_j - y_bed)) / sum_j W_j over the particles
    within 2h of the bed point: each particle's gauge pressure extrapolated hydrostatically to the bed
    and Shepard-weighted, which is what a symmetric image with a hydrostatically corrected pressure
    gives at the wall (Adami et al. 2012, eq. 27 without the acceleration term: the bed-normal
    acceleration of the near-bed water is a small fraction of g, and the lever is ~h). Time average.
  * depth: sum over the column of phi_mean dy (run.py: sum alpha dy).
  * impingement point: x of the largest time-averaged bed pressure (run.py: x_bed_pressure_max; the
    nappe is drowned in both codes' averages, so no free lower surface lands: the pressure peak is
    where the jet's momentum reaches the bed).
  * velocity profiles: at the cell column nearest x = 0.10, 0.15, 0.20 m, the phi-weighted time average
    of the Shepard-interpolated velocity sum_t phi u / sum_t phi (the VOF UMean is alpha ~ 1 there);
    where SPH has no water (phi_mean < 1e-3) u = 0, so a surface that is too low is counted as an error.
  * first impact (t = 0.005-0.045 s, instantaneous): the leading edge (largest x of a cell above the
    crown with phi > 1/2, plus half a cell) and the lowest lower surface (run.py reduce_early).
The comparisons are run.py's own mesh-study metrics (`_compare`), so each SPH number reads against the
OpenFOAM mesh study's number of the same name.

Tolerances (per q, per metric; stated, not fitted): the ASME V&V 20 idea that SPH and the reference
agree when their difference is within the numerical uncertainty of the two, estimated from what was
measured:
    tol = |OF 5 mm - OF 2.5 mm|         what a 5 mm discretisation costs a finite-volume solver here
        + |OF 3.33 mm - OF 2.5 mm|      the reference's own remaining mesh error
        + |SPH 5 mm - SPH 2.5 mm|       SPH's resolution error (only where the 2.5 mm SPH run exists)
(the OpenFOAM terms from its CSVs, the same numbers as its manifest.json mesh_convergence; the SPH term
from the committed 2.5 mm run's CSVs, run through the same metric). The same tolerance judges the 5 mm
and the 2.5 mm SPH runs. Where SPH's resolution spread is large (the bed pressure), the tolerance is
large with it: a pass there means "within SPH's own resolution uncertainty", which the results README
states per metric. The velocity profile at x = 0.20 m is reported but not
judged: the flow there is near critical and the outlet's boundary condition (zero gradient in
OpenFOAM, a deletion zone in SPH) acts on it (reference_cases/README.md sec. 4, written before these
runs: "compare SPH first at x <= 0.15 m"). Known model differences, not tolerated away: the bed is
free slip in SPH (the seed's images) and no slip in OpenFOAM; SPH has no air.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from reference_cases.openfoam_overflow_nappe.run import _compare, alpha_crossings, ballistic_surfaces
from solver.kernels import kernel_values
from solver.scene import SCENES_DIR, parse_scene

from .common import RESULTS, CaseResult, Check, Stopwatch, load_1min, reference_case_dir, save_figure

REF = reference_case_dir("openfoam_overflow_nappe")
OUT = RESULTS / "overflow_nappe"
Q_CASES = (0.06, 0.11)
DX = 0.005  # the seed's spacing
DX_FINE = 0.0025
END_TIME = 3.0  # s, as the OpenFOAM runs
WINDOW = (2.0, 3.0)  # s, the OpenFOAM averaging window
SAMPLE_EVERY = 0.01  # s between samples of the average (OpenFOAM's history is sampled as often)
EARLY_TIMES = tuple(round(0.005 * k, 3) for k in range(1, 10))  # the OpenFOAM first-impact fields
G = 9.81
RHO0 = 1000.0
Y_BED = 0.095
Y_CROWN = 0.105
FALL = Y_CROWN - Y_BED
CELL = 0.0025  # the OpenFOAM 2.5 mm mesh: the cells SPH is sampled on
STATIONS = (0.10, 0.15, 0.20)
JUDGED_STATIONS = (0.10, 0.15)
# the judged reach of the bed: x <= 0.15 m, upstream of the outlets' reach (~y_c, reference_cases/README.md
# sec. 4: SPH deletes water over the end wall, a free overfall; OpenFOAM has a zero-gradient outlet)
X_JUDGED = 0.15
X_CORNER = 2 * 1.3 * DX  # the kernel reach 2h (h = 1.3 dx) from the caisson face at 5 mm
# resolution = particles per 0.1 m (the bed depth is 0.095 m): 20 at 5 mm, 40 at 2.5 mm
DEFAULT_RESOLUTION = 20
STUDY_RESOLUTIONS = (20, 40)
NIGHTLY_STUDY_RESOLUTIONS = ()  # the 2.5 mm runs (~10 CPU min each) are committed, not rerun nightly
NIGHTLY_NOTE = "5 mm, q = 0.06 and 0.11 to 3 s; the SPH 2.5 mm spread from the committed runs"
# metric -> why it fails (measured, docs/scour_setup.md sec. 6); the nightly report lists these as known
_CORNER = (
    "5 mm: the bed-pressure spike within 2h of the caisson-bed corner (a concave body vertex has no "
    "corner image)"
)
_LANDING = (
    "the SPH jet loads the bed near its free-flight landing (x ~ 0.036 m at 2.5 mm), OpenFOAM's 35 mm "
    "further on, over a low-pressure eddy SPH does not form (results README, item 5)"
)
_OUTLET = (
    "the scour scene's outlet (deletion over the end wall) is a free overfall whose drawdown reaches "
    "x < 0.15 m at q = 0.11; OpenFOAM's zero-gradient outlet is not (with the outlet at 0.50 m SPH is "
    "within 2.2 mm / 5.1 mm / 6.0 %: results README, item 1)"
)
KNOWN_FAILURES: dict[str, str] = {
    "q=0.06 bed_pressure_max_rel": _CORNER,
    "q=0.06 x_bed_pressure_max_m": _CORNER,
    "q=0.06 x_bed_pressure_max_beyond_corner_m": _LANDING,
    "q=0.06 bed_pressure_rms_diff_over_max": _LANDING,
    "q=0.11 bed_pressure_max_rel": _CORNER,
    "q=0.11 x_bed_pressure_max_m": _CORNER,
    "q=0.11 u_rms_diff_over_max_x0.10": _LANDING + "; 6.17 % against 6.11 %",
    "q=0.11 depth_max_abs_diff_m": _OUTLET,
    "q=0.11 nappe_upper_max_abs_diff_m": _OUTLET,
    "q=0.11 u_rms_diff_over_max_x0.15": _OUTLET,
}


BEDS = ("body", "box_free_slip", "box_no_slip", "body_long")
LONG_OUTLET = 0.50  # m: bed = "body_long" moves the end wall and the outlet here


def label(q, dx, bed="body"):
    tail = "" if bed == "body" else f"_{bed}"
    return f"q{q:.2f}".replace(".", "p") + f"_dx{dx * 1000:g}mm".replace(".", "p") + tail


def scene(q, dx=DX, end_time=END_TIME, bed="body"):
    """solver/scenes/scour_dry.toml with the sand replaced by a rigid bed, q and dx set, and the flume
    empty at t = 0. bed = "body" (the case): caisson, bed at the soil surface and end wall as one
    polygon body (free-slip images, as the scour scene's bodies). Diagnostics: "box_free_slip" /
    "box_no_slip", the bed as the box's floor (y_min = 0.095 m) with that wall condition and the
    caisson as a body above it (isolates the body's concave corner, and the slip condition);
    "body_long", the bed, end wall and outlet moved from 0.25 m to LONG_OUTLET (isolates the outlet)."""
    path = SCENES_DIR / "scour_dry.toml"
    raw = tomllib.loads(path.read_text())
    raw["scene"].update(
        name=f"overflow_nappe_rigid_bed_{label(q, dx, bed)}", spacing=float(dx), end_time=end_time
    )
    raw["scene"]["description"] = "scour_dry's overflow nappe onto a rigid bed (issue 11 item 8)"
    raw["blocks"] = []
    raw["materials"].pop("sand")
    x_end = raw["bodies"][1]["vertices"][1][0]  # the end wall's outer face (0.28 m)
    if bed == "body_long":
        shift = LONG_OUTLET - 0.25
        x_end += shift
        raw["domain"]["max"][0] += shift
        raw["outlets"][0]["min"][0] += shift
        raw["outlets"][0]["max"][0] += shift
    if bed in ("body", "body_long"):
        outline = [[-0.05, 0.0], [x_end, 0.0], [x_end, Y_BED], [0.0, Y_BED], [0.0, Y_CROWN], [-0.05, Y_CROWN]]
    elif bed in BEDS:
        raw["domain"]["min"][1] = Y_BED
        raw["walls"]["y_min"] = bed[len("box_") :]
        outline = [[-0.05, Y_BED], [0.0, Y_BED], [0.0, Y_CROWN], [-0.05, Y_CROWN]]
    else:
        raise ValueError(f"bed must be one of {BEDS}, not {bed!r}")
    raw["bodies"] = [{"name": "caisson, rigid bed and end wall", "vertices": outline}]
    raw["inlets"][0].update(discharge=float(q), prefill_time=0.0)
    raw["output"]["times"] = [0.0, end_time]
    return parse_scene(raw, path)


class Grid:
    """The OpenFOAM 2.5 mm cells above the bed, and a scatter of kernel sums onto them."""

    def __init__(self, top, h):
        self.x = CELL * (np.arange(round(0.25 / CELL)) + 0.5)
        self.y = Y_BED + CELL * (np.arange(math.ceil((top - Y_BED) / CELL)) + 0.5)
        self.h = h
        reach = int(math.ceil(2.0 * h / CELL)) + 1
        o = np.arange(-reach, reach + 1)
        self.offsets = np.array(np.meshgrid(o, o, indexing="ij")).reshape(2, -1).T  # (K, 2)

    def scatter(self, x, values, y0=None):
        """sum_j values_j W(cell - x_j) per cell, for each column of `values` (N, m) -> (nx, ny, m);
        y0 shifts the grid's rows (the bed row of the pressure)."""
        ys = self.y if y0 is None else y0
        nx, ny = len(self.x), len(ys)
        i0 = np.floor((x[:, 0] - self.x[0]) / CELL + 0.5).astype(int)
        j0 = np.floor((x[:, 1] - ys[0]) / CELL + 0.5).astype(int)
        ii = i0[:, None] + self.offsets[None, :, 0]
        jj = j0[:, None] + self.offsets[None, :, 1]
        ok = (ii >= 0) & (ii < nx) & (jj >= 0) & (jj < ny)
        k = np.nonzero(ok)
        ci, cj = ii[k], jj[k]
        r = np.hypot(self.x[ci] - x[k[0], 0], ys[cj] - x[k[0], 1])
        w = kernel_values(r, self.h, 2)
        flat = ci * ny + cj
        out = np.zeros((nx * ny, values.shape[1]))
        for m in range(values.shape[1]):
            out[:, m] = np.bincount(flat, weights=w * values[k[0], m], minlength=nx * ny)
        return out.reshape(nx, ny, -1)


def with_images(x, v, h):
    """The water and its mirror images across the bed line (x >= 0) and the caisson face (y < crown),
    within 2h: the images bodies.py gives the water (free slip: normal velocity reversed)."""
    bed = (x[:, 0] >= 0.0) & (x[:, 1] < Y_BED + 2 * h)
    face = (x[:, 0] < 2 * h) & (x[:, 1] < Y_CROWN) & (x[:, 0] >= 0.0)
    xb, vb = x[bed].copy(), v[bed].copy()
    xb[:, 1] = 2 * Y_BED - xb[:, 1]
    vb[:, 1] *= -1
    xf, vf = x[face].copy(), v[face].copy()
    xf[:, 0] *= -1
    vf[:, 0] *= -1
    return np.vstack([x, xb, xf]), np.vstack([v, vb, vf]), (bed, face)


class Sampler:
    """Instantaneous fields on the grid, and their time averages."""

    def __init__(self, grid):
        self.grid = grid
        shape = (len(grid.x), len(grid.y))
        self.n = 0
        self.phi = np.zeros(shape)
        self.phi_u = np.zeros(shape + (2,))
        self.phi_p = np.zeros(shape)
        self.p_bed = np.zeros(len(grid.x))
        self.p_bed_n = np.zeros(len(grid.x))

    def fields(self, sim):
        ps = sim.particles
        x, v = ps.owned("x"), ps.owned("v")
        vol = ps.owned("mass") / ps.owned("rho")
        xa, va, (bed, face) = with_images(x, v, sim.h)
        vola = np.concatenate([vol, vol[bed], vol[face]])
        phi = self.grid.scatter(xa, vola[:, None])[..., 0]
        p = ps.owned("p")
        s = self.grid.scatter(x, np.column_stack([vol, vol * v[:, 0], vol * v[:, 1], vol * p]))
        with np.errstate(invalid="ignore", divide="ignore"):
            u = np.where(s[..., :1] > 0, s[..., 1:] / s[..., :1], 0.0)
        self.last_p = u[..., 2]  # Shepard pressure (diagnostic map, not compared)
        return phi, u[..., :2]

    def add(self, sim):
        phi, u = self.fields(sim)
        self.phi += phi
        self.phi_u += phi[..., None] * u
        self.phi_p += phi * self.last_p
        ps = sim.particles
        x, p, vol = ps.owned("x"), ps.owned("p"), ps.owned("mass") / ps.owned("rho")
        near = x[:, 1] < Y_BED + 2 * sim.h
        vals = np.column_stack([vol[near], vol[near] * (p[near] + RHO0 * G * (x[near, 1] - Y_BED))])
        s = self.grid.scatter(x[near], vals, y0=np.array([Y_BED]))[:, 0, :]
        ok = s[:, 0] > 0
        self.p_bed[ok] += s[ok, 1] / s[ok, 0]
        self.p_bed_n[ok] += 1
        self.n += 1

    def means(self):
        phi = self.phi / self.n
        with np.errstate(invalid="ignore", divide="ignore"):
            u = np.where(self.phi[..., None] > 1e-3 * self.n, self.phi_u / self.phi[..., None], 0.0)
            p = np.where(self.p_bed_n > 0, self.p_bed / self.p_bed_n, np.nan)
        return phi, u, p


def surfaces(y, phi_col):
    """(upper, lower) of a column by run.py's rule, or None without an upper surface."""
    cr = alpha_crossings(y, np.clip(phi_col, 0.0, 1.0))
    if not cr or cr[0][1] != 1:
        return None
    lower = cr[1][0] if len(cr) > 1 and cr[1][1] == -1 else float("nan")
    return cr[0][0], lower


def reduce_average(grid, phi, u, p_bed):
    """The OpenFOAM CSVs' arrays from the SPH averages: nappe (x, upper, lower), bed (x, p, depth),
    velocity (station, y, alpha, ux, uy)."""
    nappe = []
    for i, xc in enumerate(grid.x):
        s = surfaces(grid.y, phi[i])
        if s is not None:
            nappe.append((xc, *s))
    depth = np.clip(phi, 0.0, 1.0).sum(axis=1) * CELL
    bed = np.column_stack([grid.x, p_bed, depth])
    vel = []
    for xs in STATIONS:
        i = int(np.argmin(np.abs(grid.x - xs)))
        vel.append(np.column_stack([np.full(len(grid.y), xs), grid.y, phi[i], u[i, :, 0], u[i, :, 1]]))
    return {"nappe": np.array(nappe).reshape(-1, 3), "bed": bed, "vel": np.vstack(vel)}


def reduce_early(grid, t, phi):
    """Instantaneous jet surfaces per column up to the leading edge, the edge and the lowest water."""
    wet = (phi > 0.5) & (grid.y[None, :] > Y_CROWN)
    cols = np.nonzero(wet.any(axis=1))[0]
    x_front = float(grid.x[cols].max() + 0.5 * CELL) if len(cols) else 0.0
    rows, lows = [], []
    for i, xc in enumerate(grid.x):
        if xc > x_front:
            break
        cr = alpha_crossings(grid.y, np.clip(phi[i], 0, 1))
        if len(cr) >= 2 and cr[0][1] == 1 and cr[1][1] == -1:
            rows.append((t, xc, cr[0][0], cr[1][0]))
            lows.append(cr[1][0])
    return rows, (t, x_front, min(lows) if lows else float("nan"))


def simulate(q, dx=DX, end_time=END_TIME, window=WINDOW, out=OUT, log=print, bed="body"):
    """One SPH run: early surfaces, the 2-3 s averages, outflow and stored water; saved as CSVs
    (OpenFOAM's formats, file names with _sph) and a JSON summary in `out`."""
    from solver.physics.bodies import BodyGuard
    from solver.physics.outlet import Outlets
    from solver.simulation import Simulation

    sc = scene(q, dx, end_time, bed)
    lab = label(q, dx, bed)
    sim = Simulation(sc)
    sim.step()  # compile
    clock = Stopwatch()
    top = Y_CROWN + (q * q / G) ** (1 / 3) + 0.04
    grid = Grid(top, sim.h)
    sampler = Sampler(grid)
    outlets = sim.plan.term(Outlets)
    early_rows, heads, history = [], [], []
    avg_times = (
        np.round(np.arange(window[0], window[1] + 1e-9, SAMPLE_EVERY), 6) if end_time >= window[1] else []
    )
    times = sorted(set(EARLY_TIMES) | set(np.round(np.arange(0.1, end_time + 1e-9, 0.1), 6)) | set(avg_times))
    for t in times:
        if t > end_time + 1e-12:
            break
        sim.advance_to(t)
        sim.current_state()
        if t in EARLY_TIMES:
            phi, _ = sampler.fields(sim)
            r, head = reduce_early(grid, t, phi)
            early_rows += r
            heads.append(head)
        if t in avg_times:
            sampler.add(sim)
        ps = sim.particles
        area = float(np.sum((ps.owned("mass") / ps.owned("rho"))[ps.owned("inlet_buffer") < 0]))
        history.append((t, float(outlets.removed_volume().sum()), area))
        if abs(t * 10 - round(t * 10)) < 1e-9:
            w, c = clock.read()
            log(f"  {lab} t = {t:.2f} s, {sim.step_count} steps, {ps.n_owned} particles, {c:.0f} CPU s")
    wall, cpu = clock.read()
    res = {
        "q": q,
        "dx": dx,
        "bed": bed,
        "end_time": end_time,
        "steps": sim.step_count,
        "particles_end": int(sim.particles.n_owned),
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        "load_1min": round(load_1min(), 2),
        "numba_threads": os.environ.get("NUMBA_NUM_THREADS", "default"),
        "body_leaks": int(sim.plan.term(BodyGuard).leaks),
        "wall_reflections": int(sim.wall_reflections),
        "date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    }
    hist = np.array(history)
    if sampler.n:
        phi, u, p = sampler.means()
        avg = reduce_average(grid, phi, u, p)
        maps = (
            Path(__file__).resolve().parent.parent / "runs" / "overflow_nappe_maps"
        )  # diagnostics, not committed
        maps.mkdir(parents=True, exist_ok=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            p_map = np.where(sampler.phi > 0, sampler.phi_p / sampler.phi, np.nan)
        np.savez_compressed(maps / f"{lab}.npz", x=grid.x, y=grid.y, phi=phi, u=u, p=p_map)
        ps = sim.particles
        np.savez_compressed(maps / f"{lab}_final.npz", x=ps.owned("x"), v=ps.owned("v"), p=ps.owned("p"))
        sel = (hist[:, 0] >= window[0] - 1e-9) & (hist[:, 0] <= window[1] + 1e-9)
        h = hist[sel]
        res["average_window_s"] = list(window)
        res["samples"] = sampler.n
        res["outflow_over_q"] = float((h[-1, 1] - h[0, 1]) / (h[-1, 0] - h[0, 0]) / q)
        half = len(h) // 2
        res["water_area_halves_m2"] = [float(h[:half, 2].mean()), float(h[half:, 2].mean())]
        save_run(out, lab, avg, early_rows, heads, hist)
    else:
        save_run(out, lab, None, early_rows, heads, hist)
    (Path(out) / f"run_{lab}_sph.json").write_text(json.dumps(res, indent=1) + "\n")
    return res


HEADER = (
    "# ScourSPH {what}; q={q} m2/s; dx={dx} m; rules: verification/overflow_nappe_rigid_bed.py docstring\n"
)


def save_run(out, lab, avg, early_rows, heads, hist):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    q, dx = lab.split("_dx")
    hdr = HEADER.format(what="{}", q=q[1:].replace("p", "."), dx=dx)

    def write(name, what, cols, arr, fmt="%.6g"):
        np.savetxt(
            out / f"{name}_{lab}_sph.csv",
            np.asarray(arr).reshape(-1, len(cols)),
            delimiter=",",
            header=hdr.format(what)[2:] + ",".join(cols),
            comments="# ",
            fmt=fmt,
        )

    if avg is not None:
        write("nappe", "time-averaged phi = 1/2 surfaces", ["x_m", "upper_m", "lower_m"], avg["nappe"])
        write("bed", "time-averaged bed pressure and depth", ["x_m", "p_bed_Pa", "depth_m"], avg["bed"])
        write(
            "velocity",
            "time-averaged profiles",
            ["station_x_m", "y_m", "alpha_mean", "ux_m_s", "uy_m_s"],
            avg["vel"],
        )
    write("early", "first impact surfaces", ["t_s", "x_m", "upper_m", "lower_m"], early_rows)
    write("head", "first impact leading edge and lowest water", ["t_s", "front_x_m", "lowest_y_m"], heads)
    write("history", "outlet volume and stored water", ["t_s", "outlet_volume_m2", "water_area_m2"], hist)


def read(path):
    """A CSV with its header lines: the last comment line (SPH) or the first non-comment line (OpenFOAM)."""
    return np.loadtxt(
        path, delimiter=",", comments="#", skiprows=0 if "_sph" in Path(path).name else 2, ndmin=2
    )


def load_sph(q, dx, out=OUT, bed="body"):
    lab = label(q, dx, bed)
    try:
        return {k: read(Path(out) / f"{k}_{lab}_sph.csv") for k in ("nappe", "bed", "velocity", "head")}
    except OSError:
        return None


def load_of(q, dxmm):
    lab = f"q{q:.2f}".replace(".", "p") + f"_dx{dxmm}mm"
    return {k: read(REF / "data" / f"{k}_{lab}.csv") for k in ("nappe", "bed", "velocity", "early")}


def _upto(d, x_max):
    """The bed and nappe rows at x <= x_max (velocity profiles untouched)."""
    if x_max is None:
        return d
    return {**d, "bed": d["bed"][d["bed"][:, 0] <= x_max], "nappe": d["nappe"][d["nappe"][:, 0] <= x_max]}


def metrics(s, ref, x_max=X_JUDGED):
    """run.py's mesh-study metrics of s against ref (both with keys bed, nappe, velocity), as scalars,
    over 0 <= x <= x_max; plus the impingement point away from the caisson's corner (x >= X_CORNER)."""
    s, ref = _upto(s, x_max), _upto(ref, x_max)
    c = _compare(
        {"bed": s["bed"], "nappe": s["nappe"], "vel": s["velocity"]},
        {"bed": ref["bed"], "nappe": ref["nappe"], "vel": ref["velocity"]},
    )
    pm = c["bed_pressure_max_Pa"]
    out = {
        "bed_pressure_max_rel": (pm[0] - pm[1]) / pm[1],
        "x_bed_pressure_max_m": c["x_bed_pressure_max_m"][0] - c["x_bed_pressure_max_m"][1],
    }
    peaks = []
    for d in (s, ref):
        b = d["bed"][d["bed"][:, 0] >= X_CORNER]
        peaks.append(b[np.nanargmax(b[:, 1])])
    out["x_bed_pressure_max_beyond_corner_m"] = float(peaks[0][0] - peaks[1][0])
    out["bed_pressure_max_beyond_corner_rel"] = float((peaks[0][1] - peaks[1][1]) / peaks[1][1])
    out.update(
        bed_pressure_rms_diff_over_max=c["bed_pressure_rms_diff_over_max"],
        depth_max_abs_diff_m=c["depth_max_abs_diff_m"],
        nappe_upper_max_abs_diff_m=c.get("nappe_upper_max_abs_diff_m", float("nan")),
    )
    for xs, v in zip(STATIONS, c.get("velocity_rms_diff_over_max", [float("nan")] * 3)):
        out[f"u_rms_diff_over_max_x{xs:.2f}"] = v
    out["free_lower_surface_columns"] = int(np.isfinite(s["nappe"][:, 2]).sum()) - int(
        np.isfinite(ref["nappe"][:, 2]).sum()
    )
    return out


def early_metrics(head, ref_head, t_max=0.045):
    """Leading edge and lowest water before landing, against a reference (t, front, lowest) series."""
    out = {}
    for k, name in ((1, "front_x"), (2, "lowest_y")):
        d = []
        for t, *vals in head:
            if t < t_max:
                r = ref_head[np.isclose(ref_head[:, 0], t)]
                if len(r) and np.isfinite(vals[k - 1]) and np.isfinite(r[0, k]):
                    d.append(vals[k - 1] - r[0, k])
        out[f"{name}_max_abs_diff_m"] = float(np.max(np.abs(d))) if d else float("nan")
    return out


def of_head(q):
    """The OpenFOAM first impact (t, front, lowest) per mesh, from its manifest."""
    m = json.loads((REF / "manifest.json").read_text())["runs"]
    out = {}
    for dxmm in ("5", "3p33333", "2p5"):
        f = m[f"q{q:.2f}".replace(".", "p") + f"_dx{dxmm}mm"]["results"]["first_impact_vs_ballistic"]
        out[dxmm] = np.column_stack([f["t_s"], f["front_x_m"], f["lowest_y_m"]])
    return out


def ballistic_head(q, times=EARLY_TIMES):
    """The free jet's head: leading edge u_c t, lowest water crown - g t^2/2 (run.py early_check)."""
    t = np.asarray(times)
    uc = (G * q) ** (1 / 3)
    return np.column_stack([t, uc * t, Y_CROWN - 0.5 * G * t * t])


def tolerances(q, sph_fine=None, x_max=X_JUDGED, out=OUT):
    """Per metric: the OpenFOAM mesh-study spreads (5 vs 2.5, 3.33 vs 2.5) and, if given, the SPH
    5 vs 2.5 mm spread; their sum is the tolerance (module docstring)."""
    ref = load_of(q, "2p5")
    parts = {
        "OF 5 vs 2.5 mm": metrics(load_of(q, "5"), ref, x_max),
        "OF 3.33 vs 2.5 mm": metrics(load_of(q, "3p33333"), ref, x_max),
    }
    heads = of_head(q)
    parts["OF 5 vs 2.5 mm"].update(early_metrics(heads["5"], heads["2p5"]))
    parts["OF 3.33 vs 2.5 mm"].update(early_metrics(heads["3p33333"], heads["2p5"]))
    if sph_fine is not None:
        coarse = load_sph(q, DX, out) or load_sph(q, DX, OUT)
        if coarse is not None:
            parts["SPH 5 vs 2.5 mm"] = metrics(coarse, sph_fine, x_max)
            parts["SPH 5 vs 2.5 mm"].update(early_metrics(coarse["head"], sph_fine["head"]))
    tol = {}
    for key in parts["OF 5 vs 2.5 mm"]:
        tol[key] = sum(abs(p[key]) for p in parts.values() if np.isfinite(p.get(key, np.nan)))
    return tol, parts


def compare(q, dx=DX, out=OUT, bed="body"):
    """Rows (metric, SPH - OF 2.5 mm, tolerance, verdict, parts) for one saved SPH run: the judged
    metrics over x <= X_JUDGED, then the same over the whole bed (not judged: the outlets differ)."""
    s = load_sph(q, dx, out, bed)
    if s is None:
        raise FileNotFoundError(f"no saved SPH run {label(q, dx, bed)} in {out}")
    # the SPH 2.5 mm run (from `out`, else the committed one): its spread from 5 mm enters the tolerance,
    # the same tolerance for both resolutions
    fine = load_sph(q, DX_FINE, out) or load_sph(q, DX_FINE, OUT)
    ref = load_of(q, "2p5")
    rows = []
    for x_max, judged_range in ((X_JUDGED, True), (None, False)):
        tol, parts = tolerances(q, fine, x_max, out)
        m = metrics(s, ref, x_max)
        if judged_range:
            m.update(early_metrics(s["head"], of_head(q)["2p5"]))
        else:
            m = {k: v for k, v in m.items() if not k.startswith("u_rms")}
        for key, val in m.items():
            judged = judged_range and not (key.startswith("u_rms") and float(key[-4:]) not in JUDGED_STATIONS)
            name = key if judged_range else f"{key} (whole bed)"
            t = tol.get(key, float("nan"))
            rows.append(
                dict(
                    metric=name,
                    sph_minus_of=val,
                    tolerance=t,
                    judged=judged,
                    passed=bool(np.isfinite(val) and abs(val) <= t) if judged else None,
                    parts={k: p.get(key) for k, p in parts.items()},
                )
            )
    return rows


def run(resolution=DEFAULT_RESOLUTION, out_dir=None, simulate_again=True):
    """`scoursph verify overflow_nappe_rigid_bed`: both q at 0.1/resolution, 3 s each (64-103 CPU s each
    at 5 mm), compared with OpenFOAM; the SPH 2.5 mm spread enters the tolerance when its run is saved
    in verification/results/overflow_nappe/. simulate_again=False reuses saved runs in the output."""
    dx = round(0.1 / resolution, 6)
    out = Path(out_dir) / "overflow_nappe_rigid_bed" if out_dir is not None else OUT
    clock = Stopwatch()
    runs, checks, notes = {}, [], []
    for q in Q_CASES:
        js = out / f"run_{label(q, dx)}_sph.json"
        again = simulate_again or not js.exists()
        runs[q] = simulate(q, dx, out=out) if again else json.loads(js.read_text())
        for r in compare(q, dx, out):
            if r["judged"]:
                source = "OF mesh spreads + SPH 5 vs 2.5 mm spread (module docstring)"
                checks.append(Check(f"q={q} {r['metric']}", r["sph_minus_of"], r["tolerance"], source))
            else:
                notes.append(f"q={q} {r['metric']} = {r['sph_minus_of']:.4g} (not judged: outlet-affected)")
    notes.append(
        "per run (CPU s / wall s): "
        + ", ".join(f"q={q}: {r['cpu_s']} / {r['wall_s']}" for q, r in runs.items())
        + "; known failures and their reasons: KNOWN_FAILURES, verification/results/overflow_nappe/README.md"
    )
    wall, cpu = clock.read()
    res = CaseResult(
        "overflow_nappe_rigid_bed",
        resolution,
        sum(r["particles_end"] for r in runs.values()),
        sum(r["steps"] for r in runs.values()),
        wall,
        {},
        checks=checks,
        notes=notes,
        cpu_time=cpu,
    )
    res.figure = figure(dx, out)
    return res


def study(resolutions=STUDY_RESOLUTIONS, out_dir=OUT):
    """Both q at each resolution (2.5 mm: about 8x the 5 mm CPU time), saved for compare() and report()."""
    rows = []
    for resolution in resolutions:
        dx = round(0.1 / resolution, 6)
        for q in Q_CASES:
            r = simulate(q, dx, out=out_dir)
            row = dict(resolution=resolution, q=q, wall_time_s=r["wall_s"], cpu_time_s=r["cpu_s"])
            row.update(steps=r["steps"], load_1min=r["load_1min"])
            rows.append(row)
    return rows


def figure(dx=DX, out=OUT):
    """SPH on the OpenFOAM curves: surfaces, bed pressure, velocity profiles, first impact; both q."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 4, figsize=(17, 7.5))
    for row, q in enumerate(Q_CASES):
        s, sf = load_sph(q, dx, out), load_sph(q, DX_FINE, out) if dx != DX_FINE else None
        ax_n, ax_p, ax_u, ax_e = axes[row]
        for dxmm, ls in (("5", ":"), ("2p5", "-")):
            of = load_of(q, dxmm)
            lab = f"OpenFOAM {dxmm.replace('p', '.')} mm"
            ax_n.plot(of["nappe"][:, 0], of["nappe"][:, 1], "k" + ls, label=lab)
            ax_p.plot(of["bed"][:, 0], of["bed"][:, 1], "k" + ls, label=lab)
            for xs in STATIONS:
                v = of["velocity"][(of["velocity"][:, 0] == xs) & (of["velocity"][:, 2] > 0.5)]
                ax_u.plot(v[:, 3], v[:, 1], ls, color="k", lw=1)
        bx = np.linspace(0, 0.06, 50)
        up, lo = ballistic_surfaces(bx, q)
        ax_n.plot(bx, up, "g--", lw=1, label="ballistic jet")
        ax_n.plot(bx, lo, "g--", lw=1)
        long = load_sph(q, dx, out, "body_long")
        if long is not None:  # the diagnostic with the outlet at 0.50 m
            nm = f"SPH {dx * 1000:g} mm, outlet at {LONG_OUTLET} m"
            ax_n.plot(long["nappe"][:, 0], long["nappe"][:, 1], "x", ms=3, color="C2", label=nm)
            ax_p.plot(long["bed"][:, 0], long["bed"][:, 1], "x", ms=3, color="C2", label=nm)
        for data, name, mk in ((s, f"SPH {dx * 1000:g} mm", "o"), (sf, "SPH 2.5 mm", "s")):
            if data is None:
                continue
            ax_n.plot(data["nappe"][:, 0], data["nappe"][:, 1], mk, ms=3, mfc="none", label=name)
            low = data["nappe"][np.isfinite(data["nappe"][:, 2])]
            if len(low):
                ax_n.plot(low[:, 0], low[:, 2], mk, ms=3, label=name + " lower surface")
            ax_p.plot(data["bed"][:, 0], data["bed"][:, 1], mk, ms=3, mfc="none", label=name)
            for xs, c in zip(STATIONS, ("C0", "C1", "C2")):
                v = data["velocity"][(data["velocity"][:, 0] == xs) & (data["velocity"][:, 2] > 0.5)]
                ax_u.plot(v[:, 3], v[:, 1], mk, ms=3, mfc="none", color=c, label=f"{name}, x = {xs:.2f} m")
            ax_e.plot(
                data["head"][:, 0],
                data["head"][:, 1],
                mk,
                mfc="none",
                ms=4,
                color="C0",
                label=name + " front",
            )
            ax_e2 = ax_e
            ax_e2.plot(
                data["head"][:, 0],
                10 * (data["head"][:, 2] - Y_CROWN) + 0.05,
                mk,
                ms=4,
                color="C3",
                label=name + " 0.05 + 10 (lowest - crown)",
            )
        heads = of_head(q)
        bh = ballistic_head(q)
        ax_e.plot(heads["2p5"][:, 0], heads["2p5"][:, 1], "k-", label="OpenFOAM 2.5 mm")
        ax_e.plot(heads["2p5"][:, 0], 10 * (heads["2p5"][:, 2] - Y_CROWN) + 0.05, "k-")
        ax_e.plot(bh[:, 0], bh[:, 1], "g--", lw=1, label="ballistic")
        ax_e.plot(bh[:, 0], 10 * (bh[:, 2] - Y_CROWN) + 0.05, "g--", lw=1)
        ax_n.axhline(Y_BED, color="0.5", lw=3)
        ax_n.set(
            xlabel="x (m)",
            ylabel="y (m)",
            title=f"q = {q}: time-averaged upper surface (2-3 s)",
            ylim=(Y_BED - 0.005, Y_CROWN + 0.13),
        )
        ax_p.set(xlabel="x (m)", ylabel="p_bed (Pa)", title="time-averaged bed pressure")
        ax_u.set(
            xlabel="u_x (m/s)", ylabel="y (m)", title="u_x at x = 0.10 / 0.15 / 0.20 m (black: OpenFOAM)"
        )
        ax_e.set(xlabel="t (s)", ylabel="m", title="first impact: front x; lowest water (scaled)")
        for ax in axes[row]:
            ax.grid(alpha=0.3)
            ax.legend(fontsize=6)
    fig.tight_layout()
    return save_figure(fig, Path(out) / f"overflow_nappe_dx{dx * 1000:g}mm.png")


def report(out=OUT):
    """verification/results/overflow_nappe/overflow_nappe.md: per q and resolution, the comparison and the
    run's cost."""
    lines = [
        "# Overflow nappe on a rigid bed: SPH against OpenFOAM (issue 11 item 8)",
        "",
        "Made by `python -m verification.overflow_nappe_rigid_bed report`; rules and tolerances in the "
        "module docstring of `verification/overflow_nappe_rigid_bed.py`.",
        "",
    ]
    for dx in (DX, DX_FINE):
        for q in Q_CASES:
            js = Path(out) / f"run_{label(q, dx)}_sph.json"
            if not js.exists():
                continue
            r = json.loads(js.read_text())
            lines += [
                f"## q = {q} m²/s, SPH dx = {dx * 1000:g} mm",
                "",
                f"{r['steps']} steps to {r['end_time']} s, {r['particles_end']} particles at the end; "
                f"{r['cpu_s']} CPU s, {r['wall_s']} s wall (stepping and sampling, NUMBA_NUM_THREADS="
                f"{r['numba_threads']}, nice 10, 1-min load {r['load_1min']} at the end); body leaks "
                f"{r['body_leaks']}, wall reflections {r['wall_reflections']}; outflow/q over the window "
                f"{r.get('outflow_over_q', float('nan')):.4f}; stored water halves "
                f"{r.get('water_area_halves_m2')}.",
                "",
                "| metric | SPH − OF 2.5 mm | tolerance | verdict | OF 5 vs 2.5 | OF 3.33 vs 2.5 "
                "| SPH 5 vs 2.5 |",
                "|---|---|---|---|---|---|---|",
            ]
            if "samples" not in r:
                lines += ["", "(short run: no time average)", ""]
                continue
            for row in compare(q, dx, out):
                v = {True: "pass", False: "**FAIL**", None: "not judged"}[row["passed"]]
                p = row["parts"]
                lines.append(
                    f"| {row['metric']} | {row['sph_minus_of']:.4g} | {row['tolerance']:.4g} | {v} | "
                    + " | ".join(
                        _fmt(p.get(k)) for k in ("OF 5 vs 2.5 mm", "OF 3.33 vs 2.5 mm", "SPH 5 vs 2.5 mm")
                    )
                    + " |"
                )
            lines.append("")
    lines += _diagnostics(out)
    path = Path(out) / "overflow_nappe.md"
    path.write_text("\n".join(lines) + "\n")
    return path


def _diagnostics(out):
    """The bed variants side by side (5 mm): SPH - OF 2.5 mm per metric."""
    lines = [
        "## Diagnostics: where the differences come from (5 mm)",
        "",
        "`python -m verification.overflow_nappe_rigid_bed run Q --bed VARIANT`: `body` is the case; "
        "`box_free_slip` / `box_no_slip` make the bed the box's floor (y_min = 0.095 m) with that wall "
        "condition and the caisson a body above it; `body_long` moves the end wall and outlet to "
        f"{LONG_OUTLET} m. "
        "SPH − OF 2.5 mm, same metrics and ranges as above:",
        "",
    ]
    found = False
    for q in Q_CASES:
        have = [b for b in BEDS if (Path(out) / f"run_{label(q, DX, b)}_sph.json").exists()]
        if len(have) < 2:
            continue
        found = True
        cols = {b: {r["metric"]: r["sph_minus_of"] for r in compare(q, DX, out, b)} for b in have}
        cost = {b: json.loads((Path(out) / f"run_{label(q, DX, b)}_sph.json").read_text()) for b in have}
        lines += [f"q = {q} m²/s:", "", "| metric | " + " | ".join(have) + " |", "|---|" + "---|" * len(have)]
        for key in cols["body"]:
            lines.append(f"| {key} | " + " | ".join(_fmt(cols[b].get(key)) for b in have) + " |")
        lines.append(
            "| CPU s / wall s / load | "
            + " | ".join(f"{cost[b]['cpu_s']} / {cost[b]['wall_s']} / {cost[b]['load_1min']}" for b in have)
            + " |"
        )
        lines.append("")
    return lines if found else []


def _fmt(v):
    return "" if v is None else f"{v:.4g}"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.overflow_nappe_rigid_bed")
    ap.add_argument("what", nargs="?", default="all", choices=("all", "run", "report"))
    ap.add_argument("q", nargs="?", type=float)
    ap.add_argument("--dx", type=float, default=DX)
    ap.add_argument("--end", type=float, default=END_TIME)
    ap.add_argument("--bed", default="body", choices=BEDS)
    a = ap.parse_args(argv)
    if a.what in ("all", "run"):
        for q in [a.q] if a.q else Q_CASES:
            print(json.dumps(simulate(q, a.dx, a.end, bed=a.bed), indent=1), flush=True)
    if a.what in ("all", "report") and a.end >= WINDOW[1]:
        print(report())
        for dx in (DX, DX_FINE):
            if all(load_sph(q, dx) is not None for q in Q_CASES):
                print(figure(dx))
    return 0


if __name__ == "__main__":
    sys.exit(main())
