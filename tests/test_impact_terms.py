"""Issue 15 terms: the midpoint continuity (fused with the density diffusion), the density
diffusion of pore water, the wall repulsion and the hydrostatic image increment of pore water,
each against a slow NumPy twin; the numerics.scheme preset and the scene-dependent leap-frog."""

import naive_density_diffusion as naive
import numpy as np
import pytest
from conftest import disordered_lattice
from test_density_diffusion import C0, DELTA, RHO0, disordered, neighbours

from solver.errors import SceneError
from solver.kernels import cubic_spline_normalisation
from solver.physics import density_diffusion as dd
from solver.physics.hydrostatic_image_pressure import add_hydrostatic_image_pressure
from solver.physics.midpoint_continuity import midpoint_continuity
from solver.physics.wall_repulsion import wall_repulsion
from solver.plan import build_plan
from solver.scene import Leapfrog
from verification.common import scene_from_file


def fused(x, x_old, v, rho, mass, h, dim, nl, targets, rho_ref=None, diffuse=False):
    out = np.zeros(len(x))
    midpoint_continuity(
        targets, *nl.unsigned(), x, x_old, v, rho, mass, np.zeros(len(x), np.int32), np.array([C0]), h,
        cubic_spline_normalisation(dim, h), out, DELTA, True if diffuse else None, rho_ref,
        True if dim == 3 else None,
    )  # fmt: skip
    return out


@pytest.mark.parametrize("dim,variant", [(2, "plain"), (2, "molteni"), (2, "fourtakas"), (3, "fourtakas")])
def test_midpoint_continuity_matches_twin(rng, dim, variant):
    """drho = continuity with grad W at the midpoints (x + x_old)/2, plus the diffusion there."""
    x, rho, mass, h = disordered(rng, dim)
    x_old = x + rng.uniform(-0.05, 0.05, x.shape) * 0.01  # a drift of up to 5 % of dx
    v = rng.normal(0, 0.3, x.shape)
    mid = 0.5 * (x + x_old)
    targets, nl, lists = neighbours(mid, dim, h)
    rho_ref = RHO0 + rng.normal(0, 3, len(x)) if variant == "fourtakas" else None
    got = fused(x, x_old, v, rho, mass, h, dim, nl, targets, rho_ref, diffuse=variant != "plain")
    want = naive.midpoint_continuity(targets, x, x_old, v, rho, mass, h, dim, lists)
    if variant != "plain":
        want += naive.density_diffusion(targets, mid, rho, mass, C0, DELTA, h, dim, lists, rho_ref)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_midpoint_quadrature_has_no_secular_drift_for_an_oscillating_pair():
    """Two particles oscillating along their axis: the continuity at the midpoint integrates the
    change of the pair's kernel to second order, so after whole periods the density returns (the
    end-point quadrature of the former symplectic_density drifts by a first-order amount: the
    bounce model of the impact design note (not in the repository), sec. 1)."""
    dx, h, dim = 0.01, 0.013, 2
    m = np.array([0.1, 0.1])
    norm = cubic_spline_normalisation(dim, h)
    amplitude, omega, steps = 0.3 * dx, 2 * np.pi, 400
    dt = 1.0 / steps  # one period
    targets = np.array([0], np.int64)
    start, index = np.array([0, 1], np.int64), np.array([1], np.int64)

    def position(t):
        return np.array([[0.0, 0.0], [dx + amplitude * np.sin(omega * t), 0.0]])

    rho = np.array([RHO0, RHO0])
    for k in range(steps):
        x_old, x = position(k * dt), position((k + 1) * dt)
        v = (x - x_old) / dt
        out = np.zeros(2)
        midpoint_continuity(
            targets, start, index, x, x_old, v, rho, m, np.zeros(2, np.int32), np.array([C0]), h, norm, out
        )
        rho = rho + dt * out
    # exact: rho_0 changes by m [W(r_end) - W(r_start)] = 0 after a whole period; midpoint error O(dt^2)
    from solver.kernels import cubic_spline_w

    swing = m[1] * abs(cubic_spline_w(dx + amplitude, h, norm) - cubic_spline_w(dx, h, norm))
    assert abs(rho[0] - RHO0) < 1e-3 * swing


def test_density_diffusion_leaves_pore_water_out(rng):
    """Pore water (fraction < 1) neither gets nor gives density diffusion (docs/seepage.md, "Density
    diffusion and pore water"); free water among free water diffuses as before."""
    x, rho, mass, h = disordered(rng, 2)
    targets, nl, lists = neighbours(x, 2, h)
    fraction = np.where(x[:, 1] < x[:, 1].mean(), 0.4, 1.0)
    rho_app = rho * fraction

    def kernel(r, frac):
        out = np.zeros(len(x))
        dd.density_diffusion(
            targets, nl.start, nl.index, x, r, mass * fraction, np.zeros(len(x), np.int32), np.array([C0]),
            DELTA, h, cubic_spline_normalisation(2, h), out, None, None, None, frac,
        )  # fmt: skip
        return out

    got = kernel(rho_app, fraction)
    want = naive.density_diffusion(
        targets, x, rho_app, mass * fraction, C0, DELTA, h, 2, lists, fraction=fraction
    )
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    assert not got[fraction < 1.0].any()
    # free water: as without fractions, minus the pairs with pore water
    assert np.abs(got[fraction == 1.0]).max() > 0.0
    # no mass created: sum_i V_i D_i = 0 over the free water (antisymmetric pairs)
    vol = mass * fraction / rho_app
    assert abs((vol * got).sum()) < 1e-9 * (vol * np.abs(got)).sum()


def test_hydrostatic_image_increment_of_pore_water_uses_the_intrinsic_density():
    x = np.array([[0.1, 0.02], [0.1, -0.02]])  # source above the floor, its image below
    rho = np.array([400.0, 0.0])  # apparent density n rho_w with n = 0.4
    g = np.array([0.0, -9.81])
    p = np.zeros(2)
    add_hydrostatic_image_pressure(1, np.array([0]), x, rho, g, p, np.array([0.4, 0.4]))
    assert p[1] == pytest.approx(1000.0 * 9.81 * 0.04)


def test_wall_repulsion_matches_formula_and_is_zero_beyond_half_a_spacing(rng):
    dx = 0.01
    r0, d_coef = 0.5 * dx, 14.7
    x = disordered_lattice(12, 2, dx, rng, jitter=0.45)
    lo, hi = np.zeros(2), np.full(2, 12 * dx)
    acc = np.zeros_like(x)
    wall_repulsion(len(x), x, r0, d_coef, np.array([True, True]), lo, np.array([True, False]), hi, acc)
    want = np.zeros_like(x)
    for a, has_hi in ((0, True), (1, False)):
        d = x[:, a] - lo[a]
        near = d < r0
        want[near, a] += d_coef * ((r0 / d[near]) ** 12 - (r0 / d[near]) ** 4) / d[near]
        if has_hi:
            d = hi[a] - x[:, a]
            near = d < r0
            want[near, a] -= d_coef * ((r0 / d[near]) ** 12 - (r0 / d[near]) ** 4) / d[near]
    np.testing.assert_allclose(acc, want, rtol=1e-12)
    assert np.any(acc != 0.0)  # the jitter put some particles within dx/2 of a wall
    far = np.all((x - lo > r0) & (hi - x > r0), axis=1)
    assert np.all(acc[far] == 0.0)


def small_dam_break(**overrides):
    return scene_from_file("dam_break_2d.toml", **{"scene.spacing": 0.05715 / 10, **overrides})


SEED_TERMS = ["wall images", "Tait equation of state", "viscous stress", "gravity", "fluid rates"]


def test_seed_preset_plans_exactly_the_seed_scheme():
    plan = build_plan(small_dam_break(**{"numerics.scheme": "seed"}))
    assert [t.name for t in plan.terms] == SEED_TERMS
    assert ("rho", "rho_half", "drho") in [(i.value, i.half, i.rate) for i in plan.integrated]


def test_default_plan_has_the_issue_15_terms():
    names = [t.name for t in build_plan(small_dam_break()).terms]
    for term in (
        "hydrostatic image pressure",
        "hydrostatic reference density",
        "wall repulsion",
        "midpoint leap-frog: keep x_n",
        "midpoint continuity",
    ):
        assert term in names
    assert "density diffusion" not in names  # fused into the midpoint continuity


def test_explicit_keys_override_the_preset():
    scene = small_dam_break(**{"numerics.scheme": "seed", "numerics.density_diffusion": "fourtakas"})
    names = [t.name for t in build_plan(scene).terms]
    assert scene.numerics.leapfrog == Leapfrog.SEED and "density diffusion" in names
    assert "wall repulsion" not in names and "hydrostatic image pressure" not in names


def test_soil_scenes_default_to_the_seed_leapfrog_and_refuse_the_midpoint_one():
    assert scene_from_file("column_collapse_2d.toml").numerics.leapfrog == Leapfrog.SEED
    with pytest.raises(SceneError) as err:
        scene_from_file("column_collapse_2d.toml", **{"numerics.leapfrog": "midpoint_density"})
    assert err.value.key == "numerics.leapfrog"


def test_unknown_scheme_names_the_key():
    with pytest.raises(SceneError) as err:
        small_dam_break(**{"numerics.scheme": "dualsphysics"})
    assert err.value.key == "numerics.scheme"


def test_reflection_warning_names_the_count():
    from solver.run import reflection_warning

    assert "12 specular wall reflection" in reflection_warning(12)
