"""Hard cases of the water-soil coupling (issue 10, item 8), CI size: a water jet of 1 m/s onto a
dry bed and onto a saturated bed at dx = 5 mm, both formulations. No inlets exist yet, so the
"jet" is a water block 0.04 m wide and 0.06 m tall given an initial downward velocity of 1 m/s,
0.02 m above the bed; it hits at t ~ 0.02 s and spreads over the bed. Checks: no blow-up (the run
raises BlowUpError on NaN, a collapsed dt or a particle through a wall by more than h), no
particle outside the walls, reflections (if any) shallow, and the mass of each phase exactly
the initial one (masses are never recomputed and no particle is created or removed)."""

import tomllib

import numpy as np
import pytest
from conftest import rectangle_block, water_and_sand_scene

from solver.materials import Phase
from solver.scene import parse_scene
from solver.simulation import Simulation

JET = (
    water_and_sand_scene("jet_on_bed", 0.005, 0.12, "[0.2, 0.15]", youngs_modulus="5.0e6", seepage="{form}")
    + rectangle_block("bed", "sand", "[0.0, 0.0]", "[0.2, 0.05]", "geostatic = true\nsaturated = {saturated}")
    + rectangle_block("jet", "water", "[0.08, 0.07]", "[0.12, 0.13]")
)
T_END = 0.12
JET_SPEED = 1.0
BED_TOP = 0.05


def _phase_masses(sim):
    ps = sim.particles
    n = ps.n_owned
    phase = sim.plan.materials.phase[ps["material"][:n]]
    return {p: float(np.sort(ps["mass"][:n][phase == p]).sum()) for p in (Phase.WATER, Phase.SOIL)}


@pytest.mark.parametrize("saturated", [False, True])
@pytest.mark.parametrize("form", ["mixture", "seed"])
def test_jet_onto_bed(saturated, form):
    text = JET.replace("{form}", form).replace("{saturated}", "true" if saturated else "false")
    sim = Simulation(parse_scene(tomllib.loads(text), "jet.toml"))
    ps = sim.particles
    n = ps.n_owned
    jet = (sim.plan.materials.phase[ps["material"][:n]] == Phase.WATER) & (ps["x"][:n, 1] > 0.065)
    ps["v"][:n][jet] = [0.0, -JET_SPEED]
    ps["v_half"][:n][jet] = [0.0, -JET_SPEED]
    count0, mass0 = n, _phase_masses(sim)
    jet_ids = ps["id"][:n][jet]
    speeds, soil_speeds, lowest_water = [], [], []
    for t in np.linspace(0.0, T_END, 13)[1:]:
        sim.advance_to(t)
        m = ps.n_owned
        speeds.append(float(np.linalg.norm(ps["v_half"][:m], axis=1).max()))
        phase = sim.plan.materials.phase[ps["material"][:m]]
        soil_speeds.append(float(np.linalg.norm(ps["v_half"][:m][phase == Phase.SOIL], axis=1).max()))
        lowest_water.append(float(ps["x"][:m][np.isin(ps["id"][:m], jet_ids), 1].min()))
    sim.current_state()
    n = ps.n_owned
    x = ps["x"][:n]
    assert n == count0 and _phase_masses(sim) == mass0  # exactly: no particle made, lost or reweighed
    assert np.isfinite(x).all() and np.isfinite(ps["v_half"][:n]).all()
    assert (x >= sim.lo).all() and (x <= sim.hi).all()  # nothing through a wall
    assert sim.deepest_penetration < 0.5 * sim.scene.scene.spacing
    assert max(speeds) < 5 * JET_SPEED + np.sqrt(2 * 9.81 * 0.13)  # no blow-up: speeds stay physical
    assert min(lowest_water) < BED_TOP + sim.h  # the jet reached the bed
    assert max(soil_speeds) > 1e-4  # and moved it (measured 3.7e-4 m/s at the end on the dry bed)
