"""SPH side of the sheet-pile seepage cross-check against OpenFOAM (issue 10, item 5;
docs/verification_seepage.md case 5, docs/seepage.md "Against OpenFOAM").

The reference is reference_cases/openfoam_seepage_2d run with a pile W = 40 mm thick
(`python -m reference_cases.openfoam_seepage_2d.run --pile-thickness 0.04`, data/pile_w40mm/):
Laplace's equation for the head on T/10-T/80 meshes, Q/(kH) = 0.40303 by Richardson
extrapolation (observed order 1.3, GCI 0.19 %), and heads along two lines. Why a thick pile:
OpenFOAM's pile is a zero-thickness baffle; SPH needs fixed particles at least 3 dx thick (the
water on one side must not reach the far face's particles, whose pressure is the other side's:
inside 2h = 2.6 dx a 2 dx pile leaks, Q/Q_ref 0.75), and a pile of w adds a channel w long under
its tip in series with the thin pile's flow net: Q/(kH) ~ 1/(2 + w/(T - S)), 0.43 for 3 cm (the
first runs measured 0.43 against the thin pile's 0.50 and took it for an SPH error). With the
same 40 mm pile in both codes (4 dx at 10 mm, 8 dx at 5 mm) the comparison is like for like.

Geometry as the reference, shifted so the domain starts at x = 0: a fixed, saturated sand layer
T = 0.2 m thick on the impermeable floor, x in [0, 2 HALF] (free-slip sides), the pile centred at
XP = HALF from T - S up to above the upstream water, and water on the ground, 0.10 m deep
upstream (head H_UP above the base) and 0.05 m downstream (H_DOWN).

Formulation: "seed". The ponds are free water that flows into the pores; the seed form's water
is at its true density everywhere, and its steady state is Laplace's equation for the head
(docs/seepage.md: n v_w = -k grad h with div v_w = 0), the reference's equation. The mixture form
is not compared: its pore water keeps n rho_w as its equation-of-state reference, so free water
entering the pores reads a spurious tension (seepage_darcy.py, "Why a draining column"). A
first try with the ponds as fixed, saturated gravel (same n, k_pond = 100 k) ran at 10 mm but its
pond heads sat 10 and 7 mm low and Q/(k dH) oscillated between 0.38 and 0.62 (docs/seepage.md).

Numerics: the defaults (delta-SPH density diffusion on rho - rho^H), with the seed's pore water
out of the diffusion (solver/physics/density_diffusion.py, `pore_label`): in a seepage flow the
pressure is not hydrostatic, so the diffusion moves mass without moving particles, an extra
conductivity k_delta ~ delta h g / c = 6.4e-4 m/s at dx = 10 mm, the order of k = 1e-3 (the first
runs, with it: Q 0.72 of the thin-pile reference, 0.90 of the thick one). The ponds keep it: with
no diffusion at all the ponds' pressure noise grows and their heads swing by +-1 cm after 0.5 s
at 5 mm.

The pile: fixed water particles (a `[[bodies]]` polygon, image particles, was tried: its corner
images near the fixed skeleton gave head errors of order H along the face). A fixed-particle wall
holds the pressure its density gives it, so the case sets it after every step from the water on
its own side (PileWallPressure: Adami et al. 2012's extrapolation), and leaves the pile's
particles out of the density diffusion too (pore_label = n), which would otherwise carry the
upstream pressure through the pile. Below the ground the same hook gives them the velocity of that
water mirrored across the pile's nearest face (PILE_VELOCITY; the free-slip image velocity the
solver's own walls give the continuity): with v = 0 the pore water's continuity next to the tip's
corners was a spurious mass source whose alternating part, which the SPH pressure gradient does not
see and nothing in the pore water damps, grew all run (the line x = w/2 + T/10's error, 0.089 at 10 mm
at 1 s; with the mirror 0.041; docs/seepage.md, case 5).

The pore water's odd-even mode (numerics.pore_density_diffusion = "antuono", PORE_DIFFUSION;
solver/physics/seepage_pore_diffusion.py, docs/seepage.md): out of the density diffusion, nothing damped the
pore pressure's particle-to-particle alternation, which SPH's gradient does not see; without the term it
grew all run where pond water enters the bed upstream and under the tip (its largest local amplitude
0.05 -> 0.17 dH over 1 s at 10 mm; the line's error 0.024 -> 0.042 at 5 mm). Antuono et al.'s (2010)
corrected delta-SPH among pore water damps it and is blind to the smooth (quadratic) head field.

The pore water's pressure force (numerics.pore_pressure_gradient = "corrected",
solver/physics/pore_pressure_gradient.py): with the symmetric form (seed eq. 7) Q was not steady, it
fell by ~3 % of the reference per 0.5 s at 10 and 5 mm, because that form's zeroth-order term
2 p_a sum_b V_b grad W_ab, zero on a lattice, grows as the pore water drifts off its lattice and is
multiplied by the full (mostly hydrostatic) pressure (docs/seepage.md, case 5). The corrected difference
form (Randles & Libersky 1996; Bonet & Lok 1999) is exact for a linear pressure on any arrangement:
Q is steady (PRESSURE_GRADIENT; the symmetric runs stay reproducible with pressure_gradient="symmetric").

The skeleton in the pile (PILE_SKELETON): the sand's particles stop at the pile's faces, so the pore
water in the first row beside the pile and under its tip sees a cut skeleton support (Shepard sum
sum_b V_b W_ab = 0.76-0.82 instead of 1.00 at h = 1.3 dx) and feels 18-24 % less drag there: a
channel of higher conductivity along the faces and under the tip, where the flow is fastest
(measured on the held lattice: Q/(k dH) 0.4227 without, 0.4106 with). The skeleton is at rest, as the
pile is, so the case continues it into the pile below the ground with fixed soil particles at rest,
the dummy-particle idea of Adami, Hu & Adams (2012) (wall particles carry the wall's state so that the
fluid's sums near the wall have a full support), applied to the skeleton: the drag sum of the pore
water beside the pile is then complete (0.9999). These particles take no part in anything else (the
skeleton is fixed; the seed form has no buoyancy pair).

Start: the pore water at the reference head, p = gamma_w (h_ref(x, y) - y), rho = rho_w(p),
m = rho dx^2; the ponds hydrostatic. This starts the run near the steady state; what remains is
SPH's own approach to its steady state (with the corrected force Q/(k dH) is within 0.4 % of its final
value from 0.1 s at 10 mm; docs/seepage.md, case 5).

Observables (averaged over the last half of the run):
  * Q = n <v_x> (T - S) of the pore water under the pile (|x - XP| < W/2, y < T - S);
  * the heads the ponds impose (first water row above the ground, >= 0.1 m from the pile), and
    Q / (k dH) with dH their difference: the problem is linear in H, so this takes the SPH free
    surface's head deficit (~dx/2 of head at the ponds' top) out of the comparison of the seepage;
  * heads along the row nearest the floor and the column nearest x = XP + W/2 + T/10 (the reference's
    "base" and "downstream_x_T_over_10" lines), normalised by the SPH pond heads, against the
    reference's: max |(h - h_down)/dH - (h_ref - H_DOWN)/H|, with h = y + Pi(p) / g the weakly
    compressible water's own head (barotropic_head: what its still water holds uniform and its
    Darcy flow is driven by); y + p / gamma_w carries the compressibility's excess g d^2 / (2 c^2),
    0.014-0.019 dH along the base at any dx (reported beside it, "_h").

Tolerances: TOLERANCES below, with their source.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from . import seepage_common as sc
from .common import RESULTS, CaseResult, Check, machine_load, reference_case_dir, save_figure, save_study

T, S = 0.2, 0.1  # layer thickness, pile depth below the ground (m)
W = 0.04  # pile thickness (m), the same in the reference
HALF = 0.6  # half the layer length (m)
H_UP, H_DOWN = 0.30, 0.25  # heads above the base (m)
K, POROSITY = 1e-3, 0.4
K_POND = 100 * K  # the mixture's gravel ponds
E_FIXED = 1.0e5  # the fixed skeleton's stiffness plays no part (as seepage_darcy.py)
DIFFUSION = "fourtakas"  # the default; pore water left out (see the module docstring)
PILE_SKELETON = True  # fixed soil particles inside the pile below the ground (module docstring)
PRESSURE_GRADIENT = "corrected"  # the pore water's pressure force (module docstring)
PORE_DIFFUSION = "antuono"  # numerics.pore_density_diffusion: the odd-even mode damped (module docstring)
PILE_VELOCITY = True  # the pile below the ground carries the mirrored pore-water velocity (PileWallPressure)
PILE = "particles"  # "body" (image particles) or "particles" (fixed water): see the module docstring
T_END = 1.0  # s: Q is steady from 0.2 s (the pore water's storage time (2T)^2 / c_v ~ 0.02 s)
DEFAULT_RESOLUTION = 20  # dx = T / 20 = 10 mm
STUDY_RESOLUTIONS = (20, 40)  # 10 and 5 mm (the pile 4 and 8 dx thick)
QUICK_RESOLUTION = 20
OUT = RESULTS / "seepage_sheet_pile"
# Tolerances, each with its source (docs/seepage.md, "Against OpenFOAM"):
#  * Q: issue 10's 2 % for a steady Darcy discharge (item 4, "q = k i within 2 %": the same physics),
#    plus the reference's GCI (0.19 %); the same 2 % bounds Q's change across the averaging window
#    (the reference is steady, so a comparison whose result moves by more than its tolerance within
#    the window is not a comparison of steady states);
#  * heads (normalised by dH): h / T, the support truncation at the floor and the ground over the
#    layer (the error analysis of seepage_bed_at_rest.py: h/D on its profiles): 0.065 at 10 mm.
Q_TOLERANCE = 0.02
Q_SOURCE = "issue 10's 2 % for a steady Darcy discharge, plus the reference's GCI"
# The CI sample (tests/test_seepage_sheet_pile.py: 10 mm, 0.3 s, means over 0.15-0.3 s) is held to the
# same Q_TOLERANCE: with the corrected pore-pressure force Q is steady from 0.1 s (docs/seepage.md, case 5).
# Documented shortfalls at the default resolution (docs/seepage.md): shown as known by the nightly.
# The line x = w/2 + T/10 was a known failure until the pile carried the mirrored velocity (PILE_VELOCITY):
# 0.085 / 0.048 at 10 / 5 mm, then 0.039 / 0.030 (tolerances 0.065 / 0.0325), growing at 5 mm (0.024 -> 0.042)
# with the pore water's odd-even mode; with the pore diffusion (PORE_DIFFUSION) and the barotropic head
# (measure), 0.018 / 0.0077 (docs/seepage.md, case 5).
KNOWN_FAILURES: dict[str, str] = {}
NIGHTLY_NOTE = "10 mm (default) and the 10/5 mm resolution study, 1 s each (5 mm: ~250 s CPU)"
REFERENCE = reference_case_dir("openfoam_seepage_2d") / "data" / "pile_w40mm"
Q_REF_SOURCE = "OpenFOAM laplacianFoam, pile 40 mm, Richardson limit of T/20-T/40-T/80 (manifest.json)"


def reference_discharge():
    """(Q/(kH) of the reference, its relative uncertainty): the Richardson limit of the Laplace
    meshes and Roache's GCI on the finest (manifest.json, mesh_study)."""
    study = json.loads((REFERENCE / "manifest.json").read_text())["mesh_study"]["richardson"]
    return study["extrapolated_Q_over_kH"], study["gci_fine_rel"]


def reference_head():
    """h_ref(x, y) with x in the reference's frame (pile centred at 0): bilinear in head_field.csv."""
    rows = np.loadtxt(REFERENCE / "head_field.csv", delimiter=",", comments="#", skiprows=2)
    xs, ys = np.unique(rows[:, 0]), np.unique(rows[:, 1])
    grid = np.full((len(ys), len(xs)), np.nan)
    grid[np.searchsorted(ys, rows[:, 1]), np.searchsorted(xs, rows[:, 0])] = rows[:, 2]

    def at(x, y):
        fx = np.interp(np.asarray(x), xs, np.arange(len(xs)))
        fy = np.interp(np.asarray(y), ys, np.arange(len(ys)))
        i0 = np.clip(np.floor(fx).astype(int), 0, len(xs) - 2)
        j0 = np.clip(np.floor(fy).astype(int), 0, len(ys) - 2)
        tx, ty = fx - i0, fy - j0
        return (grid[j0, i0] * (1 - tx) * (1 - ty) + grid[j0, i0 + 1] * tx * (1 - ty)
                + grid[j0 + 1, i0] * (1 - tx) * ty + grid[j0 + 1, i0 + 1] * tx * ty)  # fmt: skip

    return at


def reference_line(line):
    """(x in the reference's frame, y, head) of the T/80 Laplace run along one head line."""
    import csv

    with open(REFERENCE / "head_lines.csv") as fh:
        rows = [r for r in csv.reader(fh) if not r[0].startswith("#")][1:]
    sel = [r for r in rows if r[0] == "laplace" and r[1] == "80" and r[2] == line]
    return tuple(np.array([float(r[i]) for r in sel]) for i in (3, 4, 5))


def scene(
    resolution, t_end=T_END, formulation="seed", diffusion=DIFFUSION, pile=PILE, pile_skeleton=PILE_SKELETON,
    pressure_gradient=PRESSURE_GRADIENT, pore_diffusion=PORE_DIFFUSION,
):  # fmt: skip
    dx = T / resolution
    p0, p1 = HALF - 0.5 * W, HALF + 0.5 * W  # the pile
    right = 2 * HALF
    top = H_UP + 0.02
    soil = {"shape": "rectangle", "fixed": True, "saturated": True, "material": "sand", "pore_water": "water"}
    blocks = [
        {**soil, "name": "lower_up", "min": [0.0, 0.0], "max": [HALF, T - S], "water_table": H_UP},
        {**soil, "name": "lower_down", "min": [HALF, 0.0], "max": [right, T - S], "water_table": H_DOWN},
        {**soil, "name": "upper_up", "min": [0.0, T - S], "max": [p0, T], "water_table": H_UP},
        {**soil, "name": "upper_down", "min": [p1, T - S], "max": [right, T], "water_table": H_DOWN},
    ]
    mats = {"water": sc.WATER, "sand": sc.sand(POROSITY, permeability=K, youngs_modulus=E_FIXED)}
    bodies = None
    if pile == "body":  # a rigid body: image particles across its faces (solver/physics/bodies.py)
        bodies = [{"name": "pile", "vertices": [[p0, T - S], [p1, T - S], [p1, top], [p0, top]]}]
    else:  # fixed water particles
        blocks.append({"name": "pile", "material": "pile", "shape": "rectangle", "fixed": True,
                       "min": [p0, T - S], "max": [p1, top]})  # fmt: skip
        mats["pile"] = sc.WATER
    if formulation == "seed":
        blocks += [
            {"name": "pond_up", "material": "water", "shape": "rectangle", "min": [0.0, T], "max": [p0, H_UP],
             "hydrostatic": True},
            {"name": "pond_down", "material": "water", "shape": "rectangle", "min": [p1, T],
             "max": [right, H_DOWN], "hydrostatic": True},
        ]  # fmt: skip
    else:
        mats["gravel"] = sc.sand(POROSITY, permeability=K_POND, youngs_modulus=E_FIXED)
        pond = {**soil, "material": "gravel"}
        blocks += [
            {**pond, "name": "pond_up", "min": [0.0, T], "max": [p0, H_UP], "water_table": H_UP},
            {**pond, "name": "pond_down", "min": [p1, T], "max": [right, H_DOWN], "water_table": H_DOWN},
        ]
    walls = {"x_min": "free_slip", "x_max": "free_slip", "y_min": "free_slip"}
    args = ("seepage_sheet_pile", dx, t_end, [right, top + 0.02], mats)
    rest = dict(
        formulation=formulation, walls=walls, bodies=bodies, density_diffusion=diffusion,
        pore_pressure_gradient=pressure_gradient, pore_density_diffusion=pore_diffusion,
    )  # fmt: skip
    built = sc.scene(*args, blocks, **rest)
    if pile and pile_skeleton and pile == "particles":
        # the skeleton continued into the pile below the ground, at rest (module docstring): fixed soil
        # particles at the pile's own fixed water particles' sites. Scene files refuse blocks that share
        # sites (two particles of one phase there would double its density); these are of two phases
        # (the seed's saturated blocks overlap so too), so the block is added after the check.
        skeleton = {"name": "pile_skeleton", "material": "sand", "shape": "rectangle", "fixed": True,
                    "min": [p0, T - S], "max": [p1, T]}  # fmt: skip
        alone = sc.scene(*args, [b for b in blocks if b["name"] != "pile"] + [skeleton], **rest)
        built = built.model_copy(update={"blocks": list(built.blocks) + [alone.blocks[-1]]})
    return built


def start_at_reference(sim, formulation):
    """Pore water (water below the ground) at the reference head: p, rho_w(p) (times n for the
    mixture's pore water), m = rho dx^2."""
    from solver.materials import tait_density

    ps, mats = sim.particles, sim.plan.materials
    dx = sim.scene.scene.spacing
    wa = sc.water_rows(sim)
    wa = wa[~ps["fixed"][wa]]
    pore = wa[ps["x"][wa, 1] < T]
    h_ref = reference_head()
    x, y = ps["x"][pore, 0] - HALF, ps["x"][pore, 1]
    p = np.maximum(sc.GAMMA_W * (h_ref(x, y) - y), 0.0)
    kw = mats.names.index("water")
    rho = tait_density(p, mats.rho0[kw], mats.eos_b[kw], mats.eos_exponent[kw])
    if formulation == "mixture":
        rho = POROSITY * rho
    if "pore_label" in ps:  # the pile's fixed water out of the density diffusion (module docstring)
        fixed = sc.water_rows(sim)
        ps["pore_label"][fixed[ps["fixed"][fixed]]] = POROSITY
    ps["p"][pore] = p
    ps["rho"][pore] = rho
    ps["mass"][pore] = rho * dx**2
    if "rho_half" in ps:
        ps["rho_half"][pore] = rho


class PileWallPressure:
    """The pile's fixed water particles get, after every step, the pressure of the water on their
    own side of the pile extrapolated to them (Adami, Hu & Adams 2012, J. Comput. Phys. 231:7057,
    eq. 27, without the wall's acceleration): p_w = sum_f (p_f + rho_f g (y_f - y_w)) W_wf / sum_f W_wf,
    and rho = rho_w(p_w) (Tait inverse). Why: a fixed-particle wall holds whatever pressure its
    density gives it. With the density diffusion the pile's particles diffuse pressure from one side
    to the other (a leak: Q -10 %); without it they stay at their start pressure (0: the pore water
    next to the faces is pulled into the pile, its head 0.1-0.2 H low along x = w/2 + T/10). Each
    side's particles see only that side's water, so no pressure crosses the pile. The skeleton is
    fixed and the pore water moves by < 0.1 mm over a run, so the pairs and weights are found once
    (by particle id: rows are re-sorted at rebuilds). Serial runs only (owned rows).

    Below the ground (`mirror_velocity`) they also get the velocity of that water, mirrored across the
    pile's nearest face (v_w = v_f - 2 (v_f . n) n; at the tip's corners n is the bisector): the
    free-slip image velocity the solver's own walls give the continuity (FluidRates.slip_image_velocity).
    Why: with v_w = 0 the continuity sum_j m_j (v_i - v_j) . grad W_ij of the pore water flowing past
    the tip's corners, where the faces' kernel sums are not normal to the flow, is a spurious source of
    mass. Its row-to-row, column-to-column alternating part is a mode the SPH pressure gradient does not
    see (p_j - p_i is even in j on a lattice), and the pore water, out of the density diffusion, has
    nothing else that damps it: it grew all run long, an alternation of +-0.1 dH along the row at the
    tip's level (the line's known failure; docs/seepage.md, case 5). The particles stay fixed: the
    drift the velocity gives them within a step (< 1e-6 dx) is undone after each step."""

    def __init__(self, sim, mirror_velocity=True):
        from solver.kernels import cubic_spline_normalisation, cubic_spline_w
        from solver.materials import tait_density

        ps, mats = sim.particles, sim.plan.materials
        n = ps.n_owned
        water = sc.water_rows(sim)
        wall = water[ps["fixed"][water]]
        free = water[~ps["fixed"][water]]
        h = sim.h
        norm = cubic_spline_normalisation(2, h)
        xw, xf = ps["x"][wall], ps["x"][free]
        side_w, side_f = np.sign(xw[:, 0] - HALF), np.sign(xf[:, 0] - HALF)
        rows, cols, weights = [], [], []
        for a in range(len(wall)):
            d = np.hypot(*(xf - xw[a]).T)
            near = np.flatnonzero((d < 2.0 * h) & (side_f == side_w[a]))
            rows += [a] * len(near)
            cols += near.tolist()
            weights += [cubic_spline_w(r, h, norm) for r in d[near]]
        self.pair_wall, self.pair_free = np.array(rows, int), np.array(cols, int)
        self.weight = np.array(weights)
        self.wall_id, self.free_id = ps["id"][wall].copy(), ps["id"][free].copy()
        self.y_wall = xw[:, 1].copy()
        self.sum_w = np.bincount(self.pair_wall, self.weight, len(wall))
        self.inverse = np.empty(int(ps["id"][:n].max()) + 1, int)
        k = mats.names.index("pile")
        self.eos = (mats.rho0[k], mats.eos_b[k], mats.eos_exponent[k])
        self.tait_density = tait_density
        self.x_wall = xw.copy()
        self.normal = pile_normals(xw) if mirror_velocity else None
        self(sim)

    def __call__(self, sim):
        ps = sim.particles
        n = ps.n_owned
        self.inverse[ps["id"][:n]] = np.arange(n)
        wall, free = self.inverse[self.wall_id], self.inverse[self.free_id]
        f = free[self.pair_free]
        value = ps["p"][f] + ps["rho"][f] * sc.G * (ps["x"][f, 1] - self.y_wall[self.pair_wall])
        p = np.zeros(len(wall))
        has = self.sum_w > 0
        p[has] = np.bincount(self.pair_wall, self.weight * value, len(wall))[has] / self.sum_w[has]
        p = np.maximum(p, 0.0)
        rho = self.tait_density(p, *self.eos)
        ps["p"][wall], ps["rho"][wall] = p, rho
        if "rho_half" in ps:
            ps["rho_half"][wall] = rho
        if self.normal is not None:
            ps["x"][wall] = self.x_wall
            v = np.zeros((len(wall), 2))
            for axis in (0, 1):
                v[has, axis] = np.bincount(self.pair_wall, self.weight * ps["v"][f, axis], len(wall))[has]
            v[has] /= self.sum_w[has, None]
            v -= 2.0 * np.sum(v * self.normal, axis=1)[:, None] * self.normal
            v[self.x_wall[:, 1] > T] = 0.0
            ps["v"][wall] = ps["v_half"][wall] = v  # the leap-frog predicts v from v_half (acc = 0 here)


def pile_normals(xw):
    """Outward unit normal of the pile's face nearest to each of its particles below the ground (zero
    above it, where the pile stays a wall at rest for the ponds' free water): +-x on the sides, -y on the
    tip, the bisector where a particle is as near to the tip as to a side (the corners)."""
    d_side = 0.5 * W - np.abs(xw[:, 0] - HALF)
    d_tip = xw[:, 1] - (T - S)
    side = np.sign(xw[:, 0] - HALF)
    n = np.zeros_like(xw)
    tol = 1e-9
    on_side, on_tip = d_side < d_tip - tol, d_tip < d_side - tol
    corner = ~on_side & ~on_tip
    n[on_side, 0] = side[on_side]
    n[on_tip, 1] = -1.0
    n[corner] = np.stack([side[corner], -np.ones(corner.sum())], axis=1) / np.sqrt(2.0)
    n[xw[:, 1] > T] = 0.0
    return n


class HeldPoreWater:
    """Diagnostic (not the solver's physics): the pore water put back at its start positions after
    every step, so it keeps the skeleton's lattice (an Eulerian pore water). With the symmetric
    pressure force the Lagrangian pore water's small distortions made Q/(k dH) fall; held, it stopped
    falling, which located the drift (docs/seepage.md, case 5)."""

    def __init__(self, sim):
        ps = sim.particles
        n = ps.n_owned
        water = sc.water_rows(sim)
        water = water[~ps["fixed"][water]]
        pore = water[ps["x"][water, 1] < T]
        self.ids, self.x0 = ps["id"][pore].copy(), ps["x"][pore].copy()
        self.inverse = np.empty(int(ps["id"][:n].max()) + 1, int)

    def __call__(self, sim):
        ps = sim.particles
        n = ps.n_owned
        self.inverse[ps["id"][:n]] = np.arange(n)
        ps["x"][self.inverse[self.ids]] = self.x0


class HydrostaticPorePass:
    """Diagnostic (not the solver's physics; docs/seepage.md, case 5): while active, the water's own
    pressure pass (FluidRates) acts on the pore water (pore_label < 1, not fixed) as the symmetric form
    of p - P_h, P_h = gamma_w (Y0 - y), plus P_h's gradient as the symmetric form reads it on a lattice
    (kappa gamma_w / rho, upward): the hydrostatic part no longer multiplies the zeroth-order term
    sum_b V_b grad W that the pore water's distortion makes nonzero. Not momentum-conserving (the
    neighbours get no reaction): a test of the mechanism, not a fix. Use as a context manager around
    run_one(..., pressure_gradient="symmetric", pile_skeleton=False), the case as it was measured (it
    patches FluidRates.run)."""

    Y0 = 0.5 * (H_UP + H_DOWN)  # the mean head: p - P_h is then at most gamma_w dH / 2 in the pores

    def __enter__(self):
        from solver.physics import fluid_rates
        from solver.physics.seepage import lattice_gradient_normalisation

        self.module, self.original = fluid_rates, fluid_rates.FluidRates.run
        kappa, original, y0 = lattice_gradient_normalisation(2, 1.3), self.original, self.Y0

        def run(term, ctx):
            original(term, ctx)
            ps, nl = ctx.particles, ctx.neighbours(term)
            i = np.repeat(nl.targets, np.diff(nl.start))
            j = nl.index
            keep = (ps["pore_label"][i] < 1.0) & ~ps["fixed"][i]
            i, j = i[keep], j[keep]
            x, rho, m, acc = ps["x"], ps["rho"], ps["mass"], ps["acc"]
            p_h = sc.GAMMA_W * (y0 - x[:, 1])
            d = x[i] - x[j]
            r = np.hypot(d[:, 0], d[:, 1]) + 1e-300
            big_a, big_b = np.clip(2 - r / ctx.h, 0, None), np.clip(1 - r / ctx.h, 0, None)
            f = ctx.norm * (-0.5 * big_a**2 + 2 * big_b**2) / ctx.h / r
            coef = m[j] * (p_h[i] / rho[i] ** 2 + p_h[j] / rho[j] ** 2) * f
            for axis in (0, 1):
                acc[:, axis] += np.bincount(i, coef * d[:, axis], len(x))[: len(acc)]
            rows = np.unique(i)
            acc[rows, 1] += kappa * sc.GAMMA_W / rho[rows]

        fluid_rates.FluidRates.run = run
        return self

    def __exit__(self, *exc):
        self.module.FluidRates.run = self.original


def measure(sim):
    ps = sim.particles
    dx, h_ref = sim.scene.scene.spacing, reference_head()
    wa = sc.water_rows(sim)
    wa = wa[~ps["fixed"][wa]]
    x, y = ps["x"][wa, 0] - HALF, ps["x"][wa, 1]  # x in the reference's frame
    under = (np.abs(x) < 0.5 * W) & (y < T - S)
    q = POROSITY * float(ps["v"][wa][under, 0].mean()) * (T - S)
    head = y + ps["p"][wa] / sc.GAMMA_W
    # the heads the ponds impose: the first water row above the ground, away from the pile
    row = (y > T) & (y < T + dx) & (np.abs(x) > 0.1)
    h_up, h_down = float(head[row & (x < 0)].mean()), float(head[row & (x > 0)].mean())
    out = {"Q": q, "h_up": h_up, "h_down": h_down, "Q_over_kdH": q / (K * (h_up - h_down))}
    lines = {
        "base": y < dx,
        "downstream_x_T_over_10": (np.abs(x - (0.5 * W + T / 10)) < 0.5 * dx) & (y < T),
    }
    ref_norm = (h_ref(x, y) - H_DOWN) / (H_UP - H_DOWN)
    # the line checks compare the weakly compressible water's own head (barotropic_head), normalised by the
    # ponds' in the same measure; y + p / gamma_w ("_h") is reported beside it
    star = y + barotropic_head(sim.plan.materials, ps["p"][wa])
    s_up, s_down = float(star[row & (x < 0)].mean()), float(star[row & (x > 0)].mean())
    for name, sel in lines.items():
        norm = (star[sel] - s_down) / (s_up - s_down)
        out[name] = float(np.abs(norm - ref_norm[sel]).max())
        out[name + "_h"] = float(np.abs((head[sel] - h_down) / (h_up - h_down) - ref_norm[sel]).max())
        order = np.argsort(x[sel] if name == "base" else y[sel])
        out[name + "_profile"] = (x[sel][order], y[sel][order], norm[order])
    return out


def barotropic_head(materials, p):
    """Pi(p) / g, Pi(p) = int_0^p dp' / rho(p') for the water's Tait law (seed eq. 9):
    Pi = (B / rho0) [(1 + p / B)^(1 - 1/gamma) - 1] / (1 - 1/gamma). For a barotropic fluid under gravity
    -grad p / rho + g = -g grad(y + Pi / g), so in still water y + Pi / g is uniform and in the pores the drag
    balances g grad(y + Pi / g) (Darcy's law in this head, with k rho / rho0). y + p / gamma_w instead holds
    the weak compressibility's excess, p / gamma_w - Pi / g = g d^2 / (2 c^2) at depth d below a free surface
    (c = 20 m/s: 1.1 mm at the upstream base, 0.019 dH), which does not shrink with dx (docs/seepage.md,
    case 5, "The base offset")."""
    k = materials.names.index("water")
    rho0, b, gamma = materials.rho0[k], materials.eos_b[k], materials.eos_exponent[k]
    a = 1.0 - 1.0 / gamma
    return (b / rho0) * ((1.0 + np.asarray(p) / b) ** a - 1.0) / a / sc.G


def run_one(
    resolution=DEFAULT_RESOLUTION, t_end=T_END, formulation="seed", diffusion=DIFFUSION, samples=21,
    pile=PILE, wall_pressure=True, held_pore_water=False, pile_skeleton=PILE_SKELETON,
    pressure_gradient=PRESSURE_GRADIENT, pile_velocity=PILE_VELOCITY, pore_diffusion=PORE_DIFFUSION,
):  # fmt: skip
    from solver.simulation import Simulation

    built = scene(
        resolution, t_end, formulation, diffusion, pile, pile_skeleton, pressure_gradient, pore_diffusion
    )
    sim = Simulation(built)
    start_at_reference(sim, formulation)
    hooks = [PileWallPressure(sim, pile_velocity)] if pile == "particles" and wall_pressure else []
    if held_pore_water:
        hooks.append(HeldPoreWater(sim))
    times = np.linspace(0.0, t_end, samples)
    obs, wall, cpu = sc.run_timed(sim, times, measure, on_step=lambda s: [f(s) for f in hooks])
    late = [o for t, o in zip(times, obs) if t >= 0.5 * t_end - 1e-12]
    scalars = [k for k in late[0] if not k.endswith("_profile")]
    res = {k: float(np.mean([o[k] for o in late])) for k in scalars}
    # time-averaged head profiles (the particles of a fixed skeleton barely move: same rows)
    for name in ("base", "downstream_x_T_over_10"):
        prof = [o[name + "_profile"] for o in late]
        n = min(len(p[2]) for p in prof)
        res[name + "_profile"] = (prof[-1][0][:n], prof[-1][1][:n], np.mean([p[2][:n] for p in prof], axis=0))
    q_ref, _ = reference_discharge()
    res.update(
        Q_over_reference=res["Q"] / (q_ref * K * (H_UP - H_DOWN)),
        Q_over_kdH_series=[o["Q_over_kdH"] for o in obs],
        Q_series=[o["Q"] for o in obs],
        h_up_series=[o["h_up"] for o in obs],
        h_down_series=[o["h_down"] for o in obs],
        line_series=[o["downstream_x_T_over_10"] for o in obs],
        t=times,
        particles=sim.particles.n_owned,
        steps=sim.step_count,
        wall=wall,
        cpu=cpu,
        dx=T / resolution,
        h=sim.h,
        formulation=formulation,
        diffusion=diffusion,
    )
    return res


def window_drift(t, series):
    """Change of a sampled series across the averaging window (the second half of the run)."""
    late = np.asarray(t) >= 0.5 * t[-1] - 1e-12
    return float(np.asarray(series)[late][-1] - np.asarray(series)[late][0])


def checks(r):
    """The checks of one run (seed form) against the reference (tolerances above)."""
    q_ref, gci = reference_discharge()
    drift = window_drift(r["t"], r["Q_over_kdH_series"]) / q_ref
    h_over_t = r["h"] / T
    head_src = f"h / T = {h_over_t:.3f}: support truncation at the floor and the ground (error analysis)"
    f = r["formulation"]
    return [
        Check(f"{f}: Q / (k dH) / reference - 1", r["Q_over_kdH"] / q_ref - 1.0, Q_TOLERANCE + gci, Q_SOURCE),
        Check(f"{f}: Q steady over the averaging window", drift, Q_TOLERANCE, Q_SOURCE),
        Check(f"{f}: base line, max normalised head error", r["base"], h_over_t, head_src),
        Check(f"{f}: line x = w/2 + T/10, max normalised head error", r["downstream_x_T_over_10"],
              h_over_t, head_src),
    ]  # fmt: skip


def run(resolution=DEFAULT_RESOLUTION, out_dir=None, formulations=("seed",)):
    runs = {f: run_one(resolution, formulation=f) for f in formulations}
    first = runs[formulations[0]]
    res = CaseResult(
        "seepage_sheet_pile",
        resolution,
        first["particles"],
        sum(r["steps"] for r in runs.values()),
        sum(r["wall"] for r in runs.values()),
        runs,
        cpu_time=sum(r["cpu"] for r in runs.values()),
    )
    q_ref, gci = reference_discharge()
    for f, r in runs.items():
        res.checks += checks(r)
        res.notes.append(
            f"{f}: Q = {r['Q']:.4g} m2/s = {r['Q_over_reference']:.4f} of the reference's at "
            f"H = {H_UP - H_DOWN:g} m; "
            f"pond heads {r['h_up']:.5f} / {r['h_down']:.5f} m; Q/(k dH) = {r['Q_over_kdH']:.4f} against "
            f"{q_ref:.5f} +- {100 * gci:.2f} % ({Q_REF_SOURCE}); {r['steps']} steps, {r['wall']:.1f} s wall, "
            f"{r['cpu']:.1f} s CPU"
        )  # fmt: skip
    if out_dir is not None:
        res.figure = figure(runs, Path(out_dir) / f"seepage_sheet_pile_r{resolution}.png")
    return res


def figure(runs, path):
    """Q/(k dH) over time, and the normalised heads along the two lines against the reference."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    q_ref, gci = reference_discharge()
    fig, axs = plt.subplots(1, 3, figsize=(14, 4))
    axs[0].axhline(q_ref, color="k", label=f"OpenFOAM (40 mm pile) {q_ref:.4f}")
    for (label, r), mark in zip(runs.items(), "osd^v"):
        axs[0].plot(r["t"][1:], r["Q_over_kdH_series"][1:], mark + "-", ms=4, label=f"SPH {label}")
        x, y, hn = r["base_profile"]
        axs[1].plot(x, hn, mark, ms=3, mfc="none", label=f"SPH {label}")
        x, y, hn = r["downstream_x_T_over_10_profile"]
        axs[2].plot(hn, y, mark, ms=3, mfc="none", label=f"SPH {label}")
    xr, _, hr = reference_line("base")
    axs[1].plot(xr, (hr - H_DOWN) / (H_UP - H_DOWN), "k-", label="OpenFOAM T/80")
    _, yr, hr = reference_line("downstream_x_T_over_10")
    axs[2].plot((hr - H_DOWN) / (H_UP - H_DOWN), yr, "k-", label="OpenFOAM T/80")
    axs[0].set(xlabel="t (s)", ylabel="Q / (k dH)", title="discharge under the pile")
    axs[1].set(xlabel="x - x_pile (m)", ylabel="(h - h_down) / dH", title="head along the base")
    axs[2].set(
        xlabel="(h - h_down) / dH", ylabel="y (m)", title=f"head at x = w/2 + T/10 = {0.5 * W + T / 10:g} m"
    )
    for ax in axs:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return save_figure(fig, path)


def study(resolutions=STUDY_RESOLUTIONS, out_dir=OUT, formulations=("seed",)):
    rows, runs = [], {}
    q_ref, gci = reference_discharge()
    for res_ in resolutions:
        for f in formulations:
            r = run_one(res_, formulation=f)
            runs[f"{f}, dx = {1e3 * r['dx']:g} mm"] = r
            late = np.asarray(r["t"]) >= 0.5 * r["t"][-1] - 1e-12
            line_window = np.asarray(r["line_series"])[late][[0, -1]]
            rows.append(
                {
                    "resolution": res_, "formulation": f, "dx_mm": 1e3 * r["dx"], "particles": r["particles"],
                    "steps": r["steps"], "wall_time_s": r["wall"], "cpu_time_s": r["cpu"],
                    "t_end_s": float(r["t"][-1]),
                    "Q_over_kdH": r["Q_over_kdH"], "Q_error": r["Q_over_kdH"] / q_ref - 1.0,
                    "Q_drift_over_window": window_drift(r["t"], r["Q_over_kdH_series"]) / q_ref,
                    "Q_over_reference": r["Q_over_reference"], "h_up": r["h_up"], "h_down": r["h_down"],
                    "base_max_error": r["base"], "line_max_error": r["downstream_x_T_over_10"],
                    "base_error_y_plus_p_over_gamma_w": r["base_h"],
                    "line_error_y_plus_p_over_gamma_w": r["downstream_x_T_over_10_h"],
                    "line_error_window_start": line_window[0], "line_error_end": line_window[1],
                    "load_1min": os.getloadavg()[0],
                    "checks": "; ".join(f"{c.metric}: {'pass' if c.passed else 'FAIL'}" for c in checks(r)),
                }
            )  # fmt: skip
    note = (
        f"Stepping only, one process, NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}, "
        f"{machine_load()}. Reference Q/(kH) = {q_ref:.5f} +- {100 * gci:.2f} % ({Q_REF_SOURCE}).\n"
        "Reproduce: `NUMBA_NUM_THREADS=1 python -m verification.seepage_sheet_pile --study`"
    )
    save_study(rows, out_dir, "resolution_study", note)
    figure(runs, Path(out_dir) / "seepage_sheet_pile_study.png")
    return rows


def zeroth_order_diagnostic(resolution=DEFAULT_RESOLUTION, times=(0.25, 0.5, 1.0)):
    """Why Q drifted with the symmetric form (docs/seepage.md, case 5, "Still drifting after seep5"; run
    with the case as it was then: symmetric pressure force, no skeleton in the pile): over the pore
    water within 0.08 m of the pile and 0.04-0.16 m above the floor, the symmetric pressure pass's
    zeroth-order term |2 p_a sum_b V_b grad_a W_ab| (over all water neighbours; zero on a lattice)
    against the drag n gamma_w |v| / k, at t = 0 and `times`.
    Returns [(t, median, p90, drag median, drag p90)]."""
    from solver.kernels import cubic_spline_normalisation
    from solver.neighbors import CellGrid, CellList
    from solver.simulation import Simulation

    sim = Simulation(scene(resolution, max(times), pile_skeleton=False, pressure_gradient="symmetric"))
    start_at_reference(sim, "seed")
    hook = PileWallPressure(sim, mirror_velocity=False)
    h = sim.h
    norm = cubic_spline_normalisation(2, h)
    drag_c = POROSITY * sc.GAMMA_W / K

    def observe():
        ps = sim.particles
        wa = sc.water_rows(sim)
        x, vol, p, v = ps["x"][wa], ps["mass"][wa] / ps["rho"][wa], ps["p"][wa], ps["v"][wa]
        near = ~ps["fixed"][wa] & (np.abs(x[:, 0] - HALF) < 0.08) & (x[:, 1] > 0.04) & (x[:, 1] < 0.16)
        cells = CellList(CellGrid.covering(x.min(0) - 0.1, x.max(0) + 0.1, 2 * h, pad=2 * h))
        cells.bin(x, len(x))
        targets = np.flatnonzero(near).astype(np.int64)
        nl = cells.neighbour_list(x, targets, 2 * h)
        term = []
        for t, a in enumerate(targets):
            nb = nl.index[nl.start[t] : nl.start[t + 1]]
            d = x[a] - x[nb]
            r = np.linalg.norm(d, axis=1)
            big_a, big_b = np.clip(2 - r / h, 0, None), np.clip(1 - r / h, 0, None)
            f = norm * (-0.5 * big_a**2 + 2 * big_b**2) / h / r
            term.append(2 * p[a] * np.linalg.norm((vol[nb, None] * f[:, None] * d).sum(axis=0)))
        drag = drag_c * np.linalg.norm(v[targets], axis=1)
        return (sim.t, float(np.median(term)), float(np.percentile(term, 90)), float(np.median(drag)),
                float(np.percentile(drag, 90)))  # fmt: skip

    rows = [observe()]
    for t_next in times:
        while sim.t < t_next:
            sim.step()
            hook(sim)
        rows.append(observe())
    return rows


if __name__ == "__main__":
    import sys

    from .common import case_main

    if "--zeroth-order" in sys.argv:
        for row in zeroth_order_diagnostic():
            print("t = {:.2f} s: zeroth-order term median {:.0f}, 90 % {:.0f} N/m3; drag median {:.0f}, "
                  "90 % {:.0f} N/m3".format(*row))  # fmt: skip
        raise SystemExit(0)

    raise SystemExit(case_main(sys.modules[__name__]))
