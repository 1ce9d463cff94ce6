"""The plunging scour set-up (issue 24 item 4; docs/scour_plunging.md): the scenes through the
study's machinery, the convergence verdict, and a coarse run that plunges and erodes."""

import json

import numpy as np
import pytest

from solver.scene import parse_scene
from verification import scour_plunging as sp
from verification import scour_study as st
from verification.analytic.scour_formulas import critical_depth, rand_1955_drop


def test_the_plunging_cases_are_the_shipped_scenes_with_q_dx_and_end_changed():
    raw = st.scene_raw("saturated", 0.08, 0.0025, 0.5, setup="plunging")
    assert raw["scene"]["name"] == "plunging_state_saturated_q0.08_dx2.5mm"
    assert st.case_name("dry", 0.11, 0.005, setup="plunging") == "plunging_state_dry_q0.11_dx5mm"
    # issue 24's runs keep their names under the seed's sand, whose scenes differ only in the sand
    assert st.case_name("dry", 0.11, 0.005, setup="plunging_seed_sand") == "plunging_dry_q0.11_dx5mm"
    seed = st.scene_raw("saturated", 0.08, 0.0025, 0.5, setup="plunging_seed_sand")
    assert seed["materials"]["sand"]["density"] == 1800.0 and "state" not in seed["materials"]["sand"]
    assert raw["materials"]["sand"]["state"]["void_ratio"] == 0.988  # e_max: the seed's loose sand, capped
    assert {k: v for k, v in seed.items() if k not in ("materials", "scene")} == {
        k: v for k, v in raw.items() if k not in ("materials", "scene")
    }
    assert raw["inlets"][0]["discharge"] == 0.08 and raw["scene"]["spacing"] == 0.0025
    scene = parse_scene(raw, st.SETUPS["plunging"].scene_path("saturated"))
    assert scene.materials["sand"].grain_size == 5e-4  # it erodes
    longer = st.scene_raw("dry", 0.11, 0.005, 0.5, length=0.8, setup="plunging")
    assert longer["blocks"][0]["max"][0] == pytest.approx(0.8)
    assert longer["outlets"][0]["min"][0] == pytest.approx(0.8)


def test_the_fall_makes_every_q_of_the_seed_plunge():
    """Rand (1955): the pool under the nappe is shallower than the drop when D = q^2/(g dz^3) < 1,
    i.e. dz > y_c; the scenes' crown stands sp.FALL above the soil."""
    raw = st.scene_raw("saturated", 0.11, 0.005, 0.5, setup="plunging")
    crown = raw["inlets"][0]["origin"][1]
    soil_top = raw["blocks"][0]["max"][1]
    assert crown - soil_top == pytest.approx(sp.FALL)
    q = np.array(st.Q_ALL)
    geometry = rand_1955_drop(q, sp.FALL)
    assert np.all(geometry["drop_number"] < 1) and np.all(geometry["pool_depth"] < sp.FALL)
    assert np.all(critical_depth(q) < sp.FALL)
    # the nappe's lowest streamline reaches the soil at t = 0: the fall time, to the scenes' 0.1 ms
    assert raw["inlets"][0]["prefill_time"] == pytest.approx(np.sqrt(2 * sp.FALL / 9.81), abs=1e-4)


def _fake_case(soil, dx, scale):
    t = np.linspace(0.0, 1.0, 41)
    d = scale * 0.03 * np.sqrt(t)
    return {"soil": soil, "q": sp.CONVERGENCE_Q, "dx": dx, "t": t, "d_nappe": d, "t_reached": 1.0}


def test_the_convergence_verdict_reads_the_differences_to_the_finest_spacing():
    cases = [_fake_case("saturated", 0.005, 1.08), _fake_case("saturated", 0.0035, 0.97)]
    cases += [_fake_case("saturated", 0.0025, 1.0)]
    rows = sp.convergence_rows(cases)
    assert [r["t"] for r in rows] == list(sp.CONVERGENCE_TIMES)
    for r in rows:
        assert r["ref"] == sp.DX_FINE
        assert r[f"rel_{sp.DX}"] == pytest.approx(0.08) and r[f"rel_{sp.DX_MID}"] == pytest.approx(-0.03)
    # no 2.5 mm run: 5 mm is read against 3.5 mm, and the table says the row is no three-spacing test
    rows = sp.convergence_rows(cases[:2])
    assert [r["t"] for r in rows] == list(sp.CONVERGENCE_TIMES)
    for r in rows:
        assert r["ref"] == sp.DX_MID and r[f"rel_{sp.DX}"] == pytest.approx((1.08 - 0.97) / 0.97)
    lines = "\n".join(sp._convergence_section(rows))
    assert "not reached" in lines and "(5 vs 3.5 mm only)" in lines
    assert not sp.convergence_rows(cases[:1])  # one spacing: nothing to compare against


@pytest.mark.slow
def test_a_coarse_plunging_run_erodes_and_carries_the_sand_away(tmp_path):
    """10 mm to 0.25 s (about a minute): the nappe lands, the sand erodes at the bed (the top row, 10 mm
    thick, wears through from about 0.2 s), picked-up sand moves off downstream, no particle leaks through
    a body and the volume balance closes."""
    from solver.output.hdf5_writer import read_series
    from solver.run import run_scene

    raw = st.scene_raw("saturated", 0.11, 0.01, 0.25, setup="plunging")
    raw["output"]["render"] = False
    scene = parse_scene(raw, st.SETUPS["plunging"].scene_path("saturated"))
    run_scene(scene, tmp_path / "run", quiet=True)
    report = json.loads((tmp_path / "run" / "run.json").read_text())
    assert report["body_leaks"] == 0
    dv = 0.01**2
    for name, balance in report["volume_balance"]["materials"].items():
        assert abs(balance["residual"]) < dv, name  # within one particle volume (README, Scenes)
    t, last = read_series(tmp_path / "run" / "particles.h5")[-1]
    assert t == pytest.approx(0.25)
    sand = last["material"] == 1
    moved = sand & (last["suspended"] == 1)
    assert moved.sum() > 0
    assert np.mean(last["velocity"][moved, 0]) > 0  # carried downstream, away from the jet


def test_a_model_variant_gets_its_own_convergence_table():
    """Runs with scene overrides (a variant) are read on their own: their rows name the variant and
    compare its spacings with each other, never with the base model's."""
    sets = ("materials.sand.dilatancy_angle=10.0",)
    cases = []
    for dx, scale in ((0.005, 1.05), (0.0035, 0.98), (0.0025, 1.0)):
        c = _fake_case("saturated", dx, scale) | {"sets": list(sets), "case": f"v_{dx}", "x_nappe": [0.2]}
        c |= {"d": c["d_nappe"], "steps": 1, "particles_end": 1, "cpu_s": 1.0, "wall_s": 1.0}
        cases.append(c)
    text = "\n".join(sp._variant_section(sets, cases))
    assert "## Variant: `materials.sand.dilatancy_angle=10.0`" in text
    assert "+5.0 %" in text and "-2.0 %" in text and "| no |" not in text


def test_the_curve_difference_is_the_mean_gap_over_the_mean_depth():
    """d = s * 0.03 sqrt(t) at each spacing: the mean |d(5 mm) - d(2.5 mm)| / mean d(2.5 mm) is
    |s - 1| exactly, and so is the largest pointwise difference."""
    cases = [_fake_case("dry", 0.005, 1.08), _fake_case("dry", 0.0035, 0.97), _fake_case("dry", 0.0025, 1.0)]
    (row,) = sp.curve_differences(cases)
    assert row["end"] == pytest.approx(1.0)
    assert row[sp.DX] == pytest.approx((0.08, 0.08)) and row[sp.DX_MID] == pytest.approx((0.03, 0.03))
    assert "| dry | 1 | 8.0 % (8.0 %) | 3.0 % (3.0 %) | yes |" in "\n".join(sp._curve_section([row]))
