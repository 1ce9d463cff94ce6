"""LIGGGHTS (DEM) reference run of the Bui et al. (2008) aluminium-bar column
collapse, quasi-2D, reduced to small CSV files.

    python -m reference_cases.liggghts_column_collapse_2d.run [--sliding MU] [--rolling MUR]
        [--ranks 1|2] [--tiny] [--out DIR] [--mode collapse|repose]

collapse (default): a column W = 0.20 m long and H = 0.10 m high against the left
wall x = 0 of a tank 0.60 m long, in a periodic slab 12 mm (4 mean diameters)
deep; x along the tank, y periodic (slab depth), z up. Spheres of five
diameters 2.70, 2.85, 3.00, 3.15, 3.30 mm (equal number fractions, +/-10 %),
density 2650 kg/m3 (Bui et al. 2008). Hertz-Mindlin (hertz, tangential history)
with rolling resistance (rolling_friction epsd2) between grains and with every
wall. Stages: (1) pack grains loosely behind a gate at x = W, let them fall and
settle; (2) delete the grains whose centre is above H, settle again (flat top,
settled packing); (3) remove the gate and run the collapse to rest, dumping
positions every 0.01 s.

repose: the calibration heap. Grains are poured slowly against the left wall
onto the floor of the same slab (same contact law and parameters); the angle of
repose is the slope of the settled heap surface measured with the same
volume-equivalent-height reduction as the collapse.

Reduction (both modes): on x-bins of 5 mm each grain's volume is shared among
the bins its diameter overlaps; the volume-equivalent height is
h(x) = V_grains(bin) / (bin width * slab depth * phi_ref), phi_ref being the
measured solid fraction of the settled column (grain volume / (W * H * depth)).
* runout: the x where h(x), scanned from the wall, first falls below
  h_thr = 0.5 mean diameter (1.5 mm, about half a monolayer), linearly
  interpolated between bin centres. The 99th percentile of grain x and the
  furthest grain are recorded in the manifest for comparison only.
* wall height: mean h over the first two bins (0 <= x < 10 mm).
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
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from reference_cases import _common as C

CASE_DIR = Path(__file__).resolve().parent
DATA_DIR = CASE_DIR / "data"
WORK_DIR = CASE_DIR / "work"
MANIFEST = CASE_DIR / "manifest.json"

DIAMETERS_MM = (2.70, 2.85, 3.00, 3.15, 3.30)
BIN = 0.005  # x-bin width for the volume-equivalent height [m]
SEEDS = (15485863, 15485867, 15485917, 15485927, 15485933, 32452843, 32452867, 49979687)


@dataclass
class Params:
    # geometry [m]
    column_w: float = 0.20
    column_h: float = 0.10
    tank_l: float = 0.60
    depth: float = 0.012  # periodic slab depth: 4 mean diameters
    # grains
    density: float = 2650.0
    diameters_mm: tuple = DIAMETERS_MM
    # contact law: hertz + tangential history + rolling_friction epsd2
    youngs: float = 5.0e6  # softened (aluminium is 70 GPa); static overlap < 1 % d
    poisson: float = 0.3
    restitution: float = 0.5
    sliding: float = 0.3
    rolling: float = 0.1
    dt: float = 2.0e-5
    # stages [s]
    fill_fraction: float = 0.30  # solid fraction of the loose random insertion
    fill_height: float = 0.23  # height of the insertion region (settles to > H)
    fill_time: float = 0.35
    trim_settle_time: float = 0.10
    collapse_time: float = 1.0
    output_every: float = 0.01
    # repose heap
    heap_grains: int = 1800
    heap_rate: float = 1500.0  # grains per second
    heap_settle_time: float = 0.5
    heap_tank_l: float = 0.30

    @property
    def d_mean(self) -> float:
        return 1e-3 * float(np.mean(self.diameters_mm))


def tiny_params(**kw) -> Params:
    p = Params(
        column_w=0.04,
        column_h=0.025,
        tank_l=0.15,
        fill_height=0.06,
        fill_time=0.15,
        trim_settle_time=0.04,
        collapse_time=0.25,
        output_every=0.01,
        heap_grains=300,
        heap_rate=3000.0,
        heap_settle_time=0.15,
        heap_tank_l=0.12,
    )
    for k, v in kw.items():
        setattr(p, k, v)
    return p


# ----------------------------------------------------------------------------- stability
def rayleigh_time(p: Params) -> float:
    """Rayleigh wave period for the smallest grain (Li et al. 2005 form)."""
    r = 0.5e-3 * min(p.diameters_mm)
    shear = p.youngs / (2.0 * (1.0 + p.poisson))
    return math.pi * r * math.sqrt(p.density / shear) / (0.1631 * p.poisson + 0.8766)


def hertz_contact_time(p: Params, v_impact: float = 1.0) -> float:
    """Duration of a Hertz collision of two smallest grains at v_impact (Johnson 1985)."""
    r = 0.5e-3 * min(p.diameters_mm)
    m = p.density * 4.0 / 3.0 * math.pi * r**3
    e_star = p.youngs / (2.0 * (1.0 - p.poisson**2))
    r_star, m_star = r / 2.0, m / 2.0
    return 2.87 * (m_star**2 / (r_star * e_star**2 * v_impact)) ** 0.2


# ----------------------------------------------------------------------------- input script
def _contact(p: Params) -> str:
    return "model hertz tangential history rolling_friction epsd2"


def _header(p: Params, ranks: int, xlo: float, xhi: float, ztop: float, xwall: float) -> str:
    skin = 0.5 * p.d_mean
    templ = []
    for k, d in enumerate(p.diameters_mm):
        templ.append(
            f"fix pts{k + 1} all particletemplate/sphere {SEEDS[k]} atom_type 1 "
            f"density constant {p.density:g} radius constant {0.5e-3 * d:.6g}"
        )
    weights = " ".join(f"pts{k + 1} {1.0 / len(p.diameters_mm):.6g}" for k in range(len(p.diameters_mm)))
    return f"""# ScourSPH reference: quasi-2D granular column (generated by run.py; do not edit)
atom_style      granular
atom_modify     map array
boundary        f p f
newton          off
communicate     single vel yes
units           si
processors      {ranks} 1 1
region          domain block {xlo:.6g} {xhi:.6g} 0 {p.depth:.6g} 0 {ztop:.6g} units box
create_box      1 domain
neighbor        {skin:.6g} bin
neigh_modify    delay 0

fix m1 all property/global youngsModulus peratomtype {p.youngs:g}
fix m2 all property/global poissonsRatio peratomtype {p.poisson:g}
fix m3 all property/global coefficientRestitution peratomtypepair 1 {p.restitution:g}
fix m4 all property/global coefficientFriction peratomtypepair 1 {p.sliding:g}
fix m5 all property/global coefficientRollingFriction peratomtypepair 1 {p.rolling:g}

pair_style      gran {_contact(p)}
pair_coeff      * *
timestep        {p.dt:g}
fix gravi all gravity 9.81 vector 0.0 0.0 -1.0

fix floor all wall/gran {_contact(p)} primitive type 1 zplane 0.0
fix lwall all wall/gran {_contact(p)} primitive type 1 xplane 0.0
fix rwall all wall/gran {_contact(p)} primitive type 1 xplane {xwall:.6g}

{chr(10).join(templ)}
fix pdd all particledistribution/discrete/numberbased {SEEDS[5]} {len(p.diameters_mm)} {weights}

fix integr all nve/sphere
compute rke all erotate/sphere
variable stp equal step
thermo_style    custom step atoms ke c_rke
thermo_modify   lost error norm no
"""


def steps(t: float, dt: float) -> int:
    return max(1, int(round(t / dt)))


def collapse_script(p: Params, ranks: int, balanced_box: bool = False) -> str:
    # box: with 2 ranks the x-split (box middle) falls at x = W/2, so each rank holds
    # half the column while it is filled and settled, and rank 1 takes the runout
    # (LIGGGHTS 3.8.0 has no `balance`); the empty x < 0 costs only neighbour bins.
    # Serial runs keep the box of the committed reference (inputs/*.in); the box
    # bounds change the random packing realization, not the physics.
    if ranks == 1 and not balanced_box:
        xlo = min(0.0, 2 * p.column_w - p.tank_l) - 1e-3
    else:
        xlo = p.column_w - p.tank_l
    xhi = p.tank_l + 1e-3
    ztop = p.fill_height + 0.02
    n_out = steps(p.output_every, p.dt)
    s = _header(p, ranks, xlo, xhi, ztop, p.tank_l)
    s += f"""
# ---- stage 1: loose random packing behind the gate, fall and settle
fix gate all wall/gran {_contact(p)} primitive type 1 xplane {p.column_w:.6g}
region fillreg block 0 {p.column_w:.6g} 0 {p.depth:.6g} 0 {p.fill_height:.6g} units box
fix ins all insert/pack seed {SEEDS[6]} distributiontemplate pdd maxattempt 300 &
    insert_every once overlapcheck yes all_in yes vel constant 0. 0. 0. &
    region fillreg volumefraction_region {p.fill_fraction:g}
thermo          {n_out}
run             1
unfix           ins
run             {steps(p.fill_time, p.dt)}

# ---- stage 2: flat top at H (delete grains with centre above H), settle again
region above block INF INF INF INF {p.column_h:.6g} INF units box
delete_atoms    region above
run             {steps(p.trim_settle_time, p.dt)}
print           "SETTLED_STEP ${{stp}}"
dump            d0 all custom 1 settled.dump id x y z radius vx vy vz
run             0
undump          d0

# ---- stage 3: remove the gate, collapse
unfix           gate
reset_timestep  0
print           "RELEASE_STEP ${{stp}}"
dump            dc all custom {n_out} dump/collapse_*.dump id x y z radius vx vy vz
dump_modify     dc pad 10
run             {steps(p.collapse_time, p.dt)}
print           "FINISHED_STEP ${{stp}}"
"""
    return s


def repose_script(p: Params, ranks: int) -> str:
    xlo, xhi = -1e-3, p.heap_tank_l + 1e-3
    # pour region next to the left wall, above the heap top
    z0 = 0.075 if p.heap_grains > 1000 else 0.04
    pour_x = 0.015 if p.heap_grains > 1000 else 0.01
    ztop = z0 + 0.04
    n_out = steps(p.output_every, p.dt)
    pour_time = p.heap_grains / p.heap_rate
    s = _header(p, ranks, xlo, xhi, ztop, p.heap_tank_l)
    s += f"""
# ---- pour slowly against the left wall, then settle
region pour block 0.0 {pour_x:.6g} 0 {p.depth:.6g} {z0:.6g} {z0 + 0.02:.6g} units box
fix ins all insert/rate/region seed {SEEDS[7]} distributiontemplate pdd &
    nparticles {p.heap_grains} particlerate {p.heap_rate:g} insert_every {steps(0.005, p.dt)} &
    overlapcheck yes all_in yes vel constant 0. 0. -0.3 region pour ntry_mc 10000
thermo          {n_out}
run             {steps(pour_time + 0.05, p.dt)}
unfix           ins
run             {steps(p.heap_settle_time, p.dt)}
print           "FINISHED_STEP ${{stp}}"
dump            d0 all custom 1 heap.dump id x y z radius vx vy vz
run             0
"""
    return s


# ----------------------------------------------------------------------------- reading
def read_dump(path: Path) -> tuple[int, np.ndarray]:
    with open(path) as fh:
        lines = [next(fh) for _ in range(9)]
    step = int(lines[1])
    cols = lines[8].split()[2:]
    arr = np.loadtxt(path, skiprows=9, ndmin=2)
    rec = {c: arr[:, i] for i, c in enumerate(cols)}
    return step, rec


def read_thermo(log: Path) -> np.ndarray:
    """(step, atoms, ke, rke) rows of every thermo block in a LIGGGHTS log
    (INFO lines inside a block are skipped; a repeated step keeps its last row)."""
    rows, on = {}, False
    for line in log.read_text(errors="replace").splitlines():
        if line.split()[:3] == ["Step", "Atoms", "KinEng"]:
            on = True
            continue
        if on and line.startswith("Loop time"):
            on = False
            continue
        if on:
            parts = line.split()
            if len(parts) == 4:
                try:
                    vals = [float(x) for x in parts]
                except ValueError:
                    continue
                rows[int(vals[0])] = vals
    return np.array([rows[k] for k in sorted(rows)]).reshape(-1, 4)


def marker(log: Path, name: str) -> int:
    m = re.findall(rf"^{name} (\d+)", log.read_text(errors="replace"), re.M)
    if not m:
        raise C.ToolFailed(f"{name} not found in {log}")
    return int(m[-1])


def stage_loop_times(log: Path) -> list[dict]:
    """LIGGGHTS `Loop time` of every run command: seconds, steps, grains."""
    out = []
    for m in re.finditer(
        r"^Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms",
        log.read_text(errors="replace"),
        re.M,
    ):
        t, procs, n, atoms = float(m.group(1)), int(m.group(2)), int(m.group(3)), int(m.group(4))
        if n > 1:
            out.append(
                {
                    "seconds": round(t, 1),
                    "procs": procs,
                    "steps": n,
                    "grains": atoms,
                    "steps_per_s": round(n / t, 1) if t > 0 else None,
                }
            )
    return out


def liggghts_version(log: Path) -> str:
    m = re.search(r"LIGGGHTS \(Version ([^)]*)\)", log.read_text(errors="replace"))
    return m.group(1).strip() if m else "unknown"


# ----------------------------------------------------------------------------- reduction
def volume_height(
    x: np.ndarray, r: np.ndarray, length: float, depth: float, phi: float, bin_w: float = BIN
) -> tuple[np.ndarray, np.ndarray]:
    """Volume-equivalent height on x-bins [0, length); each grain's volume is
    shared among the bins in proportion to the overlap of its diameter."""
    nb = int(round(length / bin_w))
    edges = np.arange(nb + 1) * bin_w
    vol = 4.0 / 3.0 * np.pi * r**3
    lo, hi = x - r, x + r
    acc = np.zeros(nb)
    for k in range(nb):
        ov = np.clip(np.minimum(hi, edges[k + 1]) - np.maximum(lo, edges[k]), 0.0, None)
        acc[k] = np.sum(vol * ov / (2.0 * r))
    h = acc / (bin_w * depth * phi)
    return 0.5 * (edges[:-1] + edges[1:]), h


def runout_from_profile(xc: np.ndarray, h: np.ndarray, h_thr: float) -> float:
    below = np.where(h < h_thr)[0]
    if len(below) == 0:
        return float(xc[-1] + 0.5 * (xc[1] - xc[0]))
    k = below[0]
    if k == 0:
        return 0.0
    # h crosses h_thr between bin centres k-1 and k
    return float(xc[k - 1] + (h[k - 1] - h_thr) / (h[k - 1] - h[k]) * (xc[k] - xc[k - 1]))


def wall_height(xc: np.ndarray, h: np.ndarray, width: float = 0.010) -> float:
    return float(np.mean(h[xc < width]))


def heap_angle(xc: np.ndarray, h: np.ndarray, x_min: float) -> tuple[float, dict]:
    """Slope of the heap flank: least squares on bins with x >= x_min (outside
    the pour zone) and 0.2 h_max < h < 0.8 h_max."""
    hm = float(np.max(h))
    sel = (xc >= x_min) & (h > 0.2 * hm) & (h < 0.8 * hm)
    # keep the contiguous flank only (first contiguous run after x_min)
    idx = np.where(sel)[0]
    if len(idx) < 3:
        raise ValueError("heap flank too short to fit")
    slope, icpt = np.polyfit(xc[idx], h[idx], 1)
    resid = h[idx] - (slope * xc[idx] + icpt)
    return float(math.degrees(math.atan(-slope))), {
        "fit_bins": int(len(idx)),
        "fit_x_range_m": [float(xc[idx[0]]), float(xc[idx[-1]])],
        "fit_rms_residual_m": float(np.sqrt(np.mean(resid**2))),
        "h_max_m": hm,
    }


# ----------------------------------------------------------------------------- pipeline
def _prepare(work: Path) -> None:
    if work.exists():
        shutil.rmtree(work)
    (work / "dump").mkdir(parents=True)


def _liggghts_cmd(ranks: int) -> list[str]:
    base = ["liggghts", "-in", "in.liggghts", "-log", "log.liggghts", "-echo", "none"]
    return base if ranks == 1 else C.mpirun_prefix(ranks) + base


def run_collapse(
    p: Params,
    ranks: int = 1,
    tiny: bool = False,
    out: Path | None = None,
    label: str | None = None,
    official: bool | None = None,
    balanced_box: bool = False,
) -> dict:
    C.require("liggghts")
    if ranks > 1:
        C.require("mpirun")
    label = label or (
        f"collapse_mus{p.sliding:g}_mur{p.rolling:g}"
        + ("" if ranks == 1 else f"_np{ranks}")
        + ("_tiny" if tiny else "")
    )
    work = WORK_DIR / label
    if official is None:
        official = out is None and not tiny
    out = Path(out) if out is not None else (DATA_DIR if official else work / "reduced")
    sfx = "" if ranks == 1 else f"_np{ranks}"
    _prepare(work)
    out.mkdir(parents=True, exist_ok=True)
    (work / "in.liggghts").write_text(collapse_script(p, ranks, balanced_box))
    cmds: list = []
    wall = C.run(_liggghts_cmd(ranks), work, work / "stdout.txt", None, cmds)
    t_red = time.perf_counter()
    log = work / "log.liggghts"
    release, finished = marker(log, "RELEASE_STEP"), marker(log, "FINISHED_STEP")

    _, st = read_dump(work / "settled.dump")
    n_grains = len(st["x"])
    v_grains = float(np.sum(4.0 / 3.0 * np.pi * st["radius"] ** 3))
    phi = v_grains / (p.column_w * p.column_h * p.depth)
    h_thr = 0.5 * p.d_mean
    length = p.tank_l

    hist = []
    frames = sorted((work / "dump").glob("collapse_*.dump"))
    final = None
    for f in frames:
        step, rec = read_dump(f)
        xc, h = volume_height(rec["x"], rec["radius"], length, p.depth, phi)
        t = (step - release) * p.dt
        hist.append(
            (
                t,
                runout_from_profile(xc, h, h_thr),
                wall_height(xc, h),
                len(rec["x"]),
                float(np.percentile(rec["x"], 99)),
                float(np.max(rec["x"] + rec["radius"])),
            )
        )
        final = (xc, h, rec)
    hist = np.array(hist)
    th = read_thermo(log)
    te = th[th[:, 0] >= release]
    t_e = (te[:, 0] - release) * p.dt

    with open(out / f"history{sfx}.csv", "w", newline="") as fh:
        fh.write(
            f"# LIGGGHTS quasi-2D column collapse, mu_s={p.sliding:g}, mu_r={p.rolling:g} "
            f"(epsd2), ranks={ranks}; runout = x where the volume-equivalent height falls "
            f"below {h_thr * 1e3:.2g} mm (0.5 d_mean), scanning from the wall; wall_height = "
            f"volume-equivalent height over 0 <= x < 10 mm; phi_ref={phi:.4f}\n"
        )
        w = csv.writer(fh)
        w.writerow(["t_s", "runout_m", "wall_height_m"])
        for row in hist:
            w.writerow([f"{row[0]:.4f}", f"{row[1]:.5f}", f"{row[2]:.5f}"])
    xc, h, rec = final
    with open(out / f"final_profile{sfx}.csv", "w", newline="") as fh:
        fh.write(
            f"# LIGGGHTS final deposit at t={hist[-1, 0]:.3f} s after gate removal: "
            f"volume-equivalent height on {BIN * 1e3:g} mm x-bins (bin centres), "
            f"phi_ref={phi:.4f}, mu_s={p.sliding:g}, mu_r={p.rolling:g}\n"
        )
        w = csv.writer(fh)
        w.writerow(["x_m", "height_m"])
        for xx, hh in zip(xc, h):
            w.writerow([f"{xx:.4f}", f"{hh:.5f}"])
    with open(out / f"energy{sfx}.csv", "w", newline="") as fh:
        fh.write(
            "# LIGGGHTS thermo after gate removal: total translational and rotational "
            "kinetic energy of all grains in the slab\n"
        )
        w = csv.writer(fh)
        w.writerow(["t_s", "kinetic_J", "rotational_J"])
        for t, row in zip(t_e, te):
            w.writerow([f"{t:.4f}", f"{row[2]:.6e}", f"{row[3]:.6e}"])

    ke0 = th[(th[:, 0] >= release)][:, 2]
    entry = {
        "date_utc": C.now_iso(),
        "mode": "collapse",
        "tiny": tiny,
        "ranks": ranks,
        "params": _param_record(p),
        "n_grains": int(n_grains),
        "grain_count_final": int(hist[-1, 3]),
        "phi_ref": round(phi, 4),
        "wall_time_s": round(wall, 1),
        "wall_time_reduction_s": round(time.perf_counter() - t_red, 1),
        "timestep": _timestep_record(p),
        "steps_total": int(finished),
        "stage_loop_times_s": stage_loop_times(log),
        "final": {
            "t_s": round(float(hist[-1, 0]), 4),
            "runout_m": round(float(hist[-1, 1]), 4),
            "wall_height_m": round(float(hist[-1, 2]), 4),
            "initial_wall_height_m": round(float(hist[0, 2]), 4),
            "runout_p99_grain_x_m": round(float(hist[-1, 4]), 4),
            "furthest_grain_edge_m": round(float(hist[-1, 5]), 4),
            "kinetic_energy_peak_J": float(ke0.max()),
            "kinetic_energy_final_J": float(ke0[-1]),
        },
        "commands": cmds,
        "input": str(C._rel(work / "in.liggghts")),
        "outputs": [str(C._rel(out / f"{n}{sfx}.csv")) for n in ("history", "final_profile", "energy")],
        "host": C.host_facts(),
        "version": liggghts_version(log),
    }
    if official:
        (CASE_DIR / "inputs").mkdir(exist_ok=True)
        shutil.copy(work / "in.liggghts", CASE_DIR / "inputs" / f"{label}.in")
        C.update_manifest(MANIFEST, label, entry, _top(entry["version"]))
    else:
        (out / "manifest.json").write_text(
            json.dumps({**_top(entry["version"]), "runs": {label: entry}}, indent=2) + "\n"
        )
    return {
        "label": label,
        "work": work,
        "out": out,
        "entry": entry,
        "history": hist,
        "energy": np.column_stack([t_e, te[:, 2], te[:, 3]]),
        "profile": (xc, h),
    }


def heap_solid_fraction(rec: dict, window: tuple) -> float:
    """Solid fraction inside the heap: grain volume with centres in the window
    (x0, x1, z0, z1) over the window volume (whole slab depth)."""
    x0, x1, z0, z1 = window
    sel = (rec["x"] >= x0) & (rec["x"] < x1) & (rec["z"] >= z0) & (rec["z"] < z1)
    vol = float(np.sum(4.0 / 3.0 * np.pi * rec["radius"][sel] ** 3))
    return vol / ((x1 - x0) * (z1 - z0) * rec["depth"])


def run_repose(
    p: Params, ranks: int = 1, tiny: bool = False, label: str | None = None, reuse: bool = False
) -> dict:
    """Pour a heap and measure its angle of repose; returns the angle and details.
    With reuse=True an existing heap dump in work/ is reduced again (no run)."""
    label = label or (f"repose_mus{p.sliding:g}_mur{p.rolling:g}" + ("_tiny" if tiny else ""))
    work = WORK_DIR / label
    cmds: list = []
    if reuse and (work / "heap.dump").exists():
        prev = json.loads((work / "entry.json").read_text()) if (work / "entry.json").exists() else {}
        wall, cmds = prev.get("wall_time_s"), prev.get("commands", [])
        if wall is None:  # not recorded: the LIGGGHTS loop times (setup excluded)
            loops = re.findall(r"^Loop time of (\S+)", (work / "log.liggghts").read_text(), re.M)
            wall = round(sum(float(x) for x in loops), 1)
    else:
        C.require("liggghts")
        _prepare(work)
        (work / "in.liggghts").write_text(repose_script(p, ranks))
        wall = C.run(_liggghts_cmd(ranks), work, work / "stdout.txt", None, cmds)
    _, rec = read_dump(work / "heap.dump")
    rec["depth"] = p.depth
    # the heap's own solid fraction, measured in its core (the slope in h depends on it)
    window = (0.03, 0.07, 0.004, 0.016) if not tiny else (0.01, 0.03, 0.002, 0.006)
    phi = heap_solid_fraction(rec, window)
    xc, h = volume_height(rec["x"], rec["radius"], p.heap_tank_l, p.depth, phi)
    angle, fit = heap_angle(xc, h, x_min=0.03 if not tiny else 0.015)
    th = read_thermo(work / "log.liggghts")
    entry = {
        "date_utc": C.now_iso(),
        "mode": "repose",
        "tiny": tiny,
        "ranks": ranks,
        "params": _param_record(p),
        "n_grains": int(len(rec["x"])),
        "repose_angle_deg": round(angle, 2),
        "fit": fit,
        "heap_solid_fraction": round(phi, 4),
        "solid_fraction_window_m": list(window),
        "wall_time_s": wall,
        "timestep": _timestep_record(p),
        "kinetic_energy_final_J": float(th[-1, 2]) if len(th) else None,
        "commands": cmds,
        "version": liggghts_version(work / "log.liggghts"),
        "host": C.host_facts(),
    }
    (work / "entry.json").write_text(json.dumps(entry, indent=2) + "\n")
    if not tiny:
        (CASE_DIR / "inputs").mkdir(exist_ok=True)
        shutil.copy(work / "in.liggghts", CASE_DIR / "inputs" / f"{label}.in")
    with open(work / "heap_profile.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["x_m", "height_m"])
        for xx, hh in zip(xc, h):
            w.writerow([f"{xx:.4f}", f"{hh:.5f}"])
    return {"label": label, "work": work, "angle": angle, "entry": entry, "profile": (xc, h)}


def _param_record(p: Params) -> dict:
    d = asdict(p)
    d["diameters_mm"] = list(p.diameters_mm)
    d["d_mean_m"] = p.d_mean
    return d


def _timestep_record(p: Params) -> dict:
    tr = rayleigh_time(p)
    tc = hertz_contact_time(p, 1.0)
    return {
        "dt_s": p.dt,
        "rayleigh_time_s": tr,
        "dt_over_rayleigh": round(p.dt / tr, 4),
        "hertz_contact_time_1mps_s": tc,
        "dt_over_hertz_contact": round(p.dt / tc, 4),
    }


def _top(version: str) -> dict:
    return {
        "case": "Bui et al. (2008) aluminium-bar column collapse, quasi-2D DEM",
        "tool": {
            "name": "LIGGGHTS-PUBLIC",
            "version": version,
            "debian_package": f"liggghts {C.debian_package_version('liggghts')}",
            "mpi": f"openmpi-bin {C.debian_package_version('openmpi-bin')}",
        },
        "reproduce": "python -m reference_cases.liggghts_column_collapse_2d.calibrate  (heaps + "
        "sensitivity), then python -m reference_cases.liggghts_column_collapse_2d.run "
        "--sliding MU --rolling MUR [--ranks 2]",
        "source": "Bui, H.H., Fukagawa, R., Sako, K., Ohno, S. (2008) Lagrangian meshfree "
        "particles method (SPH) for large deformation and failure flows of geomaterial "
        "using elastic-plastic soil constitutive model. Int. J. Numer. Anal. Meth. "
        "Geomech. 32, 1537-1570 (aluminium bars, friction angle 19.8 deg, "
        "density 2650 kg/m3).",
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mode", choices=["collapse", "repose"], default="collapse")
    ap.add_argument("--sliding", type=float, default=None, help="sliding friction mu_s")
    ap.add_argument("--rolling", type=float, default=None, help="rolling friction mu_r (epsd2)")
    ap.add_argument("--ranks", type=int, default=1, choices=[1, 2])
    ap.add_argument("--tiny", action="store_true", help="a few hundred grains, seconds")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--collapse-time", type=float, default=None)
    ap.add_argument(
        "--balanced-box",
        action="store_true",
        help="serial run in the 2-rank box (x from W-L), for timing comparisons",
    )
    ap.add_argument("--nice", type=int, default=0)
    a = ap.parse_args(argv)
    if a.nice:
        os.nice(a.nice)
    p = tiny_params() if a.tiny else Params()
    cal = calibrated()
    p.sliding = a.sliding if a.sliding is not None else cal[0]
    p.rolling = a.rolling if a.rolling is not None else cal[1]
    if a.collapse_time:
        p.collapse_time = a.collapse_time
    if a.mode == "repose":
        res = run_repose(p, a.ranks, a.tiny)
        e = res["entry"]
        print(
            f"{res['label']}: {e['n_grains']} grains, repose angle {e['repose_angle_deg']} deg, "
            f"wall {e['wall_time_s']} s"
        )
        return 0
    res = run_collapse(p, a.ranks, a.tiny, a.out, balanced_box=a.balanced_box)
    e = res["entry"]
    print(
        f"{res['label']}: {e['n_grains']} grains, runout {e['final']['runout_m']} m, wall height "
        f"{e['final']['wall_height_m']} m, wall {e['wall_time_s']} s -> {res['out']}"
    )
    return 0


def calibrated() -> tuple[float, float]:
    """(mu_s, mu_r) chosen by the calibration (manifest), else the defaults."""
    if MANIFEST.exists():
        cal = json.loads(MANIFEST.read_text()).get("calibration", {})
        if "chosen" in cal:
            return cal["chosen"]["sliding_friction"], cal["chosen"]["rolling_friction"]
    return Params.sliding, Params.rolling


if __name__ == "__main__":
    sys.exit(main())
