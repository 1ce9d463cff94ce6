"""What the seepage verification cases share (docs/verification_seepage.md): the materials,
scene building from a dict, the measured observables (pore pressure, effective stress, Darcy
flux) and a run loop that times both wall and CPU time (the machine is shared)."""

from __future__ import annotations

import time

import numpy as np

from solver.materials import Phase
from solver.scene import parse_scene

G = 9.81
RHO_W = 1000.0
GAMMA_W = RHO_W * G
FORMULATIONS = ("mixture", "seed")

WATER = {"model": "water", "density": RHO_W, "typical_velocity": 2.0}  # c = 20 m/s


def sand(porosity=0.4, grain_density=2650.0, permeability=1e-3, **extra):
    """A cohesionless sand: `density` is the dry density (1 - n) rho_grain (docs/seepage.md)."""
    mat = {
        "model": "soil",
        "density": (1.0 - porosity) * grain_density,
        "youngs_modulus": 5.0e6,
        "poisson_ratio": 0.3,
        "friction_angle": 33.0,
        "cohesion": 0.0,
        "porosity": porosity,
        "permeability": permeability,
    }
    mat.update(extra)
    return mat


def buoyant_unit_weight(mat):
    """gamma' = (1 - n)(rho_grain - rho_w) g = (rho_dry - (1 - n) rho_w) g."""
    return (mat["density"] - (1.0 - mat["porosity"]) * RHO_W) * G


def scene(
    name, spacing, end_time, domain_max, materials, blocks, formulation="mixture", walls=None, bodies=None,
    **numerics,
):  # fmt: skip
    raw = {
        "scene": {
            "name": name,
            "dimension": 2,
            "spacing": spacing,
            "end_time": end_time,
            "gravity": [0.0, -G],
        },
        "domain": {"min": [0.0, 0.0], "max": list(domain_max)},
        "walls": walls or {"x_min": "free_slip", "x_max": "free_slip", "y_min": "free_slip"},
        "materials": materials,
        "blocks": blocks,
        "numerics": {"seepage": formulation, **numerics},
        "output": {"interval": end_time, "vtk": False, "render": False},
    }
    if bodies:
        raw["bodies"] = bodies
    return parse_scene(raw, f"<verification {name}>")


def rows_of(sim, phase):
    """Owned rows of a phase."""
    ps = sim.particles
    n = ps.n_owned
    return np.flatnonzero(sim.plan.materials.phase[ps["material"][:n]] == phase)


def soil_rows(sim):
    return rows_of(sim, Phase.SOIL)


def water_rows(sim):
    return rows_of(sim, Phase.WATER)


def vertical_effective_stress(sim, rows):
    """-sigma'_yy of soil particles, compression positive (sigma = -p delta + s, seed eq. 12)."""
    ps = sim.particles
    return ps["mean_stress"][rows] - ps["stress_dev"][rows, 1]


def bin_profile(y, values, edges):
    """Mean of `values` in the bins of y (NaN where a bin is empty)."""
    idx = np.digitize(y, edges) - 1
    out = np.full(len(edges) - 1, np.nan)
    for k in range(len(out)):
        sel = idx == k
        if sel.any():
            out[k] = values[sel].mean()
    return out


def run_timed(sim, sample_times, observe, on_step=None):
    """Step a Simulation to each sample time, calling observe(sim) there. Returns the
    observations, the wall and the CPU time of the stepping (the first step, which compiles, is
    taken before the clock starts, as verification/common.timed_samples does)."""
    if sim.step_count == 0:
        sim.step()
    wall, cpu = time.perf_counter(), time.process_time()
    out = []
    for t in sample_times:
        if t > sim.t:
            sim.advance_to(t, on_step=on_step)
        sim.current_state()
        out.append(observe(sim))
    return out, time.perf_counter() - wall, time.process_time() - cpu


def figure_path(out_dir, stem):
    from pathlib import Path

    return None if out_dir is None else Path(out_dir) / f"{stem}.png"
