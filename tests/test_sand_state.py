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
    """I_R against the twin over states from e_min to e_max and p' from 0 to 10 MPa; by hand, Bolton's own
    I_R where his implied line meets the critical line (the two differ only through the line)."""
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
        if twin is None:  # returned past the apex: the in-plane radius is all returned
            apex += 1
            assert fast[1] == pytest.approx(fast[2], abs=1e-6 * p) and fast[4] == 0.0
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
    assert hits > 100  # the plastic branch was exercised


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
