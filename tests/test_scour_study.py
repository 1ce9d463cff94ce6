"""verification/scour_study.py's variants: --set overrides named in the case and applied to the
scene, the MPI rank tag, and the "hole stops deepening" measure (no run: these are cheap)."""

import numpy as np
import pytest

from solver.errors import SceneError
from solver.scene import parse_scene
from verification import scour_study as st


def test_a_variant_is_named_by_its_overrides_and_ranks():
    assert st.case_name("saturated", 0.11, 0.005) == "saturated_q0.11_dx5mm"
    sets = [st.SENSITIVITY["phi 28"], st.SENSITIVITY["k /10"]]
    assert st.case_name("saturated", 0.11, 0.005, sets=sets) == (
        "saturated_q0.11_dx5mm_friction_angle28.0_permeability1.0e-4"
    )
    assert st.case_name("dry", 0.06, 0.005, ranks=2) == "dry_q0.06_dx5mm_np2"


def test_the_overrides_reach_the_scene_and_nothing_else_changes():
    base = st.scene_raw("saturated", 0.11, 0.005, 0.5)
    raw = st.scene_raw("saturated", 0.11, 0.005, 0.5, sets=[st.SENSITIVITY["K x2"]])
    assert raw["materials"]["sand"]["bulk_modulus"] == 1.112e7
    assert raw["scene"]["name"] == "saturated_q0.11_dx5mm_bulk_modulus1.112e7"
    raw["materials"]["sand"]["bulk_modulus"] = base["materials"]["sand"]["bulk_modulus"]
    raw["scene"]["name"] = base["scene"]["name"]
    assert raw == base
    for name, item in st.SENSITIVITY.items():  # every variant is a valid scene
        scene = parse_scene(st.scene_raw("saturated", 0.11, 0.005, 0.5, sets=[item]), st.SCENES / "x.toml")
        key, _, value = item.partition("=")
        assert getattr(scene.materials["sand"], key.rsplit(".", 1)[-1]) == pytest.approx(float(value)), name


def test_a_bad_override_names_its_key():
    with pytest.raises(SceneError, match="inlets.7.discharge"):
        st.scene_raw("dry", 0.11, 0.005, 0.5, sets=["inlets.7.discharge=0.1"])


def test_steady_change_over_the_last_half_second():
    t = np.linspace(0.0, 2.0, 81)
    case = {"t": t, "d": 0.002 * (1 - np.exp(-t / 0.2))}
    expected = (case["d"][-1] - np.interp(1.5, t, case["d"])) / case["d"][-1]
    assert st.steady_change(case) == pytest.approx(expected)
    assert st.steady_change(case) < st.STEADY_CHANGE
    assert np.isnan(st.steady_change({"t": t[:5], "d": case["d"][:5]}))  # shorter than the window


def test_q_exponent_fit_recovers_a_power_law_and_its_scatter():
    qs = np.array([0.06, 0.07, 0.08, 0.09, 0.10, 0.11])
    e, se, n = st.q_exponent_fit(qs, 0.3 * qs**0.7)
    assert (e, n) == (pytest.approx(0.7), 6) and se == pytest.approx(0.0, abs=1e-12)
    # scatter: the standard error is the textbook one, sqrt(s^2 / Sxx)
    ds = 0.3 * qs**0.7 * np.array([1.1, 0.9, 1.05, 0.95, 1.0, 1.02])
    e, se, n = st.q_exponent_fit(qs, ds)
    x, y = np.log(qs), np.log(ds)
    b, a = np.polyfit(x, y, 1)
    s2 = np.sum((y - a - b * x) ** 2) / 4
    assert se == pytest.approx(np.sqrt(s2 / np.sum((x - x.mean()) ** 2)))
    assert np.isnan(st.q_exponent_fit(qs[:2], ds[:2])[1])  # two points: no error estimate
    assert st.q_exponent_fit(qs, np.where(qs > 0.07, ds, 0.0))[2] == 4  # zero depths left out


def test_formula_exponents_leave_out_formulas_outside_their_grain_range():
    fx = st.formula_exponents()
    assert not any(k.startswith("Veronese 1937 A, medium sand") for k in fx)
    assert not any(k.startswith("Veronese 1937 B, grain with") for k in fx)
    assert not any(k.startswith("Tschopp (Bezzola 2012), grain with") for k in fx)  # no scour at q = 0.06
    assert all(np.all(below > 0) for _, below in fx.values())


def _profiles_csv(path, x, t, z):
    with open(path, "w") as fh:
        fh.write("x_m," + ",".join(f"z_s(t={v:.4g})" for v in t) + "\n")
        for k, xk in enumerate(x):
            fh.write(f"{xk:.6g}," + ",".join(f"{v:.6g}" for v in z[k]) + "\n")


def test_the_nappe_zone_leaves_out_the_end_wall_trough(tmp_path):
    from verification import scour_zones as sz

    x = (np.arange(50) + 0.5) * 0.005  # the 0.25 m layer's bins
    t = np.array([0.0, 1.0, 2.0])
    z = np.full((50, 3), 0.095)
    z[14, 1:] -= 0.0003  # the nappe's dent at x = 0.0725 m
    z[44, 2] -= 0.005  # the end wall's trough at x = 0.2225 m (0.0275 m before the wall)
    z[3, 2] -= 0.0004  # a dip beside the caisson's face at x = 0.0175 m (the face zone)
    d, xs, d_face = sz.zone_series(x, t, z)
    assert d == pytest.approx([0.0, 0.0003, 0.0003])
    assert xs[2] == pytest.approx(0.0725)
    assert d_face == pytest.approx([0.0, 0.0, 0.0004])
    assert sz.whole_layer_depth(z)[2] == pytest.approx(0.005)
    zone = x[(x >= sz.FACE_ZONE) & (x <= 0.25 - sz.WALL_ZONE + 1e-12)]
    assert zone.min() == pytest.approx(0.0325) and zone.max() == pytest.approx(0.1475)  # 0.03-0.15 m
    assert not sz.at_zone_edge(xs, 0.25, 0.005).any()
    # the study's copy gains the zone columns; another run's profiles are refused
    prof, copy = tmp_path / "p.csv", tmp_path / "c_scour.csv"
    _profiles_csv(prof, x, t, z)
    copy.write_text("t_s,depth_m\n0,0\n1,0.0003\n2,0.005\n")
    sz.add_zone_columns(copy, prof)
    rows = copy.read_text().splitlines()
    assert rows[0] == "t_s,depth_m,depth_nappe_m,x_deepest_nappe_m,depth_face_m"
    assert rows[3].startswith("2,0.005,0.0003,0.0725,0.0004")
    copy.write_text("t_s,depth_m\n0,0\n1,0.0003\n2,0.0051\n")
    with pytest.raises(ValueError, match="another run"):
        sz.add_zone_columns(copy, prof)


def test_a_layer_above_0_1_m_is_matched_to_its_profiles_rounding(tmp_path):
    """Profiles keep 6 significant digits: z = 0.105 m is known to 1 um, not 0.1 um. The plunging
    layer's run (0.105 m deep) differed from its own profiles by 0.39 um and was refused as another
    run; a real difference (10 um) still is."""
    from verification import scour_zones as sz

    x = (np.arange(126) + 0.5) * 0.005
    t = np.array([0.0, 1.0])
    z = np.full((126, 2), 0.105)
    z[40, 1] = 0.105 - 0.02923386  # a hole whose rounded profile reads 0.0757661 (1e-7 m steps)
    prof, copy = tmp_path / "p.csv", tmp_path / "c_scour.csv"
    _profiles_csv(prof, x, t, z)
    copy.write_text("t_s,depth_m\n0,0\n1,0.02923386\n")
    sz.add_zone_columns(copy, prof)
    z[:, 0] = 0.1051234  # rounded to 0.105123: 0.4 um off, within the rounding of z > 0.1 m
    z[40, 1] = 0.1051234 - 0.02923386
    _profiles_csv(prof, x, t, z)
    copy.write_text("t_s,depth_m\n0,0\n1,0.02923386\n")
    sz.add_zone_columns(copy, prof)
    copy.write_text("t_s,depth_m\n0,0\n1,0.02924386\n")
    with pytest.raises(ValueError, match="another run"):
        sz.add_zone_columns(copy, prof)
