"""The kernels that had no NumPy twin (issue 13): continuity alone, the mixed-material branch of
fluid_rates, frictional (Coulomb) images and the hydrostatic image pressure, each against a
twin written from the equations (tests/naive.py, tests/naive_soil.py)."""

import naive
import naive_soil
import numpy as np
import pytest
from test_fluid_kernels import setup

from solver.kernels import cubic_spline_normalisation

# The kernels under test, imported in this one place (each lives in its term's module).
from solver.physics.fluid_rates import fluid_rates
from solver.physics.frictional_walls import frictional_images
from solver.physics.gravity import add_gravity
from solver.physics.hydrostatic_image_pressure import add_hydrostatic_image_pressure
from solver.physics.midpoint_continuity import midpoint_continuity


@pytest.mark.parametrize("dim", [2, 3])
def test_continuity_matches_twin(rng, dim):
    """Continuity alone (seed eq. 6): the midpoint continuity kernel with x_old = x and no
    diffusion (the seed leap-frog's continuity is fused into fluid_rates, twinned elsewhere)."""
    s = setup(rng, dim=dim, n_side=14 if dim == 2 else 6)
    n = len(s["x"])
    drho = np.full(n, np.nan)  # written, not added: every target's entry must be set
    norm = cubic_spline_normalisation(dim, s["h"])
    rho = np.full(n, 1000.0)
    midpoint_continuity(
        s["targets"], *s["nl"].unsigned(), s["x"], s["x"], s["v"], rho, s["mass"],
        np.zeros(n, np.int32), np.array([20.0]), s["h"], norm, drho, 0.0, None, None,
        True if dim == 3 else None,
    )  # fmt: skip
    expected = naive.continuity(s["targets"], s["x"], s["v"], s["mass"], s["h"], dim, s["lists"])
    np.testing.assert_allclose(drho, expected, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("dim", [2, 3])
def test_fluid_rates_mixed_materials_match_twin(rng, dim):
    """Two materials with different c, alpha, beta in one phase (mixed=True): every pair's
    artificial viscosity uses the pair means; compared with the twin, and with the single-
    material branch when both materials are made equal."""
    s = setup(rng, dim=dim, n_side=14 if dim == 2 else 6)
    n = len(s["x"])
    material = rng.integers(0, 2, n).astype(np.int32)
    p = rng.normal(0, 200, n)
    c, alpha, beta = np.array([15.0, 40.0]), np.array([0.3, 1.0]), np.array([0.2, 1.0])
    norm = cubic_spline_normalisation(dim, s["h"])
    is3d = True if dim == 3 else None

    def kernel(material, c, alpha, beta, mixed):
        drho, acc = np.zeros(n), np.zeros((n, dim))
        fluid_rates(
            s["targets"], *s["nl"].unsigned(), s["x"], s["v"], s["rho"], p, s["mass"], material, c,
            s["h"], norm, drho, acc, None, alpha, beta, None, 0.0, is3d, mixed,
        )  # fmt: skip
        return drho, acc

    drho, acc = kernel(material, c, alpha, beta, True)
    e_drho, e_acc = naive.fluid_rates_mixed(
        s["targets"],
        s["x"],
        s["v"],
        s["rho"],
        p,
        s["mass"],
        material,
        c,
        alpha,
        beta,
        s["h"],
        dim,
        s["lists"],
    )
    np.testing.assert_allclose(drho, e_drho, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(acc, e_acc, rtol=1e-10, atol=1e-10)
    # the pair means matter: with material 1 alone the result differs
    assert not np.allclose(acc, kernel(np.ones(n, np.int32), c, alpha, beta, True)[1])
    # one material given as two equal ones: the mixed branch equals the single-material branch
    same = kernel(material, c[[0, 0]], alpha[[0, 0]], beta[[0, 0]], True)[1]
    np.testing.assert_allclose(same, kernel(np.zeros(n, np.int32), c, alpha, beta, None)[1], rtol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_hydrostatic_image_pressure_matches_twin(rng, dim):
    first, n_img = 30, 25
    x = rng.uniform(-0.2, 0.2, (first + n_img, dim))
    rho = rng.uniform(990, 1010, first + n_img)
    p = rng.normal(0, 500, first + n_img)
    src = rng.integers(0, first, n_img)
    gravity = np.array([0.5, -9.81, 0.3][:dim])
    got = p.copy()
    add_hydrostatic_image_pressure(first, src, x, rho, gravity, got)
    np.testing.assert_allclose(
        got, naive.hydrostatic_image_pressure(first, src, x, rho, gravity, p), rtol=1e-13
    )
    np.testing.assert_array_equal(got[:first], p[:first])


@pytest.mark.parametrize("dim", [2, 3])
def test_frictional_images_match_twin(rng, dim):
    """Random sources near random walls: sticking and slipping, from rest and sliding, lower and
    upper walls, images not across a frictional wall (-1) left alone."""
    n_src, n_img = 60, 80
    n = n_src + n_img
    x = rng.uniform(0.0, 0.05, (n, dim))
    v = rng.normal(0, 0.05, (n, dim))
    v[rng.random(n) < 0.4] = 0.0  # at rest: slip only if the shear exceeds mu sigma_n
    rho = rng.uniform(2000, 2700, n)
    p = rng.uniform(-50, 3000, n)
    s6 = rng.normal(0, 800, (n, 6))
    s6[:, :3] -= s6[:, :3].mean(axis=1, keepdims=True)
    if dim == 2:
        s6[:, 4:] = 0.0  # plane strain: no out-of-plane shear
    src = rng.integers(0, n_src, n_img)
    fric_axis = rng.integers(-1, dim, n_img)
    fric_side = rng.choice([1, -1], n_img)
    offset = np.zeros((n_img, dim))
    for k in range(n_img):
        if fric_axis[k] >= 0:  # the plane at 0 (lower wall) or 0.05 (upper wall)
            offset[k, fric_axis[k]] = 0.0 if fric_side[k] > 0 else 0.1
    vsign = rng.choice([1.0, -1.0], (n_img, dim))
    gravity = np.array([0.0, -9.81, 0.0][:dim]) if dim == 2 else np.array([0.3, -1.0, -9.7])
    mu, v_stick = np.tan(np.radians(20.0)), 0.01
    want_vsign, want_s6, want_slipping = naive_soil.frictional_images(
        n_src, src, offset, fric_axis, fric_side, mu, p, s6, vsign, x, v, rho, gravity, v_stick
    )
    got_vsign, got_s6 = vsign.copy(), s6.copy()
    slipping = frictional_images(
        n_src, src, offset, fric_axis, fric_side, mu, p, got_s6, got_vsign, x, v, rho, gravity, v_stick
    )
    assert 0 < want_slipping < np.sum(fric_axis >= 0)  # both regimes present
    assert slipping == want_slipping
    np.testing.assert_array_equal(got_vsign, want_vsign)
    np.testing.assert_allclose(got_s6, want_s6, rtol=1e-12, atol=1e-9)


def test_gravity_kernel_matches_numpy(rng):
    """add_gravity adds g to the first n rows only (the NumPy broadcast it replaced)."""
    acc = rng.normal(0, 1, (50, 2))
    g = np.array([0.5, -9.81])
    expected = acc.copy()
    expected[:40] += g
    add_gravity(40, g, acc)
    np.testing.assert_array_equal(acc, expected)
