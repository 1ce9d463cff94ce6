"""Soil kernels (solver/physics/soil_*.py, artificial_stress.py) against hand-computed cases and
NumPy twins."""

import naive_soil as nv
import numpy as np
import pytest
from conftest import disordered_lattice

from solver.kernels import cubic_spline_normalisation, cubic_spline_w
from solver.materials import YieldModel
from solver.neighbors import CellGrid, CellList
from solver.physics.artificial_stress import artificial_stress, artificial_stress_force, tension_flags
from solver.physics.soil_rates import PAIR_COLUMNS, jaumann, soil_pair_terms, soil_rates
from solver.physics.soil_stress import return_map, soil_stress_state

K, G = 7.0e5, 3.2e5
DP, MC = int(YieldModel.DRUCKER_PRAGER), int(YieldModel.MOHR_COULOMB)


def params(phi, c, psi=0.0):
    t, tp = np.tan(np.radians(phi)), np.tan(np.radians(psi))
    return (
        K,
        G,
        t,
        c,
        t / np.sqrt(9 + 12 * t * t),
        3 * c / np.sqrt(9 + 12 * t * t),
        tp / np.sqrt(9 + 12 * tp * tp),
    )


def fast_map(p, s6, model, phi, c, psi=0.0):
    out = return_map(p, *s6, model, *params(phi, c, psi))
    return out[0], np.array(out[1:7]), out[7]


def j2root(s6):
    return np.sqrt(0.5 * (s6[0] ** 2 + s6[1] ** 2 + s6[2] ** 2) + s6[3] ** 2 + s6[4] ** 2 + s6[5] ** 2)


S_SHEAR = np.array([100.0, -100.0, 0.0, 50.0, 0.0, 0.0])  # sqrt(J2) = sqrt(1e4 + 2500) = 111.8 Pa


def test_elastic_state_is_unchanged():
    # DP, phi = 30: limit 3 alpha p = 3 * 0.16013 * 1000 = 480 Pa > 111.8 Pa
    for model in (DP, MC):
        p, s, dvol = fast_map(1000.0, S_SHEAR, model, 30.0, 0.0)
        assert p == 1000.0 and np.array_equal(s, S_SHEAR) and dvol == 0.0


def test_mohr_coulomb_scale_back_by_hand():
    # seed eq. (16): s_f = c + p tan(phi) = 10 + 100 tan(20 deg) = 46.397 Pa; sqrt(J2) = 111.80 Pa
    p, s, _ = fast_map(100.0, S_SHEAR, MC, 20.0, 10.0)
    sf = 10.0 + 100.0 * np.tan(np.radians(20.0))
    assert sf == pytest.approx(46.3970, abs=1e-4)
    assert p == 100.0
    np.testing.assert_allclose(s, S_SHEAR * sf / np.sqrt(12500.0), rtol=1e-14)
    assert j2root(s) == pytest.approx(sf, rel=1e-14)


def test_drucker_prager_associated_by_hand():
    # phi = 19.8, c = 0, psi = 0: alpha_phi = tan / sqrt(9 + 12 tan^2) = 0.110813; limit 3 alpha p at p = 200
    # Pa
    a = np.tan(np.radians(19.8)) / np.sqrt(9 + 12 * np.tan(np.radians(19.8)) ** 2)
    assert a == pytest.approx(0.110813, abs=1e-6)
    p, s, dvol = fast_map(200.0, S_SHEAR, DP, 19.8, 0.0)
    assert p == 200.0 and dvol == 0.0  # psi = 0: no plastic volume change
    assert j2root(s) == pytest.approx(3 * a * 200.0, rel=1e-12)  # lands on f = 0
    np.testing.assert_allclose(s / j2root(s), S_SHEAR / j2root(S_SHEAR), rtol=1e-12)  # radial return


def test_drucker_prager_dilatant_matches_twin_and_hand():
    # psi = 10 deg: dl = f / (G + 9 K a_phi a_psi), p rises by 3 K a_psi dl
    p, s, dvol = fast_map(200.0, S_SHEAR * 10, DP, 30.0, 50.0, psi=10.0)
    K_, G_, t, c, aphi, kc, apsi = params(30.0, 50.0, 10.0)
    f = j2root(S_SHEAR * 10) - kc - 3 * aphi * 200.0
    dl = f / (G_ + 9 * K_ * aphi * apsi)
    assert p == pytest.approx(200.0 + 3 * K_ * apsi * dl, rel=1e-12)
    assert dvol == pytest.approx(3 * apsi * dl, rel=1e-12)
    assert j2root(s) == pytest.approx(kc + 3 * aphi * p, rel=1e-10)
    p2, s2 = nv.return_map(200.0, S_SHEAR * 10, "drucker_prager", K_, G_, 30.0, 50.0, 10.0)
    assert p == pytest.approx(p2, rel=1e-12)
    np.testing.assert_allclose(s, s2, rtol=1e-10, atol=1e-9)


def test_apex_and_tension_cut_off():
    # c = 0, p < 0 (stretched): no tensile strength -> apex p = 0, s = 0; dvol restores p = 0 from eq. (17)
    p, s, dvol = fast_map(-50.0, S_SHEAR, DP, 30.0, 0.0)
    assert p == 0.0 and np.all(s == 0.0) and dvol == pytest.approx(50.0 / K)
    # cohesive DP: apex at p = -k_c / (3 alpha_phi) = -c / tan(phi)
    p, s, _ = fast_map(-1000.0, S_SHEAR, DP, 30.0, 100.0)
    assert p == pytest.approx(-100.0 / np.tan(np.radians(30.0)), rel=1e-12) and np.all(s == 0.0)
    # Mohr-Coulomb: cut-off p >= -c / tan(phi), then s_f = 0 there
    p, s, dvol = fast_map(-1000.0, S_SHEAR, MC, 30.0, 100.0)
    assert p == pytest.approx(-100.0 / np.tan(np.radians(30.0)), rel=1e-12)
    assert j2root(s) == pytest.approx(0.0, abs=1e-9)
    for model, name in ((DP, "drucker_prager"), (MC, "mohr_coulomb")):
        p2, s2 = nv.return_map(-1000.0, S_SHEAR, name, K, G, 30.0, 100.0)
        assert fast_map(-1000.0, S_SHEAR, model, 30.0, 100.0)[0] == pytest.approx(p2, rel=1e-12)


def test_random_states_match_twin_and_end_inside(rng):
    for _ in range(200):
        p = rng.uniform(-500, 2000)
        s6 = rng.normal(0, 400, 6)
        s6[:3] -= s6[:3].mean()
        for model, name in ((DP, "drucker_prager"), (MC, "mohr_coulomb")):
            phi, c = rng.uniform(10, 40), rng.uniform(0, 100)
            pf, sf, _ = fast_map(p, s6, model, phi, c)
            pn, sn = nv.return_map(p, s6, name, K, G, phi, c)
            assert pf == pytest.approx(pn, rel=1e-12, abs=1e-9)
            np.testing.assert_allclose(sf, sn, rtol=1e-10, atol=1e-8)


def test_jaumann_matches_seed_eq13_index_form(rng):
    for _ in range(50):
        s6 = rng.normal(size=6)
        L = rng.normal(size=(3, 3))
        W = 0.5 * (L - L.T)
        fast = np.array(jaumann(*s6, W[0, 1], W[0, 2], W[1, 2]))
        np.testing.assert_allclose(fast, nv.jaumann(s6, L), rtol=1e-12, atol=1e-14)


def test_jaumann_update_is_objective_under_rigid_rotation():
    """ds/dt = W s - s W for a rigid spin: the stress must rotate with the body, s(t) = Q s0 Q^T,
    with no change of its invariants. RK4 on the rate; the tolerance is RK4's error
    (dt Omega)^4 ~ 1e-10 times the number of steps, far above round-off and far below any
    error of a non-objective update (which would leave s unchanged: error O(1))."""
    s0 = np.array([3.0, -1.0, -2.0, 0.7, 0.0, 0.0])
    omega = 2.0  # rad/s about z: v = omega (-y, x)
    W = np.array([[0, -omega, 0], [omega, 0, 0], [0, 0, 0.0]])
    rate = lambda s: np.array(jaumann(*s, W[0, 1], W[0, 2], W[1, 2]))
    T, n = 0.6, 600
    dt = T / n
    s = s0.copy()
    for _ in range(n):
        k1 = rate(s)
        k2 = rate(s + 0.5 * dt * k1)
        k3 = rate(s + 0.5 * dt * k2)
        k4 = rate(s + dt * k3)
        s = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    th = omega * T
    Q = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    expected = nv.to_voigt(Q @ nv.to_matrix(s0) @ Q.T)
    np.testing.assert_allclose(s, expected, atol=1e-9)
    assert j2root(s) == pytest.approx(j2root(s0), rel=1e-9)


SUSPENDED_AV = (0.01, 0.05)  # a water-like (alpha, beta) for the pairs with suspended soil


def run_soil_rates(targets, start, index, x, v, rho, p, s, mass, *rest):
    """The two kernels of the SoilRates term: the per-row table, then the pair pass, with the
    lists' unsigned views as the term passes them (NeighbourList.unsigned)."""
    pair = np.empty((len(x), PAIR_COLUMNS))
    soil_pair_terms(len(x), rho, p, s, mass, pair)
    soil_rates(targets, start.view(np.uint64), index.view(np.uint32), x, v, rho, s, pair, *rest)


def test_soil_pair_terms_match_twin(rng):
    """The per-row table: sigma / rho^2 (eq. 12) in the Voigt order of its columns, m / rho, m."""
    n = 40
    rho = 2000 * (1 + rng.uniform(-0.05, 0.05, n))
    p = rng.uniform(-500, 3000, n)
    s = rng.normal(0, 500, (n, 6))
    mass = rng.uniform(0.1, 0.3, n)
    pair = np.full((n + 3, PAIR_COLUMNS), np.nan)
    soil_pair_terms(n, rho, p, s, mass, pair)
    sig = s - p[:, None] * np.array([1, 1, 1, 0, 0, 0])
    q = sig / rho[:, None] ** 2  # (xx, yy, zz, xy, yz, xz)
    expected = np.column_stack([q[:, 0], q[:, 1], q[:, 3], mass / rho, mass, q[:, 2], q[:, 4], q[:, 5]])
    np.testing.assert_allclose(pair[:n], expected, rtol=1e-14)
    assert np.isnan(pair[n:]).all()  # rows beyond n untouched


def _lists(x, h):
    radius = 2 * h
    lo, hi = x.min(axis=0) - h, x.max(axis=0) + h
    cl = CellList(CellGrid.covering(lo, hi, radius, pad=radius))
    cl.bin(x, len(x))
    return cl.neighbour_list(x, np.arange(len(x), dtype=np.int64), radius)


@pytest.mark.parametrize(
    "with_av,with_art,dim,mixed,with_suspended",
    [
        (False, False, 2, True, False),
        (True, False, 2, True, False),
        (True, True, 2, True, False),
        (True, True, 2, False, False),
        (True, True, 3, True, False),
        (True, True, 3, False, False),
        (True, False, 2, False, True),
        (True, False, 3, True, True),
    ],
)
def test_soil_rates_match_twin(rng, with_av, with_art, dim, mixed, with_suspended):
    """mixed False (None to the kernel): the one-soil-material path (AV constants of the target for
    every pair). with_suspended: a third of the particles are suspended (erosion), their pairs take the
    water's AV constants."""
    dx, h = 0.01, 0.013
    x = disordered_lattice(8 if dim == 2 else 5, dim, dx, rng)
    n = len(x)
    v = rng.normal(0, 0.3, (n, dim))
    rho = 2000 * (1 + rng.uniform(-0.01, 0.01, n))
    p = rng.uniform(0, 3000, n)
    s = rng.normal(0, 500, (n, 6))
    if dim == 2:
        s[:, 4:] = 0.0  # plane strain: no out-of-plane shear
    mass = rho * dx**dim
    art = rng.normal(0, 1e-4, (n, 6)) if with_art else None
    if with_art:
        if dim == 2:
            art[:, 4:] = 0.0
        art[rng.random(n) < 0.5] = 0.0  # compressed particles (R = 0): the kernel skips pairs of two
    mat = np.zeros(n, dtype=np.int32)
    c = np.array([20.0])
    av = np.array([1.0]) if with_av else None
    suspended = (rng.random(n) < 1 / 3).astype(np.uint8) if with_suspended else None
    nl = _lists(x, h)
    norm = cubic_spline_normalisation(dim, h)
    w_dx = cubic_spline_w(dx, h, norm)
    drho, acc, ds = np.zeros(n), np.zeros((n, dim)), np.zeros((n, 6))
    run_soil_rates(
        nl.targets,
        nl.start,
        nl.index,
        x,
        v,
        rho,
        p,
        s,
        mass,
        mat,
        c,
        np.array([G]),
        h,
        norm,
        drho,
        acc,
        ds,
        av,
        av,
        True if dim == 3 else None,
        True if mixed else None,
        None,  # shear_rate (mu(I) soils only)
        suspended,
        *SUSPENDED_AV,
    )
    if with_art:  # the artificial stress force is a pass (term) of its own
        flags = np.zeros(n, np.uint8)
        tense = (art != 0.0).any(axis=1)
        assert tension_flags(n, art, flags) == tense.sum()  # the count that lets the term skip the pass
        np.testing.assert_array_equal(flags, tense)
        artificial_stress_force(
            nl.targets, nl.start, nl.index, x, mass, art, flags, h, norm, 2.55, 1.0 / w_dx, acc,
            True if dim == 3 else None,
        )  # fmt: skip
    d2, a2, s2 = nv.soil_rates(
        x, v, rho, p, s, mass, 20.0, G, h, 1.0 if with_av else 0.0, 1.0 if with_av else 0.0, art, 2.55, w_dx,
        suspended, SUSPENDED_AV,
    )  # fmt: skip
    np.testing.assert_allclose(drho, d2, rtol=1e-9, atol=1e-9 * np.abs(d2).max())
    np.testing.assert_allclose(acc, a2, rtol=1e-9, atol=1e-9 * np.abs(a2).max())
    np.testing.assert_allclose(ds, s2, rtol=1e-9, atol=1e-9 * np.abs(s2).max())


def test_soil_stress_state_and_artificial_stress_match_twins(rng):
    n = 64
    rows = np.arange(n, dtype=np.int64)
    rho = 2000 * (1 + rng.uniform(-0.02, 0.02, n))
    s = rng.normal(0, 500, (n, 6))
    s[:, 4:] = 0
    s[:, :3] -= s[:, :3].mean(axis=1, keepdims=True)
    s0 = s.copy()
    mat = np.zeros(n, dtype=np.int32)
    pr = params(25.0, 20.0)
    mean = np.zeros(n)
    soil_stress_state(
        rows,
        rho,
        s,
        mat,
        np.array([2000.0]),
        *[np.array([q]) for q in pr],
        np.array([DP], dtype=np.int32),
        mean,
        None,
        False,
    )
    for i in range(n):
        pn, sn = nv.return_map(K * (rho[i] / 2000 - 1), s0[i], "drucker_prager", K, G, 25.0, 20.0)
        assert mean[i] == pytest.approx(pn, rel=1e-12, abs=1e-9)
        np.testing.assert_allclose(s[i], sn, rtol=1e-10, atol=1e-8)
    art = np.zeros((n, 6))
    p = rng.uniform(-2000, 2000, n)
    artificial_stress(rows, rho, p, s0, 0.5, art)
    for i in range(n):
        np.testing.assert_allclose(
            art[i], nv.artificial_stress(p[i], s0[i], rho[i], 0.5), rtol=1e-9, atol=1e-16
        )


def test_artificial_stress_in_3d_matches_twin(rng):
    """3D: the positive part of the full stress by Jacobi rotations against numpy's eigh, on
    random states with all six components, and on states with repeated principal stresses
    (isotropic, axisymmetric, zero), where closed-form eigenvectors break down."""
    from solver.tensors import positive_part

    n = 64
    rows = np.arange(n, dtype=np.int64)
    rho = 2000 * (1 + rng.uniform(-0.02, 0.02, n))
    s = rng.normal(0, 500, (n, 6))
    s[:, :3] -= s[:, :3].mean(axis=1, keepdims=True)
    p = rng.uniform(-2000, 2000, n)
    s[:3], p[:3] = 0.0, [-700.0, 0.0, 300.0]  # isotropic tension, zero, isotropic compression
    s[3], p[3] = [200.0, -100.0, -100.0, 0, 0, 0], 0.0  # axisymmetric: two equal principal stresses
    art = np.zeros((n, 6))
    artificial_stress(rows, rho, p, s, 0.5, art, True)
    for i in range(n):
        np.testing.assert_allclose(
            art[i],
            nv.artificial_stress(p[i], s[i], rho[i], 0.5, dim=3),
            rtol=1e-9,
            atol=1e-12 * 0.5 * np.abs(s[i]).sum() / rho[i] ** 2 + 1e-300,
        )
    sym = np.array([3.0, 1.0, -2.0, 0.5, -0.7, 1.1])
    lam, vec = np.linalg.eigh(nv.to_matrix(sym))
    expected = nv.to_voigt(sum(max(lam[a], 0) * np.outer(vec[:, a], vec[:, a]) for a in range(3)))
    np.testing.assert_allclose(positive_part(*sym), expected, rtol=1e-12, atol=1e-14)


def test_single_shear_elastic_then_plastic_plateau():
    """Simple shear v_x = gamma_dot y at constant p, integrated with the kernel's own
    Hooke-Jaumann rate (soil_rates on a lattice, centre particle) and the return mapping
    after each step, as in the solver. Elastic branch: s_xy = G gamma (Jaumann terms
    O(gamma^2)); then the plateau sqrt(J2) = 3 alpha_phi p (Bui et al. 2008, c = 0) with
    s_xx, s_yy of the order gamma * s_xy only (the Jaumann rotation terms; radial return
    keeps the direction). Catches a return mapping that does not land on f = 0 or that maps
    an elastic state, and a strain rate twice or half the right one (elastic slope G).
    The sign of the Jaumann terms is checked by the rigid-rotation test above."""
    dx, h, dim = 0.01, 0.013, 2
    g = np.arange(-3, 4) * dx
    x = np.array([(a, b) for a in g for b in g])
    centre = int(np.argmin(np.linalg.norm(x, axis=1)))
    rate = 2.0  # 1/s
    v = np.column_stack([rate * x[:, 1], np.zeros(len(x))])
    n = len(x)
    rho = np.full(n, 2650.0)
    mass = rho * dx * dx
    mat = np.zeros(n, dtype=np.int32)
    nl = _lists(x, h)
    norm = cubic_spline_normalisation(dim, h)
    p = 1000.0
    pr = params(19.8, 0.0)
    a_phi = pr[4]
    s = np.zeros(6)
    dt = 1e-5
    ds_rows = np.zeros((n, 6))
    gamma_elastic_end = 3 * a_phi * p / G  # s_xy reaches the limit at gamma = 3 a p / G
    history = []
    for k in range(int(3 * gamma_elastic_end / (rate * dt))):
        S = np.tile(s, (n, 1))
        run_soil_rates(
            nl.targets,
            nl.start,
            nl.index,
            x,
            v,
            rho,
            np.full(n, p),
            S,
            mass,
            mat,
            np.array([20.0]),
            np.array([G]),
            h,
            norm,
            np.zeros(n),
            np.zeros((n, dim)),
            ds_rows,
        )
        s = s + dt * ds_rows[centre]
        out = return_map(p, *s, DP, *pr)
        s = np.array(out[1:7])
        history.append(((k + 1) * dt * rate, s.copy()))
    gam = np.array([hh[0] for hh in history])
    sxy = np.array([hh[1][3] for hh in history])
    # SPH gradient of a linear field on a lattice is exact to the kernel's moment error (< 2 %)
    early = gam < 0.5 * gamma_elastic_end
    slope = np.polyfit(gam[early], sxy[early], 1)[0]
    assert slope == pytest.approx(G, rel=0.02)
    assert j2root(history[-1][1]) == pytest.approx(3 * a_phi * p, rel=1e-12)  # on the yield surface
    assert np.abs(history[-1][1][:3]).max() < 1e-3 * 3 * a_phi * p  # still pure shear
