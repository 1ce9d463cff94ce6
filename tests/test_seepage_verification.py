"""The seepage verification cases (issue 10, item 4): CI-sized samples here, the default
resolutions and the resolution studies nightly. Tolerances and their sources live in the case
modules (verification/seepage_*.py)."""

import numpy as np
import pytest

from verification import (
    seepage_bed_at_rest,
    seepage_critical_gradient,
    seepage_darcy,
    seepage_sheet_pile,
    seepage_terzaghi,
)


def _failed(res, known=None):
    """The failed checks that are not the case's documented KNOWN_FAILURES (those the nightly
    report lists as known)."""
    return [c.line() for c in res.checks if not c.passed and c.metric not in (known or {})]


@pytest.mark.slow
def test_bed_at_rest_carries_effective_stress_both_formulations(tmp_path):
    """dx = 10 mm: the mixture carries gamma' z and hydrostatic pore pressure without drift; the
    seed carries its dry weight (the case pins that derived value, docs/seepage.md)."""
    res = seepage_bed_at_rest.run(10, out_dir=tmp_path)
    assert res.figure.is_file()
    assert not _failed(res), "\n".join(_failed(res))
    assert abs(res.series["seed"]["slope_ratio"] - seepage_bed_at_rest.dry_weight_ratio()) < 0.1


@pytest.mark.slow
@pytest.mark.parametrize("formulation", ["mixture", "seed"])
def test_darcy_draining_column(formulation):
    """Homogeneous draining column at dx = 10 mm: q = k i within 2 % (i = 1)."""
    r = seepage_darcy.run_one(10, formulation, layered=False)
    lay = r["layers"]["column"]
    assert abs(lay["error"]) <= seepage_darcy.TOLERANCE, (lay["q"], lay["i"])
    assert abs(lay["i"] - 1.0) < 0.1


@pytest.mark.slow
def test_darcy_stiff_drag_k_1e5_runs():
    """Issue 10 item 2: k = 1e-5 m/s (drag rate ~ 4e5 1/s) runs stably under the drag's dt limit
    and gives Darcy's flux; the run's cost (steps) is what the limit costs (docs/seepage.md)."""
    t_end = 0.01
    r = seepage_darcy.run_one(10, "mixture", layered=False, k=1e-5, t_end=t_end)
    lay = r["layers"]["column"]
    assert "drag" in r["dt_limit"]
    assert np.isfinite(lay["q"]) and abs(lay["error"]) <= seepage_darcy.TOLERANCE, (lay["q"], lay["i"])


def test_mixture_pore_pressure_operators_disagree_off_lattice():
    """The analysis behind the Darcy upper layer's miss (docs/seepage.md, case 2): on coincident
    lattices the water's own pressure pass and the buoyancy pair have the same normalisation
    (1.0105 at h = 1.3 dx), so the net n grad p carries it unamplified; with the pore water half a
    dx off the fixed skeleton the pair's falls to 0.985 and the net, amplified by 1 / n, to 1.049."""
    own, pair, net = seepage_darcy.pressure_force_factors(0.0)
    assert own == pytest.approx(1.0105, abs=1e-4) and pair == pytest.approx(own, abs=1e-9)
    assert net == pytest.approx(own, abs=1e-9)
    own, pair, net = seepage_darcy.pressure_force_factors(0.5)
    assert pair == pytest.approx(0.9852, abs=1e-4) and net == pytest.approx(1.0486, abs=1e-4)


@pytest.fixture(scope="module")
def terzaghi_ci():
    """dx = 10 mm, mixture, to T_v = 0.2: the early isochrones, where the goal's margin is thinnest and
    where the density diffusion's drain showed first (17 % at T_v = 0.1). The late ones (0.5, 1) cost
    80 % of a run to T_v = 1 and run nightly (below, and in the case at its default resolution)."""
    return seepage_terzaghi.run_one(10, "mixture", tv_list=(0.1, 0.2))


@pytest.mark.slow
def test_terzaghi_consolidation_runs_to_tv_0_2(terzaghi_ci):
    """From the undrained state to T_v = 0.2 without blow-up; the degree of consolidation grows with T_v
    and at T_v = 0.2 lies within 0.05 of the series' (the profile errors against it are the checks)."""
    tv = terzaghi_ci["tv"]
    assert list(tv) == [0.1, 0.2] and tv[0.2]["U"] > tv[0.1]["U"], [o["U"] for o in tv.values()]
    assert all(np.isfinite(o["u"]).all() for o in tv.values())
    assert abs(tv[0.2]["U"] - tv[0.2]["U_exact"]) < 0.05


@pytest.mark.slow
def test_terzaghi_early_profiles_meet_the_issue_goal(terzaghi_ci):
    """dx = 10 mm: the profile error is within the issue's 2 % at T_v = 0.1 and 0.2 (1.9 and 1.2 %
    measured; the T_v = 0.1 margin is thin: docs/seepage.md, case 3). Guards the pore water against the
    density diffusion, which drained the column 1.85 times too fast (17 % at T_v = 0.1: docs/seepage.md,
    "Density diffusion and pore water")."""
    errors = {tv: o["error"] for tv, o in terzaghi_ci["tv"].items()}
    assert all(e <= seepage_terzaghi.GOAL for e in errors.values()), errors


@pytest.mark.nightly
def test_terzaghi_meets_the_issue_goal_at_every_tv():
    """dx = 10 mm, to T_v = 1: the profile error is within the issue's 2 % at T_v = 0.1, 0.2, 0.5 and 1
    (1.9, 1.2, 0.5, 0.3 % measured) and the degree of consolidation grows with T_v."""
    res = seepage_terzaghi.run_one(10, "mixture")
    assert list(res["tv"]) == [0.1, 0.2, 0.5, 1.0]
    degrees = [o["U"] for o in res["tv"].values()]
    assert all(b > a for a, b in zip(degrees, degrees[1:])), degrees
    errors = {tv: o["error"] for tv, o in res["tv"].items()}
    assert all(e <= seepage_terzaghi.GOAL for e in errors.values()), errors


@pytest.mark.slow
def test_critical_gradient_seed_does_not_heave_above_ic():
    """dx = 5 mm, seed form aimed at 1.3 i_c (measured above i_c): no heave (no buoyancy: its skeleton
    carries its dry weight, onset expected at 1.61 i_c)."""
    seed = seepage_critical_gradient.run_one(12, 1.3, "seed")
    assert seed["i"] > seepage_critical_gradient.critical_gradient()
    assert not seed["heave"], (seed["i"], seed["rise_dx"])


@pytest.fixture(scope="module")
def critical_mixture():
    """dx = 5 mm, mixture (outflow pool, linear p^), aimed at 0.95 and 1.08 i_c (measured 0.953 and
    1.069 i_c, sigma' ratios 0.156 and 0.073: docs/seepage.md, case 4)."""
    return [seepage_critical_gradient.run_one(12, r, "mixture") for r in (0.95, 1.08)]


@pytest.mark.slow
def test_critical_gradient_mixture_onset_within_ten_percent_at_5mm(critical_mixture):
    """The case's check at 5 mm: stable at >= 0.9 i_c, quick at <= 1.1 i_c, so the onset lies within the
    issue's 10 % of i_c (the finer bracket, [1.005, 1.050] i_c, is the default run's); Darcy's law holds
    in the sample (5 %: the Darcy case's 2 % plus the sample's short fit band); no blow-up (the former
    one at the baffle, docs/seepage.md, "Pore water along a wall")."""
    below, above = critical_mixture
    for r in critical_mixture:
        assert abs(r["q"] / (seepage_critical_gradient.K * r["i_sample"]) - 1.0) < 0.05, r["q"]
    assert not below["heave"] and above["heave"], (below["stress_ratio"], above["stress_ratio"])
    checks = seepage_critical_gradient.checks({"mixture": critical_mixture, "seed": []})
    assert all(c.passed for c in checks), [c.line() for c in checks]


@pytest.mark.nightly
def test_critical_gradient_onset_mixture():
    """dx = 2.5 mm: the onset bracket of the quick condition within 10 % of i_c (docs/seepage.md, case 4;
    the default resolution, 5 mm, is checked by the nightly case run)."""
    res = seepage_critical_gradient.run(24, ratios={"mixture": (0.95, 1.1), "seed": ()})
    assert not _failed(res), "\n".join(_failed(res))


# -- nightly: every case at its default resolution, all checks; the resolution studies ------------
STUDIES = [
    seepage_bed_at_rest, seepage_darcy, seepage_terzaghi, seepage_critical_gradient, seepage_sheet_pile,
]  # fmt: skip
CASES = [
    seepage_bed_at_rest,
    seepage_darcy,
    seepage_terzaghi,
    seepage_critical_gradient,
    seepage_sheet_pile,
]
IDS = ["bed_at_rest", "darcy", "terzaghi", "critical_gradient", "sheet_pile"]


@pytest.mark.nightly
@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_nightly_case_at_default_resolution(case, tmp_path):
    res = case.run(case.DEFAULT_RESOLUTION, out_dir=tmp_path)
    known = getattr(case, "KNOWN_FAILURES", {})
    assert not _failed(res, known), "\n".join(_failed(res, known))


@pytest.mark.nightly
@pytest.mark.parametrize("case", STUDIES, ids=IDS)
def test_nightly_resolution_study(case, tmp_path):
    from verification.common import study_failures

    rows = case.study(out_dir=tmp_path)
    assert not study_failures(rows)
