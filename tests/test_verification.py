"""The verification cases at CI resolution: every check must pass (tolerances and their
sources live in the case modules)."""

import pytest

from verification import column_collapse, dam_break, hydrostatic, soil_self_weight


@pytest.mark.slow
def test_dam_break_matches_experiment_ritter_and_openfoam(tmp_path):
    res = dam_break.run(dam_break.DEFAULT_RESOLUTION, out_dir=tmp_path)
    assert res.figure.is_file()
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
def test_still_water_stays_hydrostatic(tmp_path):
    res = hydrostatic.run(hydrostatic.DEFAULT_RESOLUTION, out_dir=tmp_path)
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="known defect: with the seed's alpha = 0.01 an acoustic mode grows "
    "exponentially in still water at H/40 after ~0.25 s (alpha = 0.1 is stable): the seed's half-step "
    "leap-frog "
    "is not symplectic (verification/leapfrog_stability.py); kept visible until fixed",
)
def test_still_water_stays_quiet_at_fine_resolution():
    res = hydrostatic.run(40)
    assert res.series["mach"].max() < 0.01


@pytest.mark.slow
def test_still_water_with_stronger_artificial_viscosity_is_stable_at_fine_resolution():
    """The same fine tank with alpha = 0.1 stays at rest (the control for the xfail above)."""
    res = hydrostatic.run(40, **hydrostatic.STRONGER_AV)
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.fixture(scope="module")
def fine_still_water_symplectic():
    return hydrostatic.run(40, **{"numerics.leapfrog": "symplectic_density"})


@pytest.mark.slow
def test_symplectic_density_keeps_fine_still_water_quiet(fine_still_water_symplectic):
    """With rho at whole steps (numerics.leapfrog = "symplectic_density") the acoustic mode
    that grows under the seed's scheme at H/40 stays damped with the seed's alpha = 0.01:
    spurious Mach and gauge pressure meet the case's tolerances (hydrostatic.py)."""
    res = fine_still_water_symplectic
    by_metric = {c.metric: c for c in res.checks}
    assert res.series["mach"].max() < 0.01
    assert by_metric["RMS error of time-averaged gauge pressure / (rho0 g H)"].passed


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="known defect of the seed's mirror images: an image carries its source's "
    "pressure, so the first layer has no hydrostatic support and settles onto the floor at H/40 "
    "(reflection safeguard acts ~30 times by 0.5 s); kept visible until fixed",
)
def test_bottom_layer_stays_off_the_wall_at_fine_resolution(fine_still_water_symplectic):
    assert fine_still_water_symplectic.sim_reflections == 0


@pytest.mark.slow
def test_hydrostatic_image_pressure_keeps_fine_still_water_at_rest():
    """numerics.image_pressure = "hydrostatic" gives the first layer the support the seed's
    mirror images lack: at H/40 every check of the case passes, with the seed's leap-frog and
    alpha = 0.01 (no reflection at the floor, spurious Mach < 0.01, gauge pressure within h/H)."""
    res = hydrostatic.run(40, **{"numerics.image_pressure": "hydrostatic"})
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.fixture(scope="module")
def collapse_ci(tmp_path_factory):
    """dx = 5 mm, the coarsest spacing of the committed resolution study (its tolerances carry
    that spacing's discretisation error; column_collapse module docstring)."""
    return column_collapse.run(20, out_dir=tmp_path_factory.mktemp("collapse"))


FAILURE_LINE = "failure-line RMS error in x (m)"


RUNOUT = "runout error (m)"


@pytest.mark.slow
def test_column_collapse_matches_experiment_at_ci_resolution(collapse_ci):
    """Height at the wall, free surface, rest and yield (the runout and the failure line are
    known discrepancies, each pinned by its own strict xfail below)."""
    assert collapse_ci.figure.is_file()
    failed = [c.line() for c in collapse_ci.checks if not c.passed and c.metric not in (FAILURE_LINE, RUNOUT)]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="known discrepancy since the tension-crack density fix (issue 14): the runout falls short "
    "of the experiment's 0.442 m by 47 / 59 / 30 mm at 5 / 4 / 2.5 mm, beyond the 3 mm digitisation "
    "plus the numerical uncertainty of a non-monotone study (half the range, 14.5 mm; ITTC 2017); the "
    "one-particle toe layer breaks at 2.5 mm (verification/results/column_collapse/README.md)",
)
def test_column_collapse_runout(collapse_ci):
    check = next(c for c in collapse_ci.checks if c.metric == RUNOUT)
    assert check.passed, check.line()


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="known discrepancy: the SPH undisturbed-zone boundary lies ~1 cm from the "
    "experiment's failure line (RMS 8.4 / 9.2 / 12.1 mm at 5 / 4 / 2.5 mm against 3 mm: the error grows "
    "with refinement, so no discretisation allowance); the SPH shear band is 7-8 dx wide at every "
    "displacement or strain threshold and artificial viscosity does not change it "
    "(verification/results/column_collapse/README.md); kept visible until the model resolves it",
)
def test_column_collapse_failure_line(collapse_ci):
    check = next(c for c in collapse_ci.checks if c.metric == FAILURE_LINE)
    assert check.passed, check.line()


@pytest.mark.slow
def test_soil_self_weight_matches_1d_solution_and_slope_stands(tmp_path):
    """Confined elastic column against the constrained-modulus solution, and a 15 deg heap
    (below phi = 19.8 deg) that must stand, at dx = 5 mm (the study's finest)."""
    res = soil_self_weight.run(soil_self_weight.DEFAULT_RESOLUTION, out_dir=tmp_path)
    assert res.figure.is_file()
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)
