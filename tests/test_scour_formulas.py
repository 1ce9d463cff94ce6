"""Published jet-scour formulas and the set-up hydraulics (verification/analytic/scour_formulas.py).

Each formula is checked against a value printed in a source where one was found (Kolatus:
the worked examples of the hydReng package, which reproduces Bezzola 2012), otherwise
against a hand calculation written out below with the formula's source.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from verification.analytic import scour_formulas as S


# ----------------------------------------------------------------------------- hydraulics
def test_critical_depth_matches_design_figures():
    # DESIGN.md: q = 0.06 -> y_c = 72 mm, 0.84 m/s; q = 0.11 -> 107 mm, 1.03 m/s
    for q, yc, uc in ((0.06, 0.072, 0.84), (0.11, 0.107, 1.03)):
        y = float(S.critical_depth(q))
        assert y == pytest.approx(yc, abs=0.0005)
        assert q / y == pytest.approx(uc, abs=0.005)


def test_supercritical_depth_solves_the_energy_equation():
    for q in (0.06, 0.11):
        hy = S.setup_hydraulics(q, fall=0.01)
        y = hy.h_tail
        assert y + q * q / (2 * S.G * y * y) == pytest.approx(hy.energy_up, rel=1e-10)
        assert y < hy.y_c and hy.froude_tail > 1.0
        # the energy level: crown (0.01 m) + 1.5 y_c (critical flow over the crown)
        assert hy.energy_up == pytest.approx(0.01 + 1.5 * hy.y_c)
        assert hy.head_drop == pytest.approx(hy.energy_up - y)
        assert hy.impact_speed == pytest.approx(math.hypot(hy.u_c, math.sqrt(2 * S.G * 0.01)))


def test_supercritical_depth_refuses_energy_below_critical():
    with pytest.raises(ValueError):
        S.supercritical_depth(0.06, 1.4 * float(S.critical_depth(0.06)))


def test_rand_1955_hand_calculation():
    # q = 0.06 m2/s over a 0.01 m drop: D = 0.06^2 / (9.81 * 1e-6) = 366.97;
    # pool depth y_p = 1.00 * D^0.22 * 0.01 = 0.01 * exp(0.22 ln 366.97) = 0.0367 m
    r = S.rand_1955_drop(0.06, 0.01)
    assert float(r["drop_number"]) == pytest.approx(366.97, rel=1e-4)
    assert float(r["pool_depth"]) == pytest.approx(0.0367, rel=2e-3)
    # the pool under the nappe is deeper than the drop: the nappe's underside is drowned
    assert float(r["pool_depth"]) > 0.01


# ----------------------------------------------------------------------------- formulas
def test_kolatus_against_printed_worked_examples():
    # hydReng 1.0.0 tests (Bezzola 2012 method): Q = 4 m3/s, B = 1 m, d90 = 150 mm,
    # T0 = 7.722174 m for h = 5 m and 6.457918 m for h = 3 m (tolerance there 0.01)
    assert float(S.kolatus(4.0, 5.0, 0.150)) == pytest.approx(7.722174, abs=1e-5)
    assert float(S.kolatus(4.0, 3.0, 0.150)) == pytest.approx(6.457918, abs=1e-5)


def test_tschopp_hand_calculation():
    # Bezzola (2012): T0 = 2.76 q^0.5 H^0.25 - 7.22 d90
    # q = 4, H = 3, d90 = 0.15: 2.76 * 2 * 3^0.25 - 1.083 = 5.52 * 1.316074 - 1.083 = 6.181729
    assert float(S.tschopp(4.0, 3.0, 0.15)) == pytest.approx(6.181729, abs=1e-5)


def test_schoklitsch_si_coefficient_is_the_mm_one():
    # Schoklitsch (1932) wrote 4.75 with d90 in mm: 0.521 = 4.75 / 1000^0.32 (0.03 %)
    assert 0.521 * 1000**0.32 == pytest.approx(4.75, rel=1e-3)
    d_mm = 20.0
    in_mm = 4.75 * 30**0.2 * 5**0.57 / d_mm**0.32
    assert float(S.schoklitsch_1932(5.0, 30.0, d_mm / 1000)) == pytest.approx(in_mm, rel=1e-3)


def test_schoklitsch_hand_calculation():
    # q = 5, H = 30, d90 = 0.05: 0.521 * 30^0.2 * 5^0.57 / 0.05^0.32
    #   = 0.521 * 1.973708 * 2.502112 / 0.383615 = 6.714358
    assert float(S.schoklitsch_1932(5.0, 30.0, 0.05)) == pytest.approx(6.714358, rel=1e-6)


def test_veronese_forms_meet_at_5_mm():
    # Veronese dropped d below 5 mm: his two forms agree there (0.202 / 0.005^0.42 = 1.870
    # against 1.90, 1.6 %)
    a = S.veronese_1937a(0.1, 0.05, 0.005)
    b = S.veronese_1937b(0.1, 0.05)
    assert float(a / b) == pytest.approx(1.0, abs=0.02)
    # hand calculation: q = 5, H = 30: 1.90 * 30^0.225 * 5^0.54 = 1.90 * 2.148 * 2.386 = 9.7398
    assert float(S.veronese_1937b(5.0, 30.0)) == pytest.approx(9.739792, rel=1e-6)


def test_mason_arumugam_hand_calculation():
    # q = 10, H = 50, h = 10, d = 0.25 (their prototype size): K = 6.42 - 3.10 * 50^0.1 =
    # 1.835851, x = 0.6 - 50/300 = 0.433333, y = 0.15 + 50/200 = 0.4;
    # D = K 10^x 50^y 10^0.15 / (9.81^0.3 0.25^0.1) = 19.474402 m
    assert float(S.mason_arumugam_1985(10.0, 50.0, 10.0, 0.25)) == pytest.approx(19.474402, rel=1e-6)


def test_kolatus_hole_lengths_hand_calculation():
    # q = 4, H = 3, d95 = 0.2: l1 = 3.9 * 3^0.27 * 4^0.54 / (9.81^0.27 * 0.2^0.08)
    l1, l2 = S.kolatus_hole_lengths(4.0, 3.0, 0.2)
    assert float(l1) == pytest.approx(3.9 * 3**0.27 * 4**0.54 / (9.81**0.27 * 0.2**0.08), rel=1e-12)
    assert float(l2) == pytest.approx(2.7 * 3**0.45 * 4**0.9 / (9.81**0.45 * 0.2**0.8), rel=1e-12)


def test_hole_extent_at_repose():
    lo, hi = S.hole_extent_at_repose(0.095, 0.10, 45.0)
    assert float(lo) == pytest.approx(0.005) and float(hi) == pytest.approx(0.195)


# ----------------------------------------------------------------------------- the set-up
@pytest.mark.parametrize("grains", [S.SAND, S.PARTICLE])
def test_predictions_grow_with_q(grains):
    qs = np.array([0.06, 0.08, 0.11])
    p = S.predictions(qs, grains)
    for name, r in p["formulas"].items():
        assert np.all(np.diff(r["below_bed"]) > 0), name
        # a power law in q steeper than its nominal exponent: H and h grow with q too
        assert 0.5 < r["q_exponent_in_setup"] < 1.0, name
    table = S.table(p)
    assert table.count("\n") == len(S.FORMULAS) + 1


def test_every_formula_predicts_deeper_than_the_seed_layer():
    # the long-run depth of every formula exceeds the 0.095 m layer (docs/scour_setup.md):
    # the rigid bottom of the seed's layer caps the equilibrium scour
    p = S.predictions(np.array([0.06, 0.11]), S.PARTICLE)
    for r in p["formulas"].values():
        assert np.all(r["below_bed"] > 0.095)


def test_tailwater_override():
    # the CFD tailwater (deeper than the loss-free one) lowers H and the predicted depths
    hy = S.setup_hydraulics(0.06, h_tail=0.0647)
    assert hy.h_tail == 0.0647 and hy.head_drop == pytest.approx(hy.energy_up - 0.0647)
    free = S.predictions(np.array([0.06, 0.11]), S.PARTICLE)
    cfd = S.predictions(np.array([0.06, 0.11]), S.PARTICLE, h_tail=[0.0647, 0.1074])
    for name in S.FORMULAS:
        assert np.all(cfd["formulas"][name]["below_bed"] < free["formulas"][name]["below_bed"]), name


# ----------------------------------------------------------------------------- grain thresholds
def test_shields_soulsby_hand_calculation():
    # Soulsby (1997) eqs. 75-76, d = 1 mm quartz in water: D* = 0.001 (9.81 * 1.65 / 1e-12)^(1/3)
    # = 25.2959; theta = 0.30 / (1 + 30.355) + 0.055 (1 - exp(-0.50592)) = 0.009568 + 0.021838
    # = 0.031405; tau = 0.031405 * 1650 * 9.81 * 0.001 = 0.5083 Pa
    assert float(S.shields_critical(0.001)) == pytest.approx(0.031405, abs=2e-6)
    assert float(S.critical_shear_stress(0.001)) == pytest.approx(0.50835, abs=1e-4)
    # coarse grains: the curve's plateau 0.055
    assert float(S.shields_critical(0.5)) == pytest.approx(0.055, abs=1e-4)


def test_threshold_equivalent_grain_inverts_the_threshold():
    for d in (2e-4, 5e-3, 0.04):
        tau = float(S.critical_shear_stress(d))
        assert S.threshold_equivalent_grain(tau) == pytest.approx(d, rel=1e-9)
    with pytest.raises(ValueError):
        S.threshold_equivalent_grain(1e6)


def test_sph_bed_threshold_and_its_grain():
    # saturated mixture 1150 kg/m3 submerged, 5 mm, 33 deg: 1150 * 9.81 * 0.005 * tan 33 = 36.63 Pa
    tau = S.sph_bed_threshold(1150 * S.G, 0.005, 33.0)
    assert tau == pytest.approx(1150 * 9.81 * 0.005 * 0.649408, rel=1e-5)
    g = S.threshold_grains()
    assert float(S.critical_shear_stress(g.d50)) == pytest.approx(tau, rel=1e-9)
    assert 0.03 < g.d50 < 0.05  # a coarse gravel: the 5 mm bed is far stronger than sand
