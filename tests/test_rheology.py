"""The mu(I) rheology of yielded soil (issue 24 item 1; docs/rheology.md): the friction law and the
raised return mapping against their NumPy twins (tests/naive_soil.py) and by hand, the shear rate of
the soil pass against an all-pairs twin, a shear-rate sweep of one particle's stress update against
mu(I) itself, the plan (no shear rate without mu(I), none in the seed's scheme), scene refusals, and
the seed's scheme reproducing the perfectly plastic collapse bit for bit."""

import naive_soil as nv
import numpy as np
import pytest
from conftest import disordered_lattice

from solver.kernels import cubic_spline_normalisation
from solver.materials import YieldModel
from solver.neighbors import CellGrid, CellList
from solver.physics.soil_rates import PAIR_COLUMNS, soil_pair_terms, soil_rates
from solver.physics.soil_stress import rate_friction, return_map, soil_stress_state
from solver.scene import SceneError

K, G = 7.0e5, 3.2e5
DP, MC = int(YieldModel.DRUCKER_PRAGER), int(YieldModel.MOHR_COULOMB)
D_MU, I0 = 0.26, 0.279  # Jop, Forterre & Pouliquen (2005): glass beads, the defaults
D50, RHO_GRAIN = 1.0e-3, 2650.0
INERTIA = D50 * np.sqrt(RHO_GRAIN)  # d50 sqrt(rho_grain), what the kernels take


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


def j2root(s6):
    return np.sqrt(0.5 * (s6[0] ** 2 + s6[1] ** 2 + s6[2] ** 2) + s6[3] ** 2 + s6[4] ** 2 + s6[5] ** 2)


# ---- the friction law ------------------------------------------------------------------------------


def test_rate_friction_is_jop_mu_of_i(rng):
    """mu(I) - mu_s against the twin written from I = gamma_dot d / sqrt(p / rho_grain) and Jop et al.'s
    law, over six decades of I; by hand at I = I_0 (half the increment) and in the limits."""
    for _ in range(300):
        p, rate = 10 ** rng.uniform(0, 5), 10 ** rng.uniform(-3, 3)
        fast = rate_friction(p, rate, D_MU, I0, INERTIA)
        assert fast == pytest.approx(nv.rate_friction(p, rate, D_MU, I0, D50, RHO_GRAIN), rel=1e-13)
    p = 1000.0
    rate_at_i0 = I0 * np.sqrt(p / RHO_GRAIN) / D50  # I = I_0 -> (mu_2 - mu_s) / 2
    assert rate_friction(p, rate_at_i0, D_MU, I0, INERTIA) == pytest.approx(D_MU / 2, rel=1e-14)
    assert rate_friction(p, 1e12, D_MU, I0, INERTIA) == pytest.approx(D_MU, rel=1e-9)  # I -> inf: mu_2
    for args in ((p, 0.0), (0.0, 5.0), (-50.0, 5.0)):  # at rest, unconfined, in tension: no increment
        assert rate_friction(*args, D_MU, I0, INERTIA) == 0.0
    assert rate_friction(p, 5.0, 0.0, I0, INERTIA) == 0.0  # perfectly plastic soil


S_SHEAR = np.array([100.0, -100.0, 0.0, 50.0, 0.0, 0.0])


def fast_map(p, s6, model, phi, c, psi=0.0, rate=0.0):
    out = return_map(p, *s6, model, *params(phi, c, psi), D_MU, I0, INERTIA, rate)
    return out[0], np.array(out[1:7])


def test_raised_mohr_coulomb_by_hand():
    """s_f = c + p tan(phi) + (mu(I) - mu_s) p: at p = 100 Pa, phi = 20, c = 10, I = I_0 it is
    10 + 36.397 + 0.13 x 100 = 59.397 Pa, below sqrt(J2) = 111.8 Pa: scaled back onto it."""
    p = 100.0
    rate = I0 * np.sqrt(p / RHO_GRAIN) / D50
    _, s = fast_map(p, S_SHEAR, MC, 20.0, 10.0, rate=rate)
    assert j2root(s) == pytest.approx(10.0 + 100.0 * np.tan(np.radians(20.0)) + 0.13 * 100.0, rel=1e-13)
    np.testing.assert_allclose(s / j2root(s), S_SHEAR / j2root(S_SHEAR), rtol=1e-13)  # radial


def test_raised_surface_keeps_the_elastic_skeleton():
    """A state inside the static surface is untouched at any shear rate: mu(I) only raises the cap."""
    for rate in (0.0, 1.0, 1e3):
        p, s = fast_map(1000.0, S_SHEAR, DP, 30.0, 0.0, rate=rate)
        assert p == 1000.0 and np.array_equal(s, S_SHEAR)


def test_raised_drucker_prager_lands_on_the_raised_surface():
    """With dilatancy the return raises p; the multiplier keeps mu_r at its trial value, so the state
    lands on sqrt(J2) = k_c + (3 alpha_phi + mu_r) p_new exactly."""
    p0, rate = 200.0, 30.0
    mu_r = rate_friction(p0, rate, D_MU, I0, INERTIA)
    p, s = fast_map(p0, S_SHEAR * 10, DP, 30.0, 50.0, psi=10.0, rate=rate)
    _, _, _, _, aphi, kc, _ = params(30.0, 50.0, 10.0)
    assert p > p0 and j2root(s) == pytest.approx(kc + (3 * aphi + mu_r) * p, rel=1e-12)


def test_raised_return_matches_twin(rng):
    for _ in range(300):
        p = rng.uniform(-500, 3000)
        s6 = rng.normal(0, 600, 6)
        s6[:3] -= s6[:3].mean()
        rate = 10 ** rng.uniform(-2, 3)
        for model, name in ((DP, "drucker_prager"), (MC, "mohr_coulomb")):
            phi, c, psi = rng.uniform(10, 40), rng.uniform(0, 100), rng.uniform(0, 10) * (model == DP)
            pf, sf = fast_map(p, s6, model, phi, c, psi, rate)
            cut = max(p, -c / np.tan(np.radians(phi)))  # the tension cut-off comes first
            mu_r = nv.rate_friction(cut, rate, D_MU, I0, D50, RHO_GRAIN)
            pn, sn = nv.return_map(p, s6, name, K, G, phi, c, psi, mu_r)
            assert pf == pytest.approx(pn, rel=1e-12, abs=1e-9)
            np.testing.assert_allclose(sf, sn, rtol=1e-10, atol=1e-8)


# ---- the shear rate of the soil pass -----------------------------------------------------------------


def _lists(x, h):
    radius = 2 * h
    cl = CellList(CellGrid.covering(x.min(axis=0) - h, x.max(axis=0) + h, radius, pad=radius))
    cl.bin(x, len(x))
    return cl.neighbour_list(x, np.arange(len(x), dtype=np.int64), radius)


def run_rates(x, v, rho, p, s, mass, h, shear_rate, dim=2):
    n = len(x)
    pair = np.empty((n, PAIR_COLUMNS))
    soil_pair_terms(n, rho, p, s, mass, pair)
    nl = _lists(x, h)
    norm = cubic_spline_normalisation(dim, h)
    drho, acc, ds = np.zeros(n), np.zeros((n, dim)), np.zeros((n, 6))
    soil_rates(
        nl.targets, nl.start.view(np.uint64), nl.index.view(np.uint32), x, v, rho, s, pair,
        np.zeros(n, np.int32), np.array([20.0]), np.array([G]), h, norm, drho, acc, ds,
        np.array([1.0]), np.array([1.0]), True if dim == 3 else None, None, shear_rate,
    )  # fmt: skip
    return drho, acc, ds


@pytest.mark.parametrize("dim", [2, 3])
def test_shear_rate_matches_twin_and_leaves_the_rates_alone(rng, dim):
    """gamma_dot = sqrt(2 e':e') of the kernel's own velocity gradient, against the all-pairs twin on a
    disordered lattice; asking for it changes no other output (to round-off: a kernel compiled in this
    process and one loaded from Numba's disk cache were seen to differ by 1e-13 relative, with or without
    the shear rate)."""
    dx, h = 0.01, 0.013
    x = disordered_lattice(8 if dim == 2 else 5, dim, dx, rng)
    n = len(x)
    v = rng.normal(0, 0.3, (n, dim))
    rho = 2000 * (1 + rng.uniform(-0.01, 0.01, n))
    p, s, mass = rng.uniform(0, 3000, n), rng.normal(0, 500, (n, 6)), rho * dx**dim
    if dim == 2:
        s[:, 4:] = 0.0
    rate = np.full(n, np.nan)
    with_rate = run_rates(x, v, rho, p, s, mass, h, rate, dim)
    without = run_rates(x, v, rho, p, s, mass, h, None, dim)
    np.testing.assert_allclose(rate, nv.shear_rates(x, v, rho, mass, h), rtol=1e-9)
    for a, b in zip(with_rate, without):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12 * np.abs(b).max())


def test_shear_rate_of_a_simple_shear_is_du_dy():
    """v_x = 3 y on a lattice: |gamma_dot| = 3 1/s at an interior particle (SPH gradient of a linear
    field on a lattice: exact to the kernel's moment error, 2 % as in test_soil.py's plateau test)."""
    dx, h = 0.01, 0.013
    g = np.arange(-3, 4) * dx
    x = np.array([(a, b) for a in g for b in g])
    v = np.column_stack([3.0 * x[:, 1], np.zeros(len(x))])
    rho = np.full(len(x), 2650.0)
    rate = np.zeros(len(x))
    run_rates(x, v, rho, np.full(len(x), 1000.0), np.zeros((len(x), 6)), rho * dx * dx, h, rate)
    assert rate[np.argmin(np.linalg.norm(x, axis=1))] == pytest.approx(3.0, rel=0.02)


def test_soil_stress_state_with_mu_of_i_matches_twin(rng):
    """The per-row pass with the rate tuple: each row is the twin's raised return at its own shear rate;
    suspended rows keep p and lose s whatever their rate (no rheology for picked-up soil)."""
    n = 64
    rows = np.arange(n, dtype=np.int64)
    rho = 2000 * (1 + rng.uniform(-0.002, 0.004, n))
    s = rng.normal(0, 800, (n, 6))
    s[:, 4:] = 0
    s[:, :3] -= s[:, :3].mean(axis=1, keepdims=True)
    s0 = s.copy()
    rate = 10 ** rng.uniform(-1, 2.5, n)
    suspended = (rng.random(n) < 0.2).astype(np.uint8)
    mean = np.zeros(n)
    pr = params(25.0, 20.0)
    one = lambda q: np.array([q])  # noqa: E731
    soil_stress_state(
        rows, rho, s, np.zeros(n, np.int32), one(2000.0), *[one(q) for q in pr], np.array([DP], np.int32),
        mean, None, False, suspended, (one(D_MU), one(I0), one(INERTIA), rate),
    )  # fmt: skip
    for i in range(n):
        p_trial = K * (rho[i] / 2000 - 1)
        mu_r = 0.0 if suspended[i] else nv.rate_friction(p_trial, rate[i], D_MU, I0, D50, RHO_GRAIN)
        pn, sn = nv.return_map(p_trial, s0[i], "drucker_prager", K, G, 25.0, 20.0, 0.0, mu_r)
        assert mean[i] == pytest.approx(pn, rel=1e-12, abs=1e-9)
        np.testing.assert_allclose(s[i], 0.0 if suspended[i] else sn, rtol=1e-10, atol=1e-8)


@pytest.mark.parametrize("model", [MC, DP])
def test_shear_rate_sweep_plateaus_on_mu_of_i(model):
    """The single-particle check of the rheology: simple shear at constant p, the stress integrated with
    the kernel's own Hooke-Jaumann rate and shear rate (soil_rates on a lattice, centre particle) and the
    raised return mapping after each step, as in the solver. At each shear rate the plateau is
    sqrt(J2) = (mu_s + mu(I) - mu_s) p, mu_s = tan(phi) (Mohr-Coulomb) or 3 alpha_phi (Drucker-Prager),
    I from the prescribed rate: the kernel's strain rate carries the lattice gradient's moment error
    (< 2 %, test_shear_rate_of_a_simple_shear_is_du_dy), which moves mu(I) - mu_s by at most 2 % of
    itself (d mu / d ln gamma_dot <= mu(I) - mu_s): the tolerance is 2 % of the increment."""
    dx, h = 0.01, 0.013
    g = np.arange(-3, 4) * dx
    x = np.array([(a, b) for a in g for b in g])
    centre = int(np.argmin(np.linalg.norm(x, axis=1)))
    n, p, phi = len(x), 1000.0, 19.8
    pr = params(phi, 0.0)
    mu_s = pr[2] if model == MC else 3 * pr[4]
    rho = np.full(n, RHO_GRAIN)
    for inertial in (1e-3, 0.03, 0.279, 3.0):  # I from quasi-static to beyond I_0
        gamma_dot = inertial * np.sqrt(p / RHO_GRAIN) / D50
        v = np.column_stack([gamma_dot * x[:, 1], np.zeros(n)])
        s = np.zeros(6)
        rate = np.zeros(n)
        dt = 0.2 * mu_s * p / (G * gamma_dot) / 50  # the elastic branch in about 250 steps
        for _ in range(600):
            _, _, ds = run_rates(x, v, rho, np.full(n, p), np.tile(s, (n, 1)), rho * dx * dx, h, rate)
            s = s + dt * ds[centre]
            s = np.array(return_map(p, *s, model, *pr, D_MU, I0, INERTIA, rate[centre])[1:7])
        expected = (mu_s + nv.mu_of_i(inertial, 0.0, D_MU, I0)) * p
        increment = nv.mu_of_i(inertial, 0.0, D_MU, I0) * p
        assert j2root(s) == pytest.approx(expected, abs=0.02 * increment + 1e-9 * expected)


# ---- the plan and the scene ------------------------------------------------------------------------


def collapse(dx=0.01, **over):
    from verification.column_collapse import scene_at

    bars = {"rheology": "mu_I", "grain_size": 1.0e-3}
    bars.update(over.pop("bars", {}))
    return scene_at(dx, 0.05, {"materials": {"bars": bars}, **over})


def test_shear_rate_only_for_mu_of_i_and_not_in_the_seed_scheme():
    from solver.plan import build_plan, explain

    flowing = collapse(numerics={"scheme": "default"})
    plan = build_plan(flowing)
    assert "shear_rate" in plan.fields
    text = explain(plan, flowing)
    assert (
        "mu(I) bars: mu_2 - mu_s = 0.26, I_0 = 0.279" in text and "Jop, Forterre & Pouliquen (2006)" in text
    )
    for scene in (
        collapse(bars={"rheology": "perfectly_plastic"}),  # the material's choice
        collapse(numerics={"scheme": "seed"}),  # the seed's scheme, whatever the material says
        collapse(numerics={"scheme": "default", "rheology": "perfectly_plastic"}),
    ):
        assert "shear_rate" not in build_plan(scene).fields
        assert not build_plan(scene).materials.soil.rate_dependent


@pytest.mark.parametrize(
    "bars,key,reason",
    [
        ({"grain_size": None}, "materials.bars.grain_size", "required by rheology = 'mu_I'"),
        ({"yield_model": "elastic"}, "materials.bars.rheology", "has none"),
        ({"rheology": "bingham"}, "materials.bars.rheology", "'perfectly_plastic' or 'mu_I'"),
        ({"friction_increment": -0.1}, "materials.bars.friction_increment", "greater than or equal to 0"),
        ({"inertial_number_i0": 0.0}, "materials.bars.inertial_number_i0", "greater than 0"),
    ],
)
def test_scene_refusals(bars, key, reason):
    from verification.column_collapse import SCENE, scene_at

    over = {"rheology": "mu_I", "grain_size": 1.0e-3, **bars}
    if over["grain_size"] is None:
        del over["grain_size"]
    with pytest.raises(SceneError) as err:
        scene_at(0.01, 0.05, {"materials": {"bars": over}})
    assert err.value.key == key and reason in str(err.value) and str(SCENE) in str(err.value)


def test_seed_scheme_is_the_perfectly_plastic_collapse_bit_for_bit():
    """numerics.scheme = "seed" with a mu(I) material runs the seed's perfectly plastic model exactly:
    the same positions and stresses as the scene without mu(I) after 0.05 s at 1 cm (same process, so
    the same compiled kernels)."""
    from solver.simulation import Simulation

    finals = []
    for scene in (collapse(numerics={"scheme": "seed"}), collapse(bars={"rheology": "perfectly_plastic"})):
        sim = Simulation(scene)
        sim.advance_to(scene.scene.end_time)
        sim.current_state()
        ps = sim.particles
        order = np.argsort(ps["id"][: ps.n_owned])
        finals.append((ps["x"][order].copy(), ps["stress_dev"][order].copy()))
    np.testing.assert_array_equal(finals[0][0], finals[1][0])
    np.testing.assert_array_equal(finals[0][1], finals[1][1])


@pytest.fixture
def one_thread():
    """One Numba thread, as the restart's subprocess-free run (tests/test_restart.py's fixture)."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(before)


# ---- the Bagnold profile of an inclined layer (verification/granular_incline.py) -------------------------


def test_bagnold_reference_is_mu_of_i_everywhere():
    """The reference itself: I_zeta by hand (25 deg, Jop et al.'s beads: 0.279 x 0.0844 / 0.1756 = 0.134),
    the surface speed by hand (2/3 x 0.1342 x sqrt(0.6 x 9.81 x cos 25) x 0.04^1.5 / 0.004 = 0.413 m/s), and
    the profile's shear rate giving mu(I) = tan(zeta) at every depth (GDR MiDi 2004)."""
    from verification import granular_incline as gi

    assert gi.inertial_number_at_slope() == pytest.approx(0.1342, abs=1e-4)
    assert gi.bagnold(gi.H) == pytest.approx(0.4133, abs=1e-4)
    z, eps = np.linspace(0.001, 0.039, 50), 1e-7
    rate = (gi.bagnold(z + eps) - gi.bagnold(z - eps)) / (2 * eps)  # central difference: error ~ eps^2
    p = gi.SOLID_FRACTION * gi.RHO_GRAIN * gi.G * np.cos(np.radians(gi.ZETA)) * (gi.H - z)
    inertial = rate * gi.D / np.sqrt(p / gi.RHO_GRAIN)
    mu = nv.mu_of_i(inertial, gi.mu_s(), gi.mu_s() + gi.FRICTION_INCREMENT, gi.I0)
    np.testing.assert_allclose(mu, np.tan(np.radians(gi.ZETA)), rtol=1e-7)


def test_granular_incline_holds_the_bagnold_layer_at_4mm(tmp_path):
    """The verification case in CI size (dx = 4 mm, 0.2 s): the mu(I) layer holds its Bagnold state
    (effective friction, profile); the perfectly plastic ablation fails both checks by 10x and more."""
    from verification import granular_incline as gi

    res = gi.run(gi.DEFAULT_RESOLUTION, out_dir=tmp_path)
    assert res.passed, "\n".join(c.line() for c in res.checks)
    assert res.figure.exists()
    plastic = res.series["perfectly_plastic"]
    assert abs(plastic["friction_error"]) > 5 * gi.FRICTION_TOLERANCE
    assert plastic["profile_rms"] > 5 * gi.PROFILE_TOLERANCE


@pytest.mark.nightly
def test_granular_incline_resolution_study(tmp_path):
    from verification import granular_incline as gi
    from verification.common import study_failures

    rows = gi.study(out_dir=tmp_path)
    assert not study_failures(rows)


@pytest.mark.usefixtures("one_thread")
def test_mu_of_i_restart_is_bit_for_bit(tmp_path):
    """The shear rate is a particle field, so a checkpoint carries it: a μ(I) column continued from a
    mid-run checkpoint gives the uninterrupted run's snapshots and last checkpoint bit for bit."""
    import shutil

    import h5py
    from test_restart import (
        COLUMN,
        COLUMN_SET,
        _names,
        _scene_file,
        assert_same_checkpoint,
        assert_same_series,
    )

    from scoursph.cli import main
    from solver.run import run_scene
    from solver.scene import load_scene

    sets = [*COLUMN_SET, 'materials.bars.rheology="mu_I"', "materials.bars.grain_size=0.001"]
    scene_path = _scene_file(tmp_path, COLUMN, sets)
    ref = tmp_path / "ref"
    run_scene(load_scene(scene_path), ref, quiet=True)
    names = _names(ref)
    with h5py.File(ref / "checkpoints" / names[0], "r") as f:
        assert "shear_rate" in f["particles"] and np.any(f["particles"]["shear_rate"][:] > 0)
    copy = tmp_path / "copy"
    shutil.copytree(ref, copy)
    assert main(["run", str(scene_path), "--restart", str(copy), "--checkpoint", names[0], "--quiet"]) == 0
    assert_same_series(ref, copy)
    assert_same_checkpoint(ref / "checkpoints" / names[-1], copy / "checkpoints" / names[-1])
