"""Stability matrix (issue 14): hard cases that must end with no blow-up, nothing through a
wall, and kinetic energy bounded by the energy the run had to give.

    python -m verification.stability_matrix            # the whole matrix (nightly; long)
    python -m verification.stability_matrix --ci       # the CI subset (tests/test_stability_matrix.py)
    python -m verification.stability_matrix --only column_dp_a2   # cells whose name contains a string

writes verification/results/stability_matrix/matrix.md and .csv (one row per cell: outcome,
wall reflections, deepest penetration, energy ratio, wall and CPU time, the load).

Cells
  column_dp_a{A}_dx{D}   a soil column W = 0.1 m wide, A W tall (A = 0.5, 1, 2, 3, 4) against the left
                         wall of a 1.0 m long tank, dx = D mm (5, 4, 3, 2.5), with the settings of
                         scenes/column_collapse_2d.toml (Bui et al. 2008 bars: Drucker-Prager,
                         artificial stress 0.5, no-slip floor, geostatic start), to t = 1 s (the
                         scene's end time: its flow has stopped well before).
  column_mc_a{A}_dx{D}   the same columns with the seed's soil (seed sec. 3: E = 20 MPa, nu = 0.3,
                         c = 0, rho = 1800 kg/m^3, Mohr-Coulomb scale-back, AV alpha = beta = 1, no
                         artificial stress: the seed has none). The seed gives no friction angle:
                         phi = 33 deg, the critical-state angle of quartz sand (Bolton 1986,
                         Geotechnique 36(1):65-78), with psi = 0 (no dilatancy at critical state).
                         Full K = E / 3(1 - 2 nu) (the seed's reduced K has no value in the paper).
  dam_break_r{R}         scenes/dam_break_2d.toml at a/R (R = 20, 40, 80, 160), to t = 0.6 s: the
                         surge hits the far wall at t ~ 0.30 s (T = t sqrt(2g/a) ~ 5.5) and runs up it.
  block_drop_dx{D}       a 0.1 x 0.05 m block of the bars dropped at 2 m/s onto the no-slip floor, to 0.6 s.
  saturated_bed_dx{D}    scenes/scour_saturated.toml without its inlet (soil and pore water, geostatic and
                         hydrostatic, under the free surface of its pore water) at rest, to 0.25 s.
  overflow_jet_dx{D}     scenes/scour_dry.toml (q = 0.11, the study's highest) to 0.25 s: the nappe lands
                         at t = 0 (prefill) and scours the dry layer. Also checked: the body leak counter
                         is 0 and the volume balance holds within one particle volume.
  saturated_jet_dx{D}    scenes/scour_saturated.toml with its inlet (q = 0.11) to 0.25 s: the same nappe onto
                         the two-phase bed, seepage coupling included (issue 11 item 9's hard case at 2.5 mm).

Checks per cell (CellResult.ok)
  no blow-up      the solver's own checks (NaN, particle outside the domain, wall crossing deeper
                  than h, time-step collapse) raise BlowUpError; the cell records it;
  walls           deepest specular reflection (Simulation.deepest_penetration) below dx/2, the bound
                  of tests/test_soil_hard_cases.py (a particle reflected by less than half a spacing
                  stays in its own lattice cell); the count of reflections is reported;
  energy          KE(t) <= F (KE(0) + PE(0) - PE(t) + E_el(0) + W_in), every ENERGY_EVERY steps.
                  The bracket is exact for the continuum: the total energy KE + PE + E_el never
                  grows (AV, plasticity and tension cracking only dissipate; psi = 0), E_el >= 0,
                  and W_in is the energy an inlet brings (below; 0 without one; outlets only remove
                  energy, which PE(t) >= 0 leaves out). E_el(0) is the start state's elastic energy
                  (geostatic soil, hydrostatic water), which is free to become kinetic. F is the
                  time integration's slack: leap-frog conserves a modified energy; for the fastest
                  mode, omega dt, the true energy differs from it by the factor 1 / (1 - (omega dt)^2
                  / 4) at most (Verlet on a harmonic oscillator). The fastest lattice mode has
                  omega <= 2 c / dx, and dt <= C_s h / c, so omega dt <= 2 C_s h / dx = 0.65 here,
                  F = 1.12. A blow-up exceeds the bound by orders of magnitude (issue 14: a grain at
                  3.7 km/s carries 3e5 J/m against a column's 50 J/m).
KE is measured with velocities at whole steps (Simulation.current_state), PE = -sum m g.x.
W_in (overflow_jet): each buffer layer an inlet appends brings its kinetic and potential energy,
m sum_j (u^2/2 - g.x_j) at the section, and the buffer pushes the water ahead with its pressure:
the flow work p u W dt per step, with p the mean positive pressure of the free water within one
layer spacing downstream of the section (measured every step; an estimate of the work the
kinematic buffer does, not a bound).
"""

from __future__ import annotations

import argparse
import csv
import math
import os
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
OUT = Path(__file__).with_name("results") / "stability_matrix"
COLLAPSE = ROOT / "scenes" / "column_collapse_2d.toml"
DAM_BREAK = ROOT / "scenes" / "dam_break_2d.toml"
SCOUR_DRY = ROOT / "scenes" / "scour_dry.toml"
SCOUR_SATURATED = ROOT / "scenes" / "scour_saturated.toml"
SCOUR_END = 0.25  # s: the overflow jet lands at t = 0; 0.25 s is ~10 passages of the nappe over the layer
SCOUR_SPACINGS = (0.005, 0.0025)

ASPECTS = (0.5, 1, 2, 3, 4)
SOIL_SPACINGS = (0.005, 0.004, 0.003, 0.0025)
DAM_RESOLUTIONS = (20, 40, 80, 160)
COLUMN_WIDTH = 0.1  # m
TANK_LENGTH = 1.0  # m
COLUMN_END = 1.0  # s, the collapse scene's end time
DAM_END = 0.6  # s: impact on the far wall at ~0.30 s, then the run-up
DROP_END = 0.6  # s
DROP_SPEED = 2.0  # m/s
ENERGY_EVERY = 10  # steps between energy checks
# the seed's soil (sec. 3) with phi from Bolton (1986)
SEED_SAND = {
    "model": "soil",
    "density": 1800.0,
    "youngs_modulus": 20.0e6,
    "poisson_ratio": 0.3,
    "friction_angle": 33.0,
    "cohesion": 0.0,
    "dilatancy_angle": 0.0,
    "yield_model": "mohr_coulomb",
}

# Cells that fail today, with the measured failure: strict xfails in tests/test_stability_matrix.py.
# Measured with the crack-density fix (issue 14). dam_break_r40 was one (issue 15: blow-up at t = 0.5996 s
# with the seed's scheme, a particle 5 mm through the far wall); with the issue-15 defaults it completes
# with zero wall reflections (2026-12-01, matrix.md), so it is a plain passing cell now.
KNOWN_FAILURES: dict[str, str] = {}


@dataclass
class Cell:
    name: str
    family: str
    build: object = None  # () -> (scene, setup(sim) or None)
    end_time: float = 0.0
    ci: bool = False  # in the CI subset (make test)
    placeholder: str | None = None  # a case that does not exist yet: why


@dataclass
class CellResult:
    name: str
    family: str
    status: str = "not run"  # "completed" | "blow-up: ..." | "skipped: ..."
    particles: int = 0
    steps: int = 0
    t_reached: float = 0.0
    end_time: float = 0.0
    spacing: float = 0.0
    wall_reflections: int = 0
    deepest_penetration: float = 0.0
    energy_ratio: float = 0.0  # max over checks of KE / (F * available energy)
    energy_factor: float = 1.0
    body_leaks: int = 0
    balance_ok: bool = True  # volume balance within one particle volume (scenes with inlets or outlets)
    wall_s: float = 0.0
    cpu_s: float = 0.0
    load: float = 0.0
    notes: list = field(default_factory=list)

    @property
    def completed(self):
        return self.status == "completed"

    @property
    def walls_ok(self):
        return self.deepest_penetration < 0.5 * self.spacing

    @property
    def energy_ok(self):
        return self.energy_ratio <= 1.0

    @property
    def ok(self):
        return (
            self.completed and self.walls_ok and self.energy_ok and self.body_leaks == 0 and self.balance_ok
        )

    def failure(self):
        """One line: what failed, for a report or an xfail reason."""
        out = []
        if not self.completed:
            out.append(self.status)
        if not self.walls_ok:
            out.append(f"deepest wall penetration {self.deepest_penetration:.3g} m >= dx/2")
        if not self.energy_ok:
            out.append(f"kinetic energy {self.energy_ratio:.3g} x its bound")
        if self.body_leaks:
            out.append(f"{self.body_leaks} particle-steps inside a body")
        if not self.balance_ok:
            out.append("volume balance off by more than one particle volume")
        return "; ".join(out)


# -- scenes ------------------------------------------------------------------------------------
def _parse(raw, path):
    from solver.scene import parse_scene

    return parse_scene(raw, path)


def column_raw(aspect, dx, seed_soil=False, end_time=COLUMN_END):
    """The raw scene dict of a column cell (also used by verification/column_blowup.py)."""
    raw = tomllib.loads(COLLAPSE.read_text())
    height = aspect * COLUMN_WIDTH
    raw["scene"].update(
        name=f"column_{'mc' if seed_soil else 'dp'}_a{aspect:g}", spacing=float(dx), end_time=float(end_time)
    )
    raw["domain"]["max"] = [TANK_LENGTH, max(0.3, 1.5 * height)]  # open top, well above the column
    name = "sand" if seed_soil else "bars"
    if seed_soil:
        raw["materials"] = {"sand": dict(SEED_SAND)}
        raw["numerics"]["artificial_stress"] = 0.0  # the seed has no artificial stress
    block = {"name": "column", "material": name, "shape": "rectangle", "min": [0.0, 0.0]}
    raw["blocks"] = [dict(block, max=[COLUMN_WIDTH, height], geostatic=True)]
    return raw


def column_scene(aspect, dx, seed_soil=False, end_time=COLUMN_END):
    return _parse(column_raw(aspect, dx, seed_soil, end_time), COLLAPSE)


def dam_break_scene(resolution, end_time=DAM_END):
    raw = tomllib.loads(DAM_BREAK.read_text())
    a = raw["blocks"][0]["max"][0]
    raw["scene"].update(spacing=a / resolution, end_time=float(end_time))
    return _parse(raw, DAM_BREAK)


def block_drop_scene(dx, end_time=DROP_END):
    raw = tomllib.loads(COLLAPSE.read_text())
    raw["scene"].update(name="block_drop", spacing=float(dx), end_time=float(end_time))
    raw["domain"]["max"] = [0.5, 0.3]
    raw["blocks"] = [
        {"name": "b", "material": "bars", "shape": "rectangle", "min": [0.1, 0.05], "max": [0.2, 0.1]}
    ]
    return _parse(raw, COLLAPSE)


def scour_scene(saturated, dx, end_time=SCOUR_END, jet=None):
    """The scour scenes at spacing dx. jet: keep the inlet (default: the dry scene keeps it, the
    saturated one drops it and is a bed at rest)."""
    path = SCOUR_SATURATED if saturated else SCOUR_DRY
    raw = tomllib.loads(path.read_text())
    raw["scene"].update(spacing=float(dx), end_time=float(end_time))
    raw["output"] = {"interval": float(end_time), "vtk": False, "render": False}
    if jet is None:
        jet = not saturated
    if not jet:
        raw["scene"]["name"] = "saturated_bed"
        del raw["inlets"]
    return _parse(raw, path)


def _drop(sim):
    ps = sim.particles
    ps["v"][: ps.n_owned] = (0.0, -DROP_SPEED)
    ps["v_half"][: ps.n_owned] = (0.0, -DROP_SPEED)


# -- cells -------------------------------------------------------------------------------------
CI_CELLS = {
    # under 2 min of CPU together (89 M particle-steps would be 2-3 min): the issue-14 column at
    # 4 mm (blew up before the crack-density fix); the seed's sand at 5 mm (its wave speed, 122 m/s,
    # makes each cell 6x the steps of the bars'); the dam break through its impact; the drop
    "column_dp_a2_dx4mm",
    "column_mc_a1_dx5mm",
    "dam_break_r20",
    "block_drop_dx5mm",
}


def _mm(dx):
    return f"{dx * 1000:g}mm"


def cells():
    out = []
    for seed_soil, fam in ((False, "column_dp"), (True, "column_mc")):
        for aspect in ASPECTS:
            for dx in SOIL_SPACINGS:
                name = f"{fam}_a{aspect:g}_dx{_mm(dx)}"
                out.append(
                    Cell(
                        name,
                        fam,
                        lambda a=aspect, d=dx, s=seed_soil: (column_scene(a, d, s), None),
                        COLUMN_END,
                    )
                )
    for r in DAM_RESOLUTIONS:
        out.append(Cell(f"dam_break_r{r}", "dam_break", lambda r=r: (dam_break_scene(r), None), DAM_END))
    for dx in SOIL_SPACINGS:
        out.append(
            Cell(f"block_drop_dx{_mm(dx)}", "block_drop", lambda d=dx: (block_drop_scene(d), _drop), DROP_END)
        )
    for dx in SCOUR_SPACINGS:
        for saturated, jet, fam in ((True, False, "saturated_bed"), (False, True, "overflow_jet"),
                                    (True, True, "saturated_jet")):  # fmt: skip
            out.append(
                Cell(
                    f"{fam}_dx{_mm(dx)}",
                    fam,
                    lambda d=dx, s=saturated, j=jet: (scour_scene(s, d, jet=j), None),
                    SCOUR_END,
                )
            )
    for c in out:
        c.ci = c.name in CI_CELLS
    return out


# -- energies ----------------------------------------------------------------------------------
def energies(sim):
    """(kinetic, potential, elastic) energy of the owned particles at the current time, J (per m in 2D).
    Call after sim.current_state() (whole-step velocities, stresses and pressures)."""
    from solver.materials import Phase

    ps = sim.particles
    n = ps.n_owned
    m = ps["mass"][:n]
    ke = 0.5 * float(np.sum(m * np.sum(ps["v"][:n] ** 2, axis=1)))
    pe = -float(np.sum(m * (ps["x"][:n] @ sim.gravity)))
    mats = sim.plan.materials
    mat = ps["material"][:n]
    phase = mats.phase[mat]
    rho = ps["rho"][:n]
    el = 0.0
    soil = phase == Phase.SOIL
    if soil.any():  # linear elastic energy density p^2 / 2K + J2 / 2G (seed eqs. 13, 17)
        s = ps["stress_dev"][:n][soil]
        j2 = 0.5 * np.sum(s[:, :3] ** 2, axis=1) + np.sum(s[:, 3:] ** 2, axis=1)
        k = mats.soil.bulk[mat[soil]]
        g = mats.soil.shear[mat[soil]]
        p = ps["mean_stress"][:n][soil]
        el += float(np.sum(m[soil] / rho[soil] * (p**2 / (2 * k) + j2 / (2 * g))))
    water = phase == Phase.WATER
    if water.any():  # Tait (seed eq. 9): e(rho) = int_rho0^rho p / rho'^2 drho' >= 0
        mw = mat[water]
        r0, b, gam = mats.rho0[mw], mats.eos_b[mw], mats.eos_exponent[mw]
        rw = rho[water]

        def prim(r):
            return b * ((r / r0) ** gam / (r * (gam - 1.0)) + 1.0 / r)

        el += float(np.sum(m[water] * (prim(rw) - prim(r0))))
    return ke, pe, el


def energy_factor(scene):
    """F = 1 / (1 - (omega dt)^2 / 4) with omega dt <= 2 C_s h / dx (module docstring)."""
    wdt = 2.0 * scene.numerics.cfl.sound * scene.h / scene.scene.spacing
    return 1.0 / (1.0 - 0.25 * wdt * wdt)


def estimated_cost(cell):
    """Particle-steps at the sound-speed time step (0 for placeholders): for ordering runs."""
    if cell.placeholder:
        return 0.0
    from solver.plan import build_plan

    scene, _ = cell.build()
    plan = build_plan(scene)
    dt = min(c.constant_dt for c in plan.constraints if c.constant_dt is not None)
    area = sum((b.max[0] - b.min[0]) * (b.max[1] - b.min[1]) for b in scene.blocks)
    area *= 2 if any(b.saturated for b in scene.blocks) else 1  # pore water: a second lattice
    area += sum(0.1 * 0.25 for _ in scene.inlets)  # the water an overflow keeps on the layer (about)
    return area / scene.scene.spacing**2 * cell.end_time / dt


# -- running -----------------------------------------------------------------------------------
class InflowWork:
    """W_in(t) of the inlets of a run (module docstring): layer energies plus the buffer's flow work."""

    def __init__(self, sim):
        from solver.physics.inlet import Inlets

        self.inlets = sim.plan.term(Inlets)
        self.released0 = [z.released for z in self.inlets.zones] if self.inlets else []
        self.flow_work = 0.0
        self.g = np.asarray(sim.gravity, float)

    def step(self, sim, dt):
        if self.inlets is None:
            return
        ps = sim.particles
        n = ps.n_owned
        free = ps["inlet_buffer"][:n] < 0
        for z in self.inlets.zones:
            r = ps["x"][:n] - z.origin
            xi = (r @ z.n) / z.cos
            s = r @ z.a
            ahead = free & (xi > 0) & (xi < z.ds) & (s > 0) & (s < z.width)
            if ahead.any():
                p = float(np.mean(np.maximum(ps["p"][:n][ahead], 0.0)))
                self.flow_work += p * z.speed * z.cos * z.width * dt

    def total(self):
        if self.inlets is None:
            return 0.0
        out = self.flow_work
        for z, r0 in zip(self.inlets.zones, self.released0):
            x = z.origin + z.lateral()[:, None] * z.a
            per_layer = z.mass * float(np.sum(0.5 * z.speed**2 - x @ self.g))
            out += (z.released - r0) * per_layer
        return out


def run_cell(cell, inflow_work=0.0):
    """Run one cell; never raises on a blow-up (the result says what happened)."""
    from solver.errors import BlowUpError
    from solver.output.balance import VolumeLedger
    from solver.physics.bodies import BodyGuard
    from solver.simulation import Simulation

    res = CellResult(cell.name, cell.family, end_time=cell.end_time)
    if cell.placeholder:
        res.status = f"skipped: {cell.placeholder}"
        return res
    scene, setup = cell.build()
    res.spacing = scene.scene.spacing
    res.energy_factor = f = energy_factor(scene)
    sim = Simulation(scene)
    if setup is not None:
        setup(sim)
    res.particles = sim.comm.sum(sim.particles.n_owned)
    sim.current_state()
    ke0, pe0, el0 = energies(sim)
    ratio = [0.0]
    inflow = InflowWork(sim)
    ledger = VolumeLedger(sim, sim.comm)
    last_t = [sim.t]

    def check(s, force=False):
        inflow.step(s, s.t - last_t[0])
        last_t[0] = s.t
        if s.step_count % ENERGY_EVERY and not force:
            return
        s.current_state()
        ke, pe, _ = energies(s)
        available = ke0 + pe0 - pe + el0 + inflow_work + inflow.total()
        ratio[0] = max(ratio[0], ke / (f * available) if available > 0 else (math.inf if ke > 0 else 0.0))

    t0, c0 = time.perf_counter(), time.process_time()
    try:
        sim.advance_to(cell.end_time, on_step=check)
        res.status = "completed"
        check(sim, force=True)  # the final state too, whatever the step count
    except BlowUpError as exc:
        res.status = f"blow-up at t = {exc.time:.4g} s (step {exc.step}): {exc.what} ({exc.where})"
    res.wall_s = time.perf_counter() - t0
    res.cpu_s = time.process_time() - c0
    res.load = os.getloadavg()[0]
    res.steps, res.t_reached = sim.step_count, sim.t
    res.wall_reflections = int(sim.wall_reflections)
    res.deepest_penetration = float(sim.deepest_penetration)
    res.energy_ratio = ratio[0]
    report = ledger.report(sim, sim.comm)
    res.body_leaks = int(report.get("body_leaks", 0))
    balance = report.get("volume_balance", {}).get("materials", {})
    res.balance_ok = all(m["within_one_particle"] for m in balance.values())
    if guard := sim.plan.term(BodyGuard):
        res.notes.append(f"body leaks {guard.leaks}")
    if balance:
        worst = max(abs(m["residual"]) for m in balance.values()) / res.spacing**2
        res.notes.append(f"balance residual {worst:.2g} particle volumes")
    return res


FIELDS = (
    "name",
    "family",
    "outcome",
    "particles",
    "steps",
    "t_reached",
    "end_time",
    "wall_reflections",
    "deepest_penetration_dx",
    "energy_ratio",
    "body_leaks",
    "balance_ok",
    "wall_s",
    "cpu_s",
    "load",
    "status",
)


def _row(r):
    outcome = "pass" if r.ok else ("skipped" if r.status.startswith("skipped") else "FAIL")
    return {
        "name": r.name,
        "family": r.family,
        "outcome": outcome,
        "particles": r.particles,
        "steps": r.steps,
        "t_reached": f"{r.t_reached:.4f}",
        "end_time": f"{r.end_time:g}",
        "wall_reflections": r.wall_reflections,
        "deepest_penetration_dx": f"{r.deepest_penetration / r.spacing:.3g}" if r.spacing else "",
        "energy_ratio": f"{r.energy_ratio:.3g}",
        "body_leaks": r.body_leaks,
        "balance_ok": r.balance_ok,
        "wall_s": f"{r.wall_s:.1f}",
        "cpu_s": f"{r.cpu_s:.1f}",
        "load": f"{r.load:.1f}",
        "status": r.status,
    }


def write_table(results, out=OUT, stem="matrix", header="", rows=None):
    out.mkdir(parents=True, exist_ok=True)
    rows = rows if rows is not None else [_row(r) for r in results]
    with open(out / f"{stem}.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, FIELDS)
        w.writeheader()
        w.writerows(rows)
    lines = [
        "# Stability matrix",
        "",
        "Written by `python -m verification.stability_matrix` (see its docstring for the cells and checks).",
        "Outcome `pass`: completed, deepest wall penetration < dx/2, kinetic energy within its bound",
        "(energy_ratio <= 1). Wall and CPU time: stepping, one process; `load` is the 1-min load average",
        "at the cell's end (other jobs shared the 2 cores).",
        "",
    ]
    if header:
        lines += [header, ""]
    lines.append("| " + " | ".join(FIELDS) + " |")
    lines.append("|" + "---|" * len(FIELDS))
    for r in rows:
        lines.append("| " + " | ".join(str(r[k]).replace("|", "/") for k in FIELDS) + " |")
    (out / f"{stem}.md").write_text("\n".join(lines) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.stability_matrix", description=__doc__)
    ap.add_argument("--ci", action="store_true", help="only the CI subset")
    ap.add_argument("--only", action="append", default=[], help="cells whose name contains this (repeatable)")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--stem", default="matrix")
    ap.add_argument(
        "--merge",
        nargs="+",
        type=Path,
        help="only merge these CSV tables (runs split over processes) into --out",
    )
    args = ap.parse_args(argv)
    if args.merge:
        rows = {}
        for path in args.merge:
            with open(path, newline="") as fh:
                rows.update({r["name"]: r for r in csv.DictReader(fh)})
        order = {c.name: estimated_cost(c) for c in cells()}
        write_table(
            [], args.out, args.stem, rows=sorted(rows.values(), key=lambda r: order.get(r["name"], 0.0))
        )
        return 0
    chosen = [
        c for c in cells() if (not args.ci or c.ci) and (not args.only or any(s in c.name for s in args.only))
    ]
    chosen.sort(key=estimated_cost)  # cheapest first: a run cut short still covers the most cells
    results = []
    for c in chosen:
        r = run_cell(c)
        results.append(r)
        print(
            f"{r.name}: {_row(r)['outcome']} ({r.status}; {r.wall_s:.1f} s wall, load {r.load:.1f})",
            flush=True,
        )
        write_table(results, args.out, args.stem)  # after every cell: a long run keeps what it has
    return 0 if all(r.ok or r.status.startswith("skipped") for r in results) else 1


if __name__ == "__main__":
    raise SystemExit(main())
