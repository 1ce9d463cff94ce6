"""The verification cases at CI resolution: every check must pass (tolerances and their
sources live in the case modules)."""

import pytest

from verification import column_collapse, dam_break, hydrostatic, impact_pressure, soil_self_weight


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


@pytest.fixture(scope="module")
def fine_still_water_seed():
    return hydrostatic.run(40, **hydrostatic.SEED)


@pytest.fixture(scope="module")
def fine_still_water_default():
    return hydrostatic.run(40)


@pytest.mark.slow
def test_seed_scheme_grows_an_acoustic_mode_in_fine_still_water(fine_still_water_seed):
    """Known defect of the seed's scheme, pinned (it was a strict xfail): with alpha = 0.01 the
    half-step leap-frog is not neutral (verification/leapfrog_stability.py) and an acoustic mode
    grows in still water at H/40 after ~0.25 s. Measured (hydrostatic_study.md): spurious Mach
    0.0103 at 0.5 s, per-particle pressure noise 1.41 rho0 g H. Pinned as: the Mach number passes
    the case's 0.01 tolerance, and the noise exceeds 0.5 rho0 g H (the defaults: 0.003)."""
    res = fine_still_water_seed
    assert res.series["mach"].max() > 0.01
    assert res.series["particle_pressure_noise"][-1] > 0.5


@pytest.mark.slow
def test_seed_scheme_lets_the_bottom_layer_reach_the_floor(fine_still_water_seed):
    """Known defect of the seed's mirror images, pinned (it was a strict xfail): an image carries
    its source's pressure, so the first layer has no hydrostatic support and settles into the
    image layer at H/40; the drift's reflection safeguard acts (measured: 43 times by 0.5 s)."""
    assert fine_still_water_seed.sim_reflections > 0


@pytest.mark.slow
def test_defaults_keep_fine_still_water_quiet_and_off_the_floor(fine_still_water_default):
    """The same two tests with the defaults (midpoint-density leap-frog, Fourtakas diffusion,
    hydrostatic images, wall repulsion): every check of the case passes at H/40 (Mach < 0.01,
    gauge pressure within h/H, no reflection)."""
    res = fine_still_water_default
    assert res.series["mach"].max() < 0.01
    assert res.sim_reflections == 0
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
def test_still_water_with_stronger_artificial_viscosity_is_stable_at_fine_resolution():
    """The seed's scheme with alpha = 0.1 stays quiet (the control for the pinned defect above)."""
    res = hydrostatic.run(40, **hydrostatic.SEED, **hydrostatic.STRONGER_AV)
    assert res.series["mach"].max() < 0.01


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
    "deposit's body stops early (61-67 % of the experiment's area beyond 0.30 m). Issue 24: mu(I) with the "
    "bars' size only adds friction, a Coulomb floor at their friction angle lets grains slide on (+8 % "
    "at 2.5 mm), and without the soil's artificial viscosity the runout is +20-33 % "
    "(verification/results/column_collapse/README.md, 'What makes the runout short')",
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


@pytest.fixture(scope="module")
def impact_ci(tmp_path_factory):
    """Lobovsky et al. (2014) at H/20 with the defaults (impact_pressure.DEFAULT_RESOLUTION)."""
    return impact_pressure.run(impact_pressure.DEFAULT_RESOLUTION, out_dir=tmp_path_factory.mktemp("impact"))


PLATEAU_MEAN = impact_pressure.PLATEAU_MEAN
PLATEAU_MEAN_2D = impact_pressure.PLATEAU_MEAN_2D
PLATEAU_NOISE = "plateau noise: sd of the acoustically filtered p* at sensor 2, t* 3-5.5"


@pytest.mark.slow
def test_impact_holds_and_arrives_in_time_at_ci_resolution(impact_ci):
    """No blow-up, zero wall reflections, impact time inside the experiment's window, first-impact pressure
    impulse at sensor 2 inside the band's spread + the study's allowance (measured -0.070 against 0.306 at
    H/20) (the plateau mean is a known discrepancy against the experiment and the 2D interFoam reference
    alike, pinned by strict xfails)."""
    assert impact_ci.figure.is_file()
    known = (PLATEAU_MEAN, PLATEAU_MEAN_2D)
    failed = [c.line() for c in impact_ci.checks if not c.passed and c.metric not in known]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
def test_impact_plateau_noise_at_ci_resolution(impact_ci):
    """The plateau's hydrodynamic noise (moving average over the model's acoustic period 4 H / c0, the
    same filter on the experiment) inside the repetitions' spread: measured 0.059 rho g H at H/20
    (seed scheme 0.18). The 1 ms-filtered sd (0.51 at H/20, 0.33 at H/40) is the model's artificial
    acoustics at 10-250 Hz and is reported, not checked (verification/results/impact_pressure/README.md)."""
    check = next(c for c in impact_ci.checks if c.metric == PLATEAU_NOISE)
    assert check.passed, check.line()
    assert impact_ci.series["metrics"]["plateau_sd_1ms_s2"] > check.value


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="no corner separation: the 2D SPH plateau pressure at sensor 2 lies above the repetitions' band "
    "(mean p* 0.82 / 0.85 / 0.90 at H/20 / H/40 / H/80 against the band's median 0.61 and half-width 0.12), "
    "with the unseparated stagnation corner that 2D interFoam with slip walls also has "
    "(0.93 / 0.92 / 0.93 at H/20 / H/40 / H/60); the experiment's flat plateau is that of a separated "
    "corner eddy, which interFoam's no-slip runs form through their convection scheme (0.61 / 0.59 / 0.58) "
    "and the SPH does not form with no-slip or log-law wall-function walls either "
    "(verification/results/impact_pressure/README.md, 'What sets the plateau'); every published 2D "
    "free-slip computation found gives 0.91-0.92 (reference_cases/openfoam_lobovsky_impact/README.md, "
    "'What published 2D computations get'); kept visible",
)
def test_impact_plateau_mean_at_ci_resolution(impact_ci):
    check = next(c for c in impact_ci.checks if c.metric == PLATEAU_MEAN)
    assert check.passed, check.line()


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="SPH converges toward 2D interFoam with the same free-slip walls (0.925 at H/60) from below, "
    "-0.11 / -0.07 / -0.03 at H/20 / H/40 / H/80: at H/20 more than the case's first-order allowance 0.063 "
    "plus interFoam's mesh uncertainty, as another code's WCSPH converges (TrixiParticles 0.842 / 0.887 / "
    "0.906 at H/40 / H/80 / H/400; reference_cases/openfoam_lobovsky_impact/README.md)",
)
def test_impact_plateau_mean_against_2d_interfoam(impact_ci):
    check = next(c for c in impact_ci.checks if c.metric == PLATEAU_MEAN_2D)
    assert check.passed, check.line()


@pytest.mark.slow
def test_seed_scheme_on_impact_needs_the_safeguard_and_swings():
    """The seed's scheme on the same tank, pinned (issue 15): it completes at H/20 only because the
    drift's safeguard reflects particles (measured 1,620 reflections) and its plateau pressure swings
    (sd of the 1 ms-filtered p* at sensor 2: 3.1 rho g H, against 0.51 with the defaults and 0.05 in the
    measured event; after the acoustic filter 4 H / c0: 0.18, against 0.059 with the defaults, 0.051 in
    the measured event: outside the repetitions' spread 0.115)."""
    res = impact_pressure.run(impact_pressure.DEFAULT_RESOLUTION, out_dir=None, scheme="seed")
    m = res.series["metrics"]
    assert m["reflections"] > 100
    assert m["plateau_sd_1ms_s2"] > 1.0
    assert m["plateau_sd_s2"] > res.series["reference"]["plateau_half_width"]
