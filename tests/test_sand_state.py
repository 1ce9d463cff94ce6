"""A sand with a state (issue 31; docs/sand.md): the state index and the plane-strain return against
their NumPy twins (tests/naive_sand.py), the return's flow rule by hand, the element tests of
verification/sand_element.py (Bolton's peaks, the critical state, static liquefaction), the plan and
the seed's switch, and the refusals of bad material input (file, key, reason, exit 2)."""

import math

import naive_sand as nv
import numpy as np
import pytest

from solver.physics.sand_state import plane_strain_return, relative_dilatancy_index, state_angles
from solver.sand_state import SandState
from verification import sand_element

TOY = SandState(void_ratio=0.8)
CSL = (TOY.min_void_ratio, TOY.max_void_ratio, TOY.critical_void_ratio, TOY.critical_lambda,
       TOY.critical_xi, TOY.reference_pressure, TOY.bolton_q)  # fmt: skip
K, G = 1.67e7, 7.7e6


def test_index_against_twin_and_bolton(rng):
    """I_R against the twin over states from e_min to e_max and p' from 0 to 10 MPa; by hand, its sign about
    the critical line, Bolton's clip, and the plane-strain angles of I_R = 1."""
    for _ in range(500):
        e, p = rng.uniform(0.6, 1.0), 10 ** rng.uniform(-1, 7) * rng.choice([0.0, 1.0], p=[0.05, 0.95])
        assert relative_dilatancy_index(e, p, *CSL) == pytest.approx(nv.bolton_index(e, p, *CSL), abs=1e-12)
    # on the critical line I_R = 0, loose of it < 0, dense of it > 0; clipped at 4 (Bolton 1986)
    p = 100e3
    e_c = nv.critical_void_ratio(p, *CSL[2:6])
    assert relative_dilatancy_index(e_c, p, *CSL) == pytest.approx(0.0, abs=1e-12)
    assert relative_dilatancy_index(e_c + 0.01, p, *CSL) < 0 < relative_dilatancy_index(e_c - 0.01, p, *CSL)
    assert relative_dilatancy_index(0.616, 1e3, *CSL) == 4.0
    sin_phi, sin_psi = state_angles(1.0, 33.0)
    assert math.degrees(math.asin(sin_phi)) == pytest.approx(38.0)  # phi_cv + 5 I_R, plane strain
    assert math.degrees(math.asin(sin_psi)) == pytest.approx(6.25)  # 5 I_R / 0.8


def test_plane_strain_return_against_twin(rng):
    """The kernel's closed form against the general formula in the principal frame, for random trial
    states (rotated in-plane, dilatant and contractive); the result lies on f = 0."""
    hits = apex = 0
    for _ in range(400):
        p = rng.uniform(-2e3, 2e5)
        s6 = rng.normal(0.0, 8e4, 6) * np.array([1, 1, 1, 1, 0, 0])
        s6[:3] -= s6[:3].mean()
        sin_phi = math.sin(math.radians(rng.uniform(15, 53)))
        sin_psi = math.sin(math.radians(rng.uniform(-25, 25)))
        fast = plane_strain_return(p, *s6, sin_phi, sin_psi, 0.0, K, G)
        twin = nv.plane_strain_return(p, s6, sin_phi, sin_psi, 0.0, K, G)
        if twin is None:  # at or past the apex: stress-free at the cut-off, a crack
            apex += 1
            assert fast[:7] == (0.0,) * 7 and fast[7] == fast[8] == pytest.approx(-p / K)
            continue
        p_n, s_n, dvol = twin
        assert fast[0] == pytest.approx(p_n, rel=1e-9, abs=1e-6)
        assert np.allclose(fast[1:7], s_n, rtol=1e-9, atol=1e-6)
        if dvol is not None and dvol != 0.0:
            hits += 1
            assert fast[7] == pytest.approx(dvol, rel=1e-9)
            sig = -fast[0] * np.eye(3) + nv.to_matrix(np.array(fast[1:7]))
            w = np.linalg.eigvalsh(-sig[:2, :2])
            f = 0.5 * (w[1] - w[0]) - 0.5 * (w[1] + w[0]) * sin_phi
            assert f == pytest.approx(0.0, abs=1e-6 * max(p, 1.0))
    assert hits > 100 and apex > 0  # the plastic and the apex branches were exercised


def test_in_plane_tension_under_out_of_plane_compression_cracks():
    """The blow-up of the first dry plunging run (t = 0.615 s): an in-plane tensile mean with a compressive
    sigma_zz (p > 0) has f > 0 at R = 0; the return must crack it, not divide by R = 0."""
    p, s6 = 1.0e3, np.array([2.0e3, 2.0e3, -4.0e3, 0.0, 0.0, 0.0])  # in-plane mean -1 kPa, sigma_zz 5 kPa
    out = plane_strain_return(p, *s6, math.sin(math.radians(40)), math.sin(math.radians(10)), 0.0, K, G)
    assert np.all(np.isfinite(out)) and out[:7] == (0.0,) * 7 and out[8] == pytest.approx(-p / K)


def test_flow_rule_dilatancy_by_hand():
    """An in-plane shear trial beyond the surface: the plastic volume change over the plastic shear
    (d eps_1 - d eps_3 = the radius returned / G) is sin(psi), Bolton's plane-strain dilatancy."""
    p, t = 1e5, 8e4  # sigma_xy = t on p: radius 8e4 > p sin(phi)
    sin_phi, sin_psi = math.sin(math.radians(40)), math.sin(math.radians(9))
    out = plane_strain_return(p, 0, 0, 0, t, 0, 0, sin_phi, sin_psi, 0.0, K, G)
    radius_back = t - abs(out[4])
    assert out[7] / (radius_back / G) == pytest.approx(sin_psi, rel=1e-12)


def test_element_tests_pass():
    """verification/sand_element.py at a coarse increment: every check (Bolton's peaks within 1 deg, the
    critical state, static liquefaction of a loose sand, the dense undrained gain)."""
    res = sand_element.run(1000)
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, failed


def test_constant_sand_fails_the_element_tests():
    """The checks can fail: the seed's sand (Mohr-Coulomb at a constant phi_cv, psi = 0) at the same
    material points neither peaks, dilates, contracts nor liquefies."""
    checks = {c.metric: c for c in sand_element.checks(sand_element.run_tests(500, with_state=False))}
    failing = [m for m, c in checks.items() if not c.passed]
    for part in ("peak phi - Bolton", "dense dilates", "dense peaks", "loose contracts", "liquefied"):
        assert any(part in m or part in checks[m].source for m in failing), (part, failing)


# ---- in the solver: a column of sand with a state ---------------------------------------------------


def sand_column(state=None, numerics=None, **bars):
    from verification.column_collapse import scene_at

    sand = {"friction_angle": 33.0, "yield_model": "mohr_coulomb", "dilatancy_angle": 0.0, **bars}
    if state is not None:
        sand["state"] = state
    # the default scheme: the column's own (column_collapse.SCHEME) is the seed's, which turns the state off
    return scene_at(
        0.01, 0.05, {"materials": {"bars": sand}, "numerics": {"scheme": "default", **(numerics or {})}}
    )


def final_state(scene):
    from solver.simulation import Simulation

    sim = Simulation(scene)
    sim.advance_to(scene.scene.end_time)
    sim.current_state()
    ps = sim.particles
    order = np.argsort(ps["id"][: ps.n_owned])
    return ps["x"][order].copy(), ps["eps_vp"][order].copy()


def test_column_of_dense_and_loose_sand():
    """The collapsing column in the solver: the dense sand dilates where it yields, the loose one contracts;
    the plan names Bolton's relations; numerics.sand_state = "none" (the seed's scheme) is the constant sand
    bit for bit."""
    from solver.plan import build_plan, explain

    dense, loose = sand_column({"void_ratio": 0.65}), sand_column({"void_ratio": 0.95})
    assert "Bolton (1986)" in explain(build_plan(dense), dense)
    _, eps_dense = final_state(dense)
    _, eps_loose = final_state(loose)
    assert eps_dense.max() > 1e-3 and eps_dense.min() >= 0.0  # I_R > 0 at every p' of a dense column
    assert eps_loose.min() < -1e-3
    switched = final_state(sand_column({"void_ratio": 0.65}, numerics={"sand_state": "none"}))
    constant = final_state(sand_column())
    assert "Bolton" not in explain(build_plan(sand_column()), sand_column())
    np.testing.assert_array_equal(switched[0], constant[0])


# ---- bad material input -----------------------------------------------------------------------------

SAND_SCENE = """
[scene]
name = "sand"
dimension = 2
spacing = 0.01
end_time = 0.01
gravity = [0.0, -9.81]

[domain]
min = [0.0, 0.0]
max = [0.2, 0.2]

[walls]
y_min = "no_slip"

[materials.sand]
model = "soil"
density = 1640.0
youngs_modulus = 2.0e7
poisson_ratio = 0.3
friction_angle = 33.0
cohesion = 0.0
yield_model = "{yield_model}"
grain_size = {grain_size}

[materials.sand.state]
void_ratio = {void_ratio}
critical_lambda = {lam}

[[blocks]]
name = "layer"
material = "sand"
shape = "rectangle"
min = [0.0, 0.0]
max = [0.1, 0.1]
"""
GOOD = dict(yield_model="mohr_coulomb", grain_size=5e-4, void_ratio=0.616, lam=0.019)
BAD = {
    "void ratio below e_min": (
        dict(void_ratio=0.47),
        "materials.sand.state",
        "outside the sand's e_min-e_max",
    ),
    "void ratio above e_max": (
        dict(void_ratio=1.08),
        "materials.sand.state",
        "outside the sand's e_min-e_max",
    ),
    "negative grain size": (dict(grain_size=-5e-4), "materials.sand.grain_size", "greater than 0"),
    "critical line crosses zero": (dict(lam=0.2), "materials.sand.state", "crosses zero below the crushing"),
    "drucker-prager": (
        dict(yield_model="drucker_prager"),
        "materials.sand.yield_model",
        "must be 'mohr_coulomb'",
    ),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_sand_is_refused_with_file_key_reason(tmp_path, case):
    from solver.scene import SceneError, load_scene

    change, key, reason = BAD[case]
    path = tmp_path / "sand.toml"
    path.write_text(SAND_SCENE.format(**{**GOOD, **change}))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.key == key and reason in err.value.reason and str(path) in str(err.value)


def test_good_sand_loads_and_bad_one_exits_2(tmp_path):
    import subprocess

    from conftest import ENV, SCOURSPH

    from solver.scene import load_scene

    path = tmp_path / "sand.toml"
    path.write_text(SAND_SCENE.format(**GOOD))
    assert load_scene(path).materials["sand"].state.void_ratio == 0.616
    path.write_text(SAND_SCENE.format(**{**GOOD, "void_ratio": 0.47}))
    out = tmp_path / "out"
    proc = subprocess.run([*SCOURSPH, "run", str(path), "--out", str(out), "--quiet"], capture_output=True,
                          text=True, env=ENV, cwd=tmp_path)  # fmt: skip
    assert proc.returncode == 2 and "materials.sand.state" in proc.stderr and str(path) in proc.stderr
    assert not out.exists()
