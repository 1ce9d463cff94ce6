"""SPH side of the sheet-pile seepage cross-check against OpenFOAM (issue 10, item 5;
docs/verification_seepage.md case 5). The reference is reference_cases/openfoam_seepage_2d
(data/: discharge, heads along lines, the head field of its finest Laplace mesh).

Geometry as the reference, shifted so that the domain starts at x = 0: a fixed, saturated sand
layer T = 0.2 m thick on the impermeable floor, x in [0, 2 HALF + dx] (closed, free-slip sides),
a sheet pile centred at XP = HALF + dx/2 (the reference's x = 0) from the ground surface down to
T - S, and free water above the ground, 0.10 m deep upstream (head H_UP above the base) and
0.05 m downstream (head H_DOWN). The pile is a fixed block of water particles 3 dx thick from
T - S to above the upstream water (the reference pile has zero thickness). 3 dx, not 2: the
water on one side must not reach the pile particles of the other side's face (2 dx apart with a
2 dx pile, inside 2h = 2.6 dx), whose pressure is the other side's; the half-cell shift keeps
the lattice aligned with a pile of odd thickness.

Formulation: "seed" only. Free water flows into the pores here, which the mixture form cannot do
yet (its pore water keeps n rho_w as its EOS reference, so water entering from a pond reads a
spurious tension: seepage_darcy.py, "Why a draining column"); the seed form's water is at its true
density everywhere, and its steady state is Laplace's equation for the head (docs/seepage.md:
n v_w = -k grad h with div v_w = 0), the reference's equation. In the seed form the water particles
move at the pore velocity v_w and tile the whole bed, so the discharge is Q = n int v_w . dA.

Start: the pore water at the reference head, p = gamma_w (h_ref(x, y) - y), rho = rho_w(p) and
m = rho dx^2 (the lattice), so that the run starts near its steady state; the ponds hydrostatic.

Observables (averaged over the last half of the run):
  * Q = n <v_x> (T - S) of the pore water in the particle column at x = XP below the pile tip
    (the section under the pile);
  * heads h = y + p / gamma_w of the pore water along the row nearest the floor and the column
    nearest x = XP + T/10 (the reference's "base" and "downstream_x_T_over_10" lines), against
    the reference head field at the particles' positions, as max |h - h_ref| / H (H = H_UP -
    H_DOWN).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import seepage_common as sc

T, S = 0.2, 0.1  # layer thickness, pile depth below the ground (m)
HALF = 0.6  # half the layer length (m)
H_UP, H_DOWN = 0.30, 0.25  # heads above the base (m)
K, POROSITY = 1e-3, 0.4
E_FIXED = 1.0e5  # the fixed skeleton's stiffness plays no part (as seepage_darcy.py)
Q_REFERENCE = 0.5 * K * (H_UP - H_DOWN)  # Q/(kH) = 1/2 (Harr 1962), the reference's mesh limit to 7e-5
DATA = Path(__file__).resolve().parents[1] / "reference_cases" / "openfoam_seepage_2d" / "data"


def pile_centre(dx):
    return HALF + 0.5 * dx


def reference_head():
    """h_ref(x, y) with x in the reference's frame (pile at 0): bilinear in its head_field.csv."""
    rows = np.loadtxt(DATA / "head_field.csv", delimiter=",", comments="#", skiprows=2)
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


def scene(resolution, t_end, formulation="seed"):
    dx = T / resolution
    p0, p1 = pile_centre(dx) - 1.5 * dx, pile_centre(dx) + 1.5 * dx  # the pile
    right = 2 * HALF + dx
    top = H_UP + 0.02
    soil = {"shape": "rectangle", "fixed": True, "saturated": True, "material": "sand", "pore_water": "water"}
    blocks = [
        {**soil, "name": "lower_up", "min": [0.0, 0.0], "max": [HALF, T - S], "water_table": H_UP},
        {**soil, "name": "lower_down", "min": [HALF, 0.0], "max": [right, T - S], "water_table": H_DOWN},
        {**soil, "name": "upper_up", "min": [0.0, T - S], "max": [p0, T], "water_table": H_UP},
        {**soil, "name": "upper_down", "min": [p1, T - S], "max": [right, T], "water_table": H_DOWN},
        {"name": "pile", "material": "pile", "shape": "rectangle", "fixed": True, "min": [p0, T - S],
         "max": [p1, top]},
        {"name": "pond_up", "material": "water", "shape": "rectangle", "min": [0.0, T], "max": [p0, H_UP],
         "hydrostatic": True},
        {"name": "pond_down", "material": "water", "shape": "rectangle", "min": [p1, T],
         "max": [right, H_DOWN], "hydrostatic": True},
    ]  # fmt: skip
    mats = {
        "water": sc.WATER,
        "pile": sc.WATER,
        "sand": sc.sand(POROSITY, permeability=K, youngs_modulus=E_FIXED),
    }
    walls = {"x_min": "free_slip", "x_max": "free_slip", "y_min": "free_slip"}
    return sc.scene("seepage_sheet_pile", dx, t_end, [right, top + 0.02], mats, blocks, formulation, walls)


def start_at_reference(sim):
    """Pore water (free water below the ground) at the reference head: p, rho_w(p), m = rho dx^2."""
    from solver.materials import tait_density

    ps, mats = sim.particles, sim.plan.materials
    wa = sc.water_rows(sim)
    wa = wa[~ps["fixed"][wa]]
    x = ps["x"][wa]
    pore = wa[x[:, 1] < T]
    h_ref = reference_head()
    xp = pile_centre(sim.scene.scene.spacing)
    p = np.maximum(sc.GAMMA_W * (h_ref(ps["x"][pore, 0] - xp, ps["x"][pore, 1]) - ps["x"][pore, 1]), 0.0)
    kw = mats.names.index("water")
    rho = tait_density(p, mats.rho0[kw], mats.eos_b[kw], mats.eos_exponent[kw])
    ps["p"][pore] = p
    ps["rho"][pore] = rho
    ps["mass"][pore] = rho * sim.scene.scene.spacing**2
    for half in ("rho_half",):
        if half in ps:
            ps[half][pore] = rho


def measure(sim):
    ps = sim.particles
    dx, h_ref = sim.scene.scene.spacing, reference_head()
    wa = sc.water_rows(sim)
    wa = wa[~ps["fixed"][wa]]
    xp = pile_centre(dx)
    x, y = ps["x"][wa, 0] - xp, ps["x"][wa, 1]  # x in the reference's frame
    under = (np.abs(x) < 0.5 * dx) & (y < T - S)
    q = POROSITY * float(ps["v"][wa][under, 0].mean()) * (T - S)
    head = y + ps["p"][wa] / sc.GAMMA_W
    err = head - h_ref(x, y)
    lines = {
        "base": y < dx,
        "downstream_x_T_over_10": (np.abs(x - T / 10) < 0.5 * dx) & (y < T - dx),
    }
    out = {"Q": q}
    for name, sel in lines.items():
        out[name] = float(np.abs(err[sel]).max() / (H_UP - H_DOWN))
    # the heads the ponds actually impose (SPH's free-surface pressure deficit is ~dx/2 of head):
    # the row of pond water just above the ground, away from the pile
    row = (y > T) & (y < T + dx) & (np.abs(x) > 0.1)
    up, down = row & (x < 0), row & (x > 0)
    h_up, h_down = float(head[up].mean()), float(head[down].mean())
    out.update(h_up=h_up, h_down=h_down, Q_over_kdH=q / (K * (h_up - h_down)))
    # heads normalised by the imposed drop, against the reference's
    ref_norm = (h_ref(x, y) - H_DOWN) / (H_UP - H_DOWN)
    norm_err = (head - h_down) / (h_up - h_down) - ref_norm
    for name, sel in lines.items():
        out[name + "_normalised"] = float(np.abs(norm_err[sel]).max())
    return out


def run_one(resolution=10, t_end=0.3, formulation="seed", samples=7):
    from solver.simulation import Simulation

    sim = Simulation(scene(resolution, t_end, formulation))
    start_at_reference(sim)
    times = np.linspace(0.0, t_end, samples)
    obs, wall, cpu = sc.run_timed(sim, times, measure)
    late = [o for t, o in zip(times, obs) if t >= 0.5 * t_end - 1e-12]
    res = {k: float(np.mean([o[k] for o in late])) for k in late[0]}
    res.update(
        Q_over_reference=res["Q"] / Q_REFERENCE,
        series=obs,
        t=times,
        particles=sim.particles.n_owned,
        steps=sim.step_count,
        wall=wall,
        cpu=cpu,
        dx=T / resolution,
        formulation=formulation,
    )
    return res


if __name__ == "__main__":  # NUMBA_NUM_THREADS=1 python -m verification.seepage_sheet_pile [resolution t_end]
    import sys

    args = [float(a) for a in sys.argv[1:]]
    r = run_one(int(args[0]) if args else 10, args[1] if len(args) > 1 else 0.3)
    for t, o in zip(r["t"], r["series"]):
        print(f"t {t:.3f} s: Q/Q_ref {o['Q'] / Q_REFERENCE:.4f}, Q/(k dH_sph) {o['Q_over_kdH']:.4f} "
              f"(ref 0.5), h_up {o['h_up']:.5f} h_down {o['h_down']:.5f}; max |h - h_ref|/H: base "
              f"{o['base']:.4f}, x=T/10 {o['downstream_x_T_over_10']:.4f}; normalised by the SPH drop: "
              f"{o['base_normalised']:.4f}, {o['downstream_x_T_over_10_normalised']:.4f}")  # fmt: skip
    print({k: v for k, v in r.items() if k not in ("series", "t")})
