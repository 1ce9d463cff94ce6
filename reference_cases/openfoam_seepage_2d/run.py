"""OpenFOAM reference of steady 2D seepage under a sheet pile (issue 10, item 5), solved
two ways, with a 1D check of the Darcy coefficient and the closed-form flow-net value.

    python -m reference_cases.openfoam_seepage_2d.run [--cells-per-T 10 20 40 80] [--tiny] [--out DIR]

Geometry (per unit depth; x along the ground, y up, datum at the base y = 0): a
homogeneous soil layer of thickness T = 0.2 m on an impermeable base, x from -L to L
(L = 3T = 0.6 m, closed impermeable sides), and a sheet pile of zero thickness at x = 0
from the ground surface y = T down to y = T - s (s = T/2 by default). The ground surface
left of the pile is held at the upstream head h_up = T + 0.10 m, right of it at
h_down = T + 0.05 m (still water 0.10 m and 0.05 m deep): H = 0.05 m. Hydraulic
conductivity k = 1e-3 m/s (medium sand), water nu = 1e-6 m2/s, g = 9.81 m/s2.

Two solvers, same mesh (one uniform block structure, square cells of T/N, the pile a
baffle between blocks that share no vertex along it):

* laplace: laplacianFoam with a steadyState ddt solves div(k grad h) = 0 for the total head
  h (field T); for steady flow of incompressible water through a rigid homogeneous layer
  this is exactly Darcy's law plus continuity. Discharge from the finite-volume boundary
  fluxes k (h_P - h_b)/(dx/2) dx over the ground-surface patches.
* porous: porousSimpleFoam with a DarcyForchheimer porosity zone over the whole layer,
  d = g/(nu k) (OpenFOAM's source S = -(mu d + rho|U|f/2) U acting on the superficial
  velocity: at steady state U = -(1/(nu d)) grad(p/rho) = -k grad h with p/rho = g h),
  f = 0; discharge = the face flux phi through the patches.

A 1D column (no pile, T tall, head drop H over T) checks the Darcy coefficient of both:
q must equal k H/T to solver tolerance. The closed-form value Q/(kH) = K(m')/(2K(m)),
m = sin(pi s/(2T)) (reference_cases/sheet_pile_discharge.py) is the third
check: it assumes an unbounded layer, L = 3T makes the truncation error ~exp(-pi L/T)
(~1e-4; measured below with L = 6T).

Reduced data (data/, CSV with a provenance header):
* discharge.csv: solver, cells per T, Q (m2/s), Q/(kH), inflow-outflow imbalance;
* head_lines.csv: head h and pore pressure u = rho g (h - y) along the base (y = 0), along a
  vertical line just downstream of the pile (x = +T/10) and along the downstream ground
  surface (exit gradient), on mesh-independent sample points, per mesh and solver;
* head_field.csv: the finest Laplace head field on a T/20 grid (initial pore pressure
  for an SPH run, full-field comparison). Near the pile tip (r^-1/2 gradient) and along
  the pile (h jumps across it) bilinear interpolation between cell centres is coarse.

`--pile-thickness w` replaces the baffle by a solid pile |x| < w/2 (a hole in the upper row of
blocks, wall patch `pile`) and writes data/pile_w<mm>mm/ with its own manifest.json and inputs/:
the reference of the SPH comparison (verification/seepage_sheet_pile.py), whose pile cannot be
thinner than 3 particles. The vertical head line is then T/10 downstream of the pile's face.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import shutil
import sys
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from reference_cases import _common as C
from reference_cases.openfoam_dam_break_2d.run import foam_version, read_internal_field
from reference_cases.sheet_pile_discharge import sheet_pile_shape_factor

CASE_DIR = Path(__file__).resolve().parent
TEMPLATE_DIR = CASE_DIR / "case"
DATA_DIR = CASE_DIR / "data"
INPUTS_DIR = CASE_DIR / "inputs"
WORK_DIR = CASE_DIR / "work"
MANIFEST = CASE_DIR / "manifest.json"
FOAM_ENV = {"WM_PROJECT_DIR": "/usr/share/openfoam"}
SOLVERS = {"laplace": "laplacianFoam", "porous": "porousSimpleFoam"}
TINY_CELLS = 10
MESHES = (10, 20, 40, 80)


@dataclass(frozen=True)
class Geometry:
    thickness: float = 0.2  # T (m)
    penetration: float = 0.1  # s (m)
    half_length: float = 0.6  # L (m), each side of the pile
    h_up: float = 0.30  # upstream head above the base (m): 0.10 m of water on the ground
    h_down: float = 0.25  # downstream head (m)
    k: float = 1e-3  # hydraulic conductivity (m/s)
    nu: float = 1e-6  # water kinematic viscosity (m2/s)
    g: float = 9.81
    rho_w: float = 1000.0
    pile_thickness: float = 0.0  # w (m): 0 = the thin pile (a baffle); > 0 a solid block |x| < w/2

    @property
    def half_pile(self) -> float:
        return 0.5 * self.pile_thickness

    @property
    def dh(self) -> float:
        return self.h_up - self.h_down

    @property
    def darcy_d(self) -> float:
        """OpenFOAM's Darcy coefficient d = 1/K_intrinsic = g/(nu k) (1/m2)."""
        return self.g / (self.nu * self.k)


# ----------------------------------------------------------------------------- mesh
def block_mesh_dict(geo: Geometry, cells_per_t: int, column: bool = False) -> str:
    """blockMeshDict of the sheet-pile layer (four blocks; the pile is a baffle because the
    two upper blocks use different vertices along it), or of the 1D column (`column`)."""
    t, s, half = geo.thickness, geo.penetration, geo.half_length
    dx = t / cells_per_t
    nx, ny_top, ny_bot = _cells(half, dx), _cells(s, dx), _cells(t - s, dx)
    if column:
        pts = [(0, 0), (4 * dx, 0), (4 * dx, t), (0, t)]
        blocks = [((0, 1, 2, 3), (4, cells_per_t))]
        patches = {
            "upstream": [(3, 2)],
            "downstream": [(0, 1)],
            "impermeable": [(1, 2), (3, 0)],
        }
    elif geo.pile_thickness > 0.0:
        # a solid pile |x| < a from the ground down to T - s: a hole in the upper row of blocks
        a, y0 = geo.half_pile, t - s
        ns, npile = _cells(half - a, dx), _cells(2 * a, dx)
        pts = [(x, y) for y in (0, y0, t) for x in (-half, -a, a, half)]
        blocks = [
            ((0, 1, 5, 4), (ns, ny_bot)),
            ((1, 2, 6, 5), (npile, ny_bot)),
            ((2, 3, 7, 6), (ns, ny_bot)),
            ((4, 5, 9, 8), (ns, ny_top)),
            ((6, 7, 11, 10), (ns, ny_top)),
        ]
        patches = {
            "upstream": [(8, 9)],
            "downstream": [(10, 11)],
            "impermeable": [(0, 1), (1, 2), (2, 3), (0, 4), (4, 8), (3, 7), (7, 11)],
            "pile": [(5, 9), (5, 6), (6, 10)],
        }
    else:
        y0 = t - s
        pts = [(-half, 0), (0, 0), (half, 0), (-half, y0), (0, y0), (half, y0), (-half, t), (0, t), (0, t)]
        pts.append((half, t))
        blocks = [
            ((0, 1, 4, 3), (nx, ny_bot)),
            ((1, 2, 5, 4), (nx, ny_bot)),
            ((3, 4, 7, 6), (nx, ny_top)),
            ((4, 5, 9, 8), (nx, ny_top)),
        ]
        patches = {
            "upstream": [(6, 7)],
            "downstream": [(8, 9)],
            "impermeable": [(0, 1), (1, 2), (0, 3), (3, 6), (2, 5), (5, 9)],
            "pile": [(4, 7), (4, 8)],
        }
    n = len(pts)
    lines = ["convertToMeters 1;", "", "vertices", "("]
    for z in (0.0, dx):
        lines += [f"    ({C.fmt(x, 12)} {C.fmt(y, 12)} {C.fmt(z, 12)})" for x, y in pts]
    lines += [");", "", "blocks", "("]
    for (a, b, c, d), (ncx, ncy) in blocks:
        verts = f"{a} {b} {c} {d} {a + n} {b + n} {c + n} {d + n}"
        lines.append(f"    hex ({verts}) soil ({ncx} {ncy} 1) simpleGrading (1 1 1)")
    lines += [");", "", "edges ();", "", "boundary", "("]
    for name, edges in patches.items():
        kind = "wall" if name in ("impermeable", "pile") else "patch"
        faces = " ".join(f"({a} {b} {b + n} {a + n})" for a, b in edges)
        lines.append(f"    {name} {{ type {kind}; faces ({faces}); }}")
    back = " ".join(f"({a} {d} {c} {b})" for (a, b, c, d), _ in blocks)
    front = " ".join(f"({a + n} {b + n} {c + n} {d + n})" for (a, b, c, d), _ in blocks)
    lines.append(f"    frontAndBack {{ type empty; faces ({back} {front}); }}")
    lines += [");", "", "mergePatchPairs ();", ""]
    head = (TEMPLATE_DIR / "laplace" / "system" / "controlDict").read_text().split("FoamFile")[0]
    foam = "FoamFile\n{\n    version     2.0;\n    format      ascii;\n    class       dictionary;\n"
    foam += "    object      blockMeshDict;\n}\n"
    return head + foam + "\n".join(lines)


def _cells(length: float, dx: float) -> int:
    n = round(length / dx)
    if abs(n * dx - length) > 1e-9 * length:
        raise ValueError(f"{length} m is not a whole number of cells of {dx} m")
    return n


def case_values(geo: Geometry, n_iter: int, residual: float) -> dict:
    return {
        "TOL": "1e-14",
        "K": C.fmt(geo.k, 12),
        "H_MEAN": C.fmt(0.5 * (geo.h_up + geo.h_down), 12),
        "H_UP": C.fmt(geo.h_up, 12),
        "H_DOWN": C.fmt(geo.h_down, 12),
        "N_ITER": n_iter,
        "RESIDUAL": C.fmt(residual),
        "NU": C.fmt(geo.nu, 12),
        "D": C.fmt(geo.darcy_d, 12),
        "P_MEAN": C.fmt(geo.g * 0.5 * (geo.h_up + geo.h_down), 12),
        "P_UP": C.fmt(geo.g * geo.h_up, 12),
        "P_DOWN": C.fmt(geo.g * geo.h_down, 12),
    }


def write_case(work: Path, solver: str, geo: Geometry, cells_per_t: int, column: bool, values: dict) -> None:
    C.copy_template(TEMPLATE_DIR / solver, work, values)
    (work / "system" / "blockMeshDict").write_text(block_mesh_dict(geo, cells_per_t, column))


# ----------------------------------------------------------------------------- reading
def read_patch_values(path: Path, patch: str) -> np.ndarray:
    """The `value` list of one patch in an ASCII boundaryField (scalar fields such as phi)."""
    text = Path(path).read_text()
    m = re.search(rf"\n\s*{patch}\s*\n\s*\{{(.*?)\n\s*\}}", text, re.S)
    if m is None:
        raise ValueError(f"{path}: no patch {patch}")
    body = m.group(1)
    u = re.search(r"value\s+uniform\s+([^;]+);", body)
    if u:
        return np.array([float(u.group(1))])
    lst = re.search(r"value\s+nonuniform\s+List<scalar>\s*(\d+)\s*\((.*?)\)\s*;", body, re.S)
    if lst is None:
        raise ValueError(f"{path}: cannot read patch {patch}")
    vals = np.array(lst.group(2).split(), float)
    assert len(vals) == int(lst.group(1))
    return vals


@dataclass
class Field2D:
    """Cell values of a uniform structured mesh as an (ny, nx) array, x and y centres."""

    xc: np.ndarray
    yc: np.ndarray
    h: np.ndarray

    @classmethod
    def from_cells(cls, centres: np.ndarray, values: np.ndarray, dx: float, holes: bool = False) -> Field2D:
        """With `holes` (a thick pile), cells missing from the grid take the value of the nearest
        cell of their row: the pile's faces are impermeable (zero normal gradient), so this is the
        zero-gradient extrapolation up to the face that `at` uses at every wall."""
        x, y = centres[:, 0], centres[:, 1]
        xs, ys = np.unique(np.round(x / dx, 6)), np.unique(np.round(y / dx, 6))
        ix = np.searchsorted(xs, np.round(x / dx, 6))
        iy = np.searchsorted(ys, np.round(y / dx, 6))
        grid = np.full((len(ys), len(xs)), np.nan)
        grid[iy, ix] = values
        if holes:
            for row in grid:
                ok = np.flatnonzero(~np.isnan(row))
                for i in np.flatnonzero(np.isnan(row)):
                    row[i] = row[ok[np.argmin(np.abs(ok - i))]]
        assert not np.isnan(grid).any(), "mesh is not a full uniform grid"
        return cls(xs * dx, ys * dx, grid)

    def at(self, x, y) -> np.ndarray:
        """Bilinear interpolation between cell centres; beyond the outer centres the value is
        extrapolated with zero normal gradient up to a wall (O(dx^2) there) or linearly."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        fx = np.interp(x.ravel(), self.xc, np.arange(len(self.xc)))
        fy = np.interp(y.ravel(), self.yc, np.arange(len(self.yc)))
        i0 = np.clip(np.floor(fx).astype(int), 0, len(self.xc) - 2)
        j0 = np.clip(np.floor(fy).astype(int), 0, len(self.yc) - 2)
        tx, ty = fx - i0, fy - j0
        h = self.h
        v = (
            h[j0, i0] * (1 - tx) * (1 - ty)
            + h[j0, i0 + 1] * tx * (1 - ty)
            + h[j0 + 1, i0] * (1 - tx) * ty
            + h[j0 + 1, i0 + 1] * tx * ty
        )
        return v.reshape(x.shape)


def discharge_laplace(f: Field2D, geo: Geometry, dx: float) -> tuple[float, float]:
    """Finite-volume boundary fluxes (per unit depth) through the ground surface: the flux
    laplacianFoam itself uses at a fixedValue face, k (h_P - h_b)/(dx/2) dx."""
    top = f.h[-1]
    left, right = f.xc < -geo.half_pile, f.xc > geo.half_pile  # the pile's own columns are not ground
    q_in = float(np.sum(geo.k * (geo.h_up - top[left]) / (0.5 * dx) * dx))
    q_out = float(np.sum(geo.k * (top[right] - geo.h_down) / (0.5 * dx) * dx))
    return q_in, q_out


# ----------------------------------------------------------------------------- one run
def run_one(
    solver: str,
    cells_per_t: int,
    geo: Geometry,
    column: bool = False,
    work: Path | None = None,
    n_iter: int = 20000,
    residual: float = 1e-9,
) -> dict:
    app = SOLVERS[solver]
    C.require("blockMesh", app, "postProcess")
    label = f"{'column' if column else 'pile' + pile_tag(geo)}_{solver}_T{cells_per_t}"
    work = Path(work) if work is not None else WORK_DIR / label
    write_case(work, solver, geo, cells_per_t, column, case_values(geo, n_iter, residual))
    logs = work / "logs"
    logs.mkdir()
    cmds: list = []
    t0 = time.perf_counter()
    C.run(["blockMesh"], work, logs / "blockMesh.log", FOAM_ENV, cmds)
    solver_wall = C.run([app], work, logs / f"{app}.log", FOAM_ENV, cmds)
    centres_cmd = ["postProcess", "-func", "writeCellCentres", "-time", "0"]
    C.run(centres_cmd, work, logs / "centres.log", FOAM_ENV, cmds)
    dx = geo.thickness / cells_per_t
    times = [p for p in work.iterdir() if _is_time(p.name) and float(p.name) > 0]
    last = max(times, key=lambda p: float(p.name))
    centres = read_internal_field(work / "0" / "C")
    n_cells = len(centres)
    if solver == "laplace":
        holes = geo.pile_thickness > 0 and not column
        field = Field2D.from_cells(centres, read_internal_field(last / "T", n_cells), dx, holes)
        if column:
            q_in = float(np.sum(geo.k * (geo.h_up - field.h[-1]) / (0.5 * dx) * dx))
            q_out = float(np.sum(geo.k * (field.h[0] - geo.h_down) / (0.5 * dx) * dx))
        else:
            q_in, q_out = discharge_laplace(field, geo, dx)
    else:
        p = read_internal_field(last / "p", n_cells)
        field = Field2D.from_cells(centres, p / geo.g, dx, geo.pile_thickness > 0 and not column)
        phi = last / "phi"
        depth = dx  # the mesh is one cell (dx) thick
        q_in = -float(read_patch_values(phi, "upstream").sum()) / depth
        q_out = float(read_patch_values(phi, "downstream").sum()) / depth
    log = (logs / f"{app}.log").read_text(errors="replace")
    iterations = len(re.findall(r"^Time = ", log, re.M))
    return {
        "label": label,
        "solver": solver,
        "application": app,
        "cells_per_T": cells_per_t,
        "dx_m": dx,
        "n_cells": n_cells,
        "column": column,
        "Q_in": q_in,
        "Q_out": q_out,
        "iterations": iterations,
        "converged": ("SIMPLE solution converged" in log) if solver == "porous" else True,
        "wall_time_solver_s": round(solver_wall, 2),
        "wall_time_total_s": round(time.perf_counter() - t0, 2),
        "version": foam_version(logs / f"{app}.log"),
        "commands": cmds,
        "field": field,
        "work": work,
    }


def pile_tag(geo: Geometry) -> str:
    """'' for the thin pile, '_w40mm' for a 40 mm thick one (labels, the data subdirectory)."""
    return f"_w{round(geo.pile_thickness * 1000):d}mm" if geo.pile_thickness > 0 else ""


def data_dir(geo: Geometry) -> Path:
    """data/ for the thin pile; data/pile_w40mm/ (its own manifest and inputs) for a thick one."""
    return DATA_DIR / f"pile{pile_tag(geo)}" if geo.pile_thickness > 0 else DATA_DIR


def _is_time(name: str) -> bool:
    try:
        float(name)
        return True
    except ValueError:
        return False


# ----------------------------------------------------------------------------- samples
def sample_lines(f: Field2D, geo: Geometry) -> list[tuple]:
    """(line, x, y, h, u) on mesh-independent points every T/20."""
    t, half = geo.thickness, geo.half_length
    step = t / 20
    rows = []
    xs = np.arange(-half, half + 0.5 * step, step)
    for x, h in zip(xs, f.at(xs, np.zeros_like(xs))):
        rows.append(("base", x, 0.0, h))
    ys = np.arange(0.0, t + 0.5 * step, step)
    x_line = geo.half_pile + 0.1 * t  # T/10 downstream of the pile's face
    for y, h in zip(ys, f.at(np.full_like(ys, x_line), ys)):
        rows.append(("downstream_x_T_over_10", x_line, y, h))
    # exit gradient along the downstream ground surface: (h(x, T - T/40) - h_down)/(T/40)
    # from the interpolated field (a finite-difference estimate, resolution T/40)
    xe = np.arange(geo.half_pile + step, half + 0.5 * step, step)
    dy = t / 40
    he = f.at(xe, np.full_like(xe, t - dy))
    for x, h in zip(xe, he):
        rows.append(("exit_gradient", x, t, (h - geo.h_down) / dy))
    out = []
    for line, x, y, h in rows:
        u = geo.rho_w * geo.g * (h - y) if line != "exit_gradient" else float("nan")
        out.append((line, float(x), float(y), float(h), float(u)))
    return out


# ----------------------------------------------------------------------------- pipeline
def run_all(
    meshes=MESHES, geo: Geometry = Geometry(), out: Path | None = None, tiny: bool = False, keep: bool = False
):
    """Column checks, the sheet pile on every mesh with both solvers, reduced CSVs and the
    manifest (official runs only: no --out, not --tiny)."""
    if tiny:
        meshes = (TINY_CELLS,)
    official = out is None and not tiny
    out = Path(out) if out is not None else (data_dir(geo) if not tiny else WORK_DIR / "tiny" / "reduced")
    out.mkdir(parents=True, exist_ok=True)
    work_root = WORK_DIR / (("tiny" if tiny else "full") + pile_tag(geo))
    results, t_all = [], time.perf_counter()
    # the column is 4 cells (4 T/10) wide: Q = k (H/T) * width
    q_darcy_column = geo.k * geo.dh / geo.thickness * 4 * geo.thickness / TINY_CELLS
    for solver in SOLVERS:
        # a uniform 1D flow makes the normalised U residual noise: a fixed 300 iterations
        # (the flux settles to round-off in under 300; checked by the imbalance column)
        r = run_one(solver, TINY_CELLS, geo, column=True, work=work_root / f"column_{solver}", n_iter=300)
        r["Q_exact"] = q_darcy_column
        results.append(r)
    for n in meshes:
        for solver in SOLVERS:
            if solver == "porous" and n > 40 and not tiny:
                continue  # the Laplace solve carries the finest mesh; porous to T/40
            results.append(run_one(solver, n, geo, work=work_root / f"pile{pile_tag(geo)}_{solver}_T{n}"))
    factor = sheet_pile_shape_factor(geo.penetration, geo.thickness)
    q_exact = geo.k * geo.dh * factor

    header = (
        f"# tool=OpenFOAM {results[0]['version']} laplacianFoam (steady Laplace for the head) and "
        f"porousSimpleFoam (DarcyForchheimer d=g/(nu k)={geo.darcy_d:.6g} 1/m2, f=0), Debian package "
        f"openfoam {C.debian_package_version('openfoam')}; sheet pile at x=0 to depth s={geo.penetration} m "
        f"in a layer T={geo.thickness} m, x in [-{geo.half_length}, {geo.half_length}] m; "
        f"h_up={geo.h_up} m, h_down={geo.h_down} m above the base; k={geo.k} m/s; "
        f"closed form Q/(kH)={factor:.6f} (Harr 1962, unbounded layer, thin pile)"
        + (f"; pile {geo.pile_thickness} m thick (|x| < {geo.half_pile} m)" if geo.pile_thickness > 0 else "")
        + "\n"
    )
    with open(out / "discharge.csv", "w", newline="") as fh:
        fh.write(header)
        w = csv.writer(fh)
        w.writerow(["case", "solver", "cells_per_T", "n_cells", "Q_m2_per_s", "Q_over_kH", "imbalance_rel"])
        for r in results:
            q = 0.5 * (r["Q_in"] + r["Q_out"])
            w.writerow(
                [
                    "column" if r["column"] else "sheet_pile",
                    r["solver"],
                    r["cells_per_T"],
                    r["n_cells"],
                    f"{q:.9g}",
                    f"{q / (geo.k * geo.dh):.9g}",
                    f"{(r['Q_in'] - r['Q_out']) / q:.2e}",
                ]
            )
    with open(out / "head_lines.csv", "w", newline="") as fh:
        fh.write(header)
        w = csv.writer(fh)
        w.writerow(["solver", "cells_per_T", "line", "x_m", "y_m", "head_m_or_gradient", "pore_pressure_Pa"])
        for r in results:
            if r["column"]:
                continue
            for line, x, y, h, u in sample_lines(r["field"], geo):
                row = [r["solver"], r["cells_per_T"], line, f"{x:.6g}", f"{y:.6g}", f"{h:.9g}", f"{u:.6g}"]
                w.writerow(row)

    write_head_field(results, geo, out / "head_field.csv", header)
    study = mesh_study(results, geo, q_exact)
    entry_runs = {}
    for r in results:
        e = {k: v for k, v in r.items() if k not in ("field", "work")}
        e["Q"] = 0.5 * (r["Q_in"] + r["Q_out"])
        entry_runs[r["label"]] = e
    top = {
        "case": "Steady 2D seepage under a sheet pile in a finite soil layer (issue 10 item 5)",
        "tool": {
            "name": "OpenFOAM (laplacianFoam, porousSimpleFoam)",
            "version": results[0]["version"],
            "debian_package": f"openfoam {C.debian_package_version('openfoam')}",
        },
        "reproduce": "python -m reference_cases.openfoam_seepage_2d.run"
        + (f" --pile-thickness {geo.pile_thickness:g}" if geo.pile_thickness > 0 else ""),
        "parameters": {**asdict(geo), "darcy_d_per_m2": geo.darcy_d, "dh_m": geo.dh},
        "environment": FOAM_ENV,
        "closed_form": {
            "Q_over_kH": factor,
            "Q_m2_per_s": q_exact,
            "source": "Harr, M.E. (1962) Groundwater and Seepage, McGraw-Hill (Dover 1991): single sheet "
            "pile in a layer of finite depth, conformal mapping; Q/(kH) = K(cos a)/(2 K(sin a)), "
            "a = pi s/(2T)",
        },
        "column_check": {
            r["solver"]: {"Q": 0.5 * (r["Q_in"] + r["Q_out"]), "Q_exact_kH_over_T": q_darcy_column}
            for r in results
            if r["column"]
        },
        "mesh_study": study,
        "date_utc": C.now_iso(),
        "wall_time_total_s": round(time.perf_counter() - t_all, 1),
        "host": C.host_facts(),
        "runs": entry_runs,
    }
    if official and geo.pile_thickness > 0:
        (out / "manifest.json").write_text(json.dumps(top, indent=2) + "\n")
        save_inputs(results, out / "inputs")
    elif official:
        MANIFEST.write_text(json.dumps(top, indent=2) + "\n")
        save_inputs(results)
    else:
        (out / "manifest.json").write_text(json.dumps(top, indent=2) + "\n")
    if not keep:
        for r in results:
            for p in r["work"].iterdir():
                if _is_time(p.name) and float(p.name) > 0:
                    shutil.rmtree(p)
    return {"results": results, "study": study, "q_exact": q_exact, "factor": factor, "out": out}


def write_head_field(results, geo: Geometry, path: Path, header: str) -> None:
    """The head of the finest Laplace run on a T/20 grid over the whole layer (for an SPH
    run's initial pore pressure and for full-field comparison)."""
    lap = [r for r in results if r["solver"] == "laplace" and not r["column"]]
    if not lap:
        return
    best = max(lap, key=lambda r: r["cells_per_T"])
    step = geo.thickness / 20
    xs = np.arange(-geo.half_length, geo.half_length + 0.5 * step, step)
    ys = np.arange(0.0, geo.thickness + 0.5 * step, step)
    gx, gy = np.meshgrid(xs, ys)
    h = best["field"].at(gx, gy)
    with open(path, "w", newline="") as fh:
        fh.write(header.rstrip("\n") + f"; head field of laplace T/{best['cells_per_T']}, bilinear\n")
        w = csv.writer(fh)
        w.writerow(["x_m", "y_m", "head_m", "pore_pressure_Pa"])
        for x, y, hh in zip(gx.ravel(), gy.ravel(), h.ravel()):
            w.writerow([f"{x:.6g}", f"{y:.6g}", f"{hh:.9g}", f"{geo.rho_w * geo.g * (hh - y):.6g}"])


def save_inputs(results, inputs_dir: Path = INPUTS_DIR) -> None:
    """The exact dictionaries of the official runs (small text), for the record."""
    if inputs_dir.exists():
        shutil.rmtree(inputs_dir)
    for r in results:
        for sub in ("system", "constant", "0"):
            for src in (r["work"] / sub).glob("*"):
                if src.is_file() and src.name not in ("C", "Cx", "Cy", "Cz"):
                    dst = inputs_dir / r["label"] / sub / src.name
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy(src, dst)


def mesh_study(results, geo: Geometry, q_exact: float) -> dict:
    """Discharge per mesh and solver against the closed form; observed order and a
    Richardson estimate from the three finest Laplace meshes (grid ratio 2)."""
    kh = geo.k * geo.dh
    out = {"Q_exact_over_kH": q_exact / kh, "per_mesh": []}
    lap = {}
    for r in results:
        if r["column"]:
            continue
        q = 0.5 * (r["Q_in"] + r["Q_out"])
        out["per_mesh"].append(
            {
                "solver": r["solver"],
                "cells_per_T": r["cells_per_T"],
                "Q_over_kH": q / kh,
                "rel_error_vs_closed_form": q / q_exact - 1.0,
            }
        )
        if r["solver"] == "laplace":
            lap[r["cells_per_T"]] = q / kh
    pairs = {}
    for r in results:
        if r["column"] or r["solver"] != "porous":
            continue
        if r["cells_per_T"] in lap:
            q = 0.5 * (r["Q_in"] + r["Q_out"]) / kh
            pairs[r["cells_per_T"]] = q / lap[r["cells_per_T"]] - 1.0
    out["porous_vs_laplace_same_mesh_rel"] = pairs
    ns = sorted(lap)
    if len(ns) >= 3:
        f1, f2, f3 = lap[ns[-1]], lap[ns[-2]], lap[ns[-3]]  # fine, medium, coarse
        if (f3 - f2) * (f2 - f1) > 0:
            p = math.log(abs(f3 - f2) / abs(f2 - f1)) / math.log(2.0)
            f_ext = f1 + (f1 - f2) / (2.0**p - 1.0)
            out["richardson"] = {
                "meshes": ns[-3:],
                "observed_order": p,
                "extrapolated_Q_over_kH": f_ext,
                "gci_fine_rel": 1.25 * abs(f1 - f2) / (2.0**p - 1.0) / abs(f1),
                "extrapolated_vs_closed_form_rel": f_ext / (q_exact / kh) - 1.0,
            }
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cells-per-T", type=int, nargs="+", default=list(MESHES))
    p.add_argument("--tiny", action="store_true", help="T/10 only, both solvers (seconds)")
    p.add_argument("--out", type=Path, default=None)
    p.add_argument("--half-length", type=float, default=None, help="L (m), each side of the pile")
    p.add_argument("--keep-fields", action="store_true")
    p.add_argument(
        "--pile-thickness", type=float, default=0.0,
        help="w (m): a solid pile |x| < w/2 instead of the thin baffle (data/pile_w<mm>mm/)",
    )  # fmt: skip
    a = p.parse_args(argv)
    geo = Geometry(pile_thickness=a.pile_thickness)
    if a.half_length is not None:
        geo = Geometry(half_length=a.half_length, pile_thickness=a.pile_thickness)
    res = run_all(tuple(a.cells_per_T), geo, a.out, a.tiny, a.keep_fields)
    print(f"closed form Q/(kH) = {res['factor']:.6f}")
    for m in res["study"]["per_mesh"]:
        err = m["rel_error_vs_closed_form"]
        print(f"  {m['solver']:8s} T/{m['cells_per_T']:<3d} Q/(kH) = {m['Q_over_kH']:.6f} ({err:+.2e})")
    if "richardson" in res["study"]:
        print("  Richardson:", json.dumps(res["study"]["richardson"]))
    print(f"wrote {res['out']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
