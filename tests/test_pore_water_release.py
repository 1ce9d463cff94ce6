"""Pore water that leaves an eroding bed becomes free water (solver/physics/pore_water_release.py).

The kernel against its NumPy twin (tests/naive_erosion.py) on random rows: exactly the pore water
outside the bed is released, its density divided by its fraction, its pressure unchanged to round-off;
the term exists only with an eroding bed and mixture pore water; in the mobile-bed dam break the release
happens (pore water reaches the free stream) and keeps the pore water's tension bounded.
"""

import numpy as np
import pytest
from naive_erosion import release_pore_water as twin

from solver.physics.pore_water_release import PoreWaterRelease, release_pore_water

RHO0, C = 1000.0, 37.0
TAIT_B = RHO0 * C * C / 7.0


def test_release_matches_twin_and_keeps_the_pressure():
    rng = np.random.default_rng(24)
    n = 400
    fraction = np.where(rng.random(n) < 0.5, rng.choice([0.4, 0.47], n), 1.0)
    free = (rng.random(n) < 0.5).astype(np.uint8)
    rho = fraction * RHO0 * (1.0 + 0.02 * rng.standard_normal(n))
    rho_half = rho * (1.0 + 1e-3 * rng.standard_normal(n))
    rows = np.sort(rng.choice(n, 300, replace=False))  # the water rows (the rest stand for soil)
    expected = twin(free[rows], fraction[rows], rho[rows], rho_half[rows], TAIT_B, RHO0)
    f, r, rh = fraction.copy(), rho.copy(), rho_half.copy()
    release_pore_water(rows, free, f, r, rh)
    np.testing.assert_array_equal(f[rows], expected[0])
    np.testing.assert_allclose(r[rows], expected[1], rtol=1e-14)  # fastmath: a reciprocal multiply
    np.testing.assert_allclose(rh[rows], expected[2], rtol=1e-14)  # fastmath: a reciprocal multiply
    others = np.setdiff1d(np.arange(n), rows)
    assert (f[others] == fraction[others]).all() and (r[others] == rho[others]).all()
    released = (fraction[rows] < 1.0) & (free[rows] != 0)
    assert released.any() and (f[rows][released] == 1.0).all()
    assert (f[rows][(fraction[rows] < 1.0) & (free[rows] == 0)] < 1.0).all()  # pore water in the bed stays
    np.testing.assert_allclose(expected[4], expected[3], rtol=1e-9, atol=1e-9 * TAIT_B)  # p unchanged
    release_pore_water(rows, free, f, r, None)  # without the leap-frog's half-step density: idempotent
    np.testing.assert_allclose(r[rows], expected[1], rtol=1e-14)


def test_the_term_only_with_an_eroding_bed_and_mixture_pore_water():
    from solver.plan import build_plan
    from verification import mobile_bed_dam_break as case
    from verification import sediment_threshold as st

    names = lambda plan: {t.name for t in plan.terms}  # noqa: E731
    assert PoreWaterRelease.name in names(build_plan(case.scene(35)))
    assert PoreWaterRelease.name not in names(build_plan(case.scene(35, rigid=True)))  # no soil
    assert PoreWaterRelease.name not in names(build_plan(case.scene(35, erosion="none")))
    assert PoreWaterRelease.name not in names(build_plan(case.scene(35, bed_shear="drag")))  # no flags
    assert PoreWaterRelease.name not in names(build_plan(st.scene(7, seepage="seed")))  # no fractions


@pytest.fixture(scope="module")
def dam_break_10mm():
    """The mobile-bed dam break at 10 mm to 0.25 s (about 25 s of CPU)."""
    from solver.simulation import Simulation
    from verification import mobile_bed_dam_break as case

    sim = Simulation(case.scene(35, 0.25))
    sim.advance_to(0.25)
    return sim


def test_pore_water_reaches_the_stream_and_is_released(dam_break_10mm):
    from verification.seepage_common import water_rows

    ps = dam_break_10mm.particles
    water = water_rows(dam_break_10mm)
    n_pore = 0.47
    light = ps["mass"][water] < 0.6 * ps["mass"][water].max()  # pore water's mass is n rho_w V
    released = water[(ps["water_fraction"][water] == 1.0) & light]
    assert len(released) > 0  # pore water (mass n rho_w V) now free water
    still = water[ps["water_fraction"][water] < 1.0]
    assert (ps["free_water"][still] == 0).all()  # every pore particle outside the bed was released
    # no tension beyond what water can hold: gauge pressure above -1 atm (cavitation near the vapour
    # pressure); escaped pore water kept at its pore reference read -B = -196 kPa before the release
    assert ps["p"][water].min() > -101325.0, ps["p"][water].min()
    assert n_pore == pytest.approx(ps["water_fraction"][still].max())
