"""Cubic spline (seed eq. 5 with the erratum): normalisation, compact support, gradient."""

import naive
import numpy as np
import pytest

from solver.kernels import cubic_spline_dwdr, cubic_spline_normalisation, cubic_spline_w, kernel_values


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_matches_the_printed_piecewise_form(dim):
    h = 0.37
    r = np.linspace(0, 2.5 * h, 101)
    norm = cubic_spline_normalisation(dim, h)
    np.testing.assert_allclose(
        [cubic_spline_w(x, h, norm) for x in r], naive.cubic_spline(r, h, dim), rtol=1e-13, atol=1e-13
    )
    np.testing.assert_allclose(
        [cubic_spline_dwdr(x, h, norm) for x in r], naive.cubic_spline_dwdr(r, h, dim), rtol=1e-12, atol=1e-10
    )


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_normalised_to_one(dim):
    """Eq. (2): the integral of W over its support is 1. Radial quadrature, exact to ~1e-10."""
    h = 0.5
    r = np.linspace(0, 2 * h, 200001)
    shell = {1: 2.0, 2: 2 * np.pi * r, 3: 4 * np.pi * r**2}[dim]
    assert np.trapezoid(kernel_values(r, h, dim) * shell, r) == pytest.approx(1.0, abs=1e-8)


def test_continuous_at_r_equals_h_and_compact():
    """The erratum matters: the printed 1.5 would jump at R = 1. Eq. (4): zero beyond 2h."""
    h = 1.0
    eps = 1e-9
    assert kernel_values(h - eps, h, 2) == pytest.approx(kernel_values(h + eps, h, 2), rel=1e-7)
    assert kernel_values(2 * h, h, 2) == 0.0
    assert kernel_values(5 * h, h, 2) == 0.0


def test_gradient_is_the_derivative():
    h = 0.8
    r = np.linspace(0.05, 1.95, 39) * h
    norm = cubic_spline_normalisation(2, h)
    step = 1e-6
    fd = (kernel_values(r + step, h, 2) - kernel_values(r - step, h, 2)) / (2 * step)
    np.testing.assert_allclose([cubic_spline_dwdr(x, h, norm) for x in r], fd, rtol=1e-6, atol=1e-8)


@pytest.mark.parametrize("dim", [1, 2])
def test_gradient_antisymmetry_on_the_default_lattice(dim):
    """sum_j V_j grad_i W_ij = 0 on a full lattice at h = 1.3 dx: exact by antisymmetry."""
    dx, h, n = 0.1, 0.13, 21
    axes = [np.arange(-(n // 2), n // 2 + 1) * dx] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    grads = np.array([naive.grad_w(np.zeros(dim), p, h, dim) for p in pts])
    np.testing.assert_allclose(dx**dim * grads.sum(axis=0), 0.0, atol=1e-12)


@pytest.mark.parametrize("dim", [1, 2])
@pytest.mark.parametrize("h_over_dx", [4, 8])
def test_first_order_consistency(dim, h_over_dx):
    """sum_j V_j (x_j - x_i) (x) grad_i W_ij -> I (the SPH gradient of f = x is exact in the
    continuum). On a lattice this is a trapezoidal quadrature of a C^2 kernel, whose error
    is O((dx/h)^3) (Euler-Maclaurin): that is the tolerance."""
    h = 1.0
    dx = h / h_over_dx
    n = int(4.4 * h_over_dx) | 1
    axes = [np.arange(-(n // 2), n // 2 + 1) * dx] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    grads = np.array([naive.grad_w(np.zeros(dim), p, h, dim) for p in pts])
    first = dx**dim * np.einsum("ja,jb->ab", pts, grads)
    np.testing.assert_allclose(first, np.eye(dim), atol=(dx / h) ** 3)
