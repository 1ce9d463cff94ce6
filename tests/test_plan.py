"""The plan builds only what the scene calls for (no field, pass, exchange or dt limit more)."""

from conftest import ROOT

from solver.materials import Phase
from solver.physics.fluid_rates import FluidRates
from solver.plan import build_plan
from solver.simulation import Simulation
from solver.term import Stage
from verification.common import scene_from_file

WATER_ONLY_SOIL_FIELDS = ("stress_dev", "stress_dev_half", "dstress", "mean_stress", "art_stress", "eps_vp")


def small_dam_break(**overrides):
    return scene_from_file("dam_break_2d.toml", **{"scene.spacing": 0.05715 / 10, **overrides})


def test_water_only_scene_has_no_soil_field_or_pass():
    scene = small_dam_break()
    plan = build_plan(scene)
    assert not any(f in plan.fields for f in WATER_ONLY_SOIL_FIELDS)
    assert [t.name for t in plan.terms] == [
        "wall images",
        "Tait equation of state",
        "viscous stress",
        "gravity",
        "fluid rates",
    ]
    assert plan.pairs == ((Phase.WATER, Phase.WATER),)
    sim = Simulation(scene)
    assert not any(f in sim.particles for f in WATER_ONLY_SOIL_FIELDS)


def test_water_only_run_compiles_no_soil_kernel():
    """A water-only run never calls (so never compiles) a kernel of any term it does not have:
    every module of an absent term (soil stress, soil rates, artificial stress, soil images,
    frictional walls, ...) ends the run with no compiled signature."""
    import subprocess
    import sys

    code = (
        "import importlib\n"
        "from numba.core.registry import CPUDispatcher\n"
        "from verification.common import scene_from_file\n"
        "from solver.simulation import Simulation\n"
        "from solver.physics import TERMS\n"
        "sim = Simulation(scene_from_file('dam_break_2d.toml', **{'scene.spacing': 0.05715/10}))\n"
        "[sim.step() for _ in range(3)]\n"
        "sim.current_state()\n"
        "present = {type(t).__module__ for t in sim.plan.terms}\n"
        "absent = {c.__module__ for c in TERMS} - present\n"
        "own = [(m, n, f) for m in sorted(absent) for n, f in vars(importlib.import_module(m)).items()\n"
        "       if isinstance(f, CPUDispatcher) and f.py_func.__module__ == m]\n"
        "compiled = [m + '.' + n for m, n, f in own if f.signatures]\n"
        "print('ABSENT', sorted(absent))\n"
        "print('COMPILED', compiled)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert "solver.physics.soil_rates" in out.stdout  # the check looked at the soil modules
    assert "COMPILED []" in out.stdout


def test_viscosity_off_removes_term_field_and_dt_limit():
    on = build_plan(small_dam_break())
    off = build_plan(small_dam_break(**{"numerics.viscous_stress": False}))
    assert on.has_term("viscous stress") and "tau" in on.fields
    assert not off.has_term("viscous stress") and "tau" not in off.fields
    assert "viscous" in [c.name for c in on.constraints] and "viscous" not in [
        c.name for c in off.constraints
    ]
    assert "tau" not in off.halo_fields and not any(
        "tau" in s.refresh for v in off.schedule.values() for s in v
    )
    terms = [e.what for _, e in off.equations()]
    assert "viscous stress divergence" not in terms


def test_xsph_off_removes_term_and_field():
    off = build_plan(small_dam_break(**{"numerics.xsph_epsilon": 0.0}))
    assert "xsph" not in off.fields
    assert "XSPH" not in [e.what for _, e in off.equations()] and off.position_correction is None


def test_artificial_viscosity_off_when_alpha_beta_zero():
    off = build_plan(
        small_dam_break(**{"numerics.artificial_viscosity": {"water": {"alpha": 0.0, "beta": 0.0}}})
    )
    assert off.term(FluidRates).av_alpha is None
    assert "Monaghan artificial viscosity" not in [e.what for _, e in off.equations()]


def test_absent_terms_are_not_compiled_into_the_kernel():
    """The fluid kernel is specialised with None for absent terms: Numba prunes them."""
    from solver.physics import fluid_rates as fluid

    sim = Simulation(small_dam_break(**{"numerics.viscous_stress": False, "numerics.xsph_epsilon": 0.0}))
    sim.step()
    sig = [s for s in fluid.fluid_rates.signatures if len(s) >= 15]
    assert any(str(s[14]) == "none" and str(s[17]) == "none" for s in sig)  # tau and xsph are None


def test_explain_lists_passes_terms_fields(capsys):
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-m", "scoursph", "run", str(ROOT / "scenes" / "dam_break_2d.toml"), "--explain"],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert out.returncode == 0
    for text in (
        "fluid rates: water <- water",
        "continuity [seed eq. (6)]",
        "XSPH [seed eq. (22)]",
        "viscous [seed eq. (30)]",
        "bytes per particle",
        "Not in this plan",
    ):
        assert text in out.stdout
    assert "stress_dev" not in out.stdout


def test_memory_per_particle_is_within_budget():
    """Issue target: <= 1 KB per particle including neighbour lists and images."""
    sim = Simulation(small_dam_break(**{"scene.spacing": 0.05715 / 40}))
    n = sim.particles.n_owned
    lists = sum(nl.index.nbytes + nl.start.nbytes + nl.targets.nbytes for nl in sim.lists.values())
    cells = sim.cells.cells.nbytes + sim.cells.order.nbytes + sim.cells.cell_start.nbytes
    total = sim.particles.nbytes() + lists + cells
    assert total / n < 1024


def test_symplectic_density_option_moves_continuity_after_the_drift():
    seed = build_plan(small_dam_break())
    sym = build_plan(small_dam_break(**{"numerics.leapfrog": "symplectic_density"}))
    assert "rho_half" in seed.fields and "rho_half" not in sym.fields
    assert ("rho", "rho_half", "drho") not in sym.integrated
    assert [s.term.name for s in sym.schedule[Stage.AFTER_DRIFT]] == ["symplectic continuity"]
    assert "continuity" not in [e.what for e in sym.term(FluidRates).equations]
    assert sym.schedule[Stage.AFTER_DRIFT][0].refresh == ("x", "v_half")


def test_symplectic_density_refused_with_soil():
    import pytest

    from solver.errors import SceneError

    with pytest.raises(SceneError) as err:
        scene_from_file("column_collapse_2d.toml", **{"numerics.leapfrog": "symplectic_density"})
    assert err.value.key == "numerics.leapfrog"


def test_hydrostatic_image_pressure_option_is_planned_and_explained():
    import subprocess
    import sys

    plan = build_plan(small_dam_break(**{"numerics.image_pressure": "hydrostatic"}))
    assert plan.has_term("hydrostatic image pressure") and not build_plan(small_dam_break()).has_term(
        "hydrostatic image pressure"
    )
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "scoursph",
            "run",
            str(ROOT / "scenes" / "dam_break_2d.toml"),
            "--explain",
            "--set",
            'numerics.image_pressure="hydrostatic"',
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    assert "p_image = p_source + rho_source g . (x_image - x_source)" in out.stdout
