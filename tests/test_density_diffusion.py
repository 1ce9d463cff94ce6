"""Density diffusion (solver/physics/density_diffusion.py) against its NumPy twin
(tests/naive_density_diffusion.py), and the properties each variant is chosen for."""

import naive_density_diffusion as naive
import numpy as np
import pytest
from conftest import disordered_lattice

from solver.kernels import cubic_spline_normalisation
from solver.neighbors import CellGrid, CellList
from solver.physics import density_diffusion as dd

C0 = 15.0
DELTA = 0.1
RHO0 = 1000.0
GAMMA = 7.0
B = RHO0 * C0**2 / GAMMA  # seed eq. (9)
G = 9.81


def neighbours(x, dim, h):
    n = len(x)
    radius = 2 * h * 1.1
    lo, hi = x.min(axis=0) - radius, x.max(axis=0) + radius
    cells = CellList(CellGrid.covering(lo, hi, radius, pad=radius))
    cells.bin(x, n)
    targets = np.arange(n, dtype=np.int64)
    nl = cells.neighbour_list(x, targets, radius)
    lists = [nl.index[nl.start[t] : nl.start[t + 1]].tolist() for t in range(n)]
    return targets, nl, lists


def disordered(rng, dim):
    dx = 0.01
    h = 1.3 * dx
    x = disordered_lattice(14 if dim == 2 else 6, dim, dx, rng)
    rho = RHO0 + rng.normal(0, 5, len(x))
    mass = np.full(len(x), RHO0 * dx**dim)
    return x, rho, mass, h


def run_kernel(x, rho, mass, h, dim, nl, targets, rho_ref=None, grad_rho=None):
    out = np.zeros(len(x))
    dd.density_diffusion(
        targets,
        nl.start,
        nl.index,
        x,
        rho,
        mass,
        np.zeros(len(x), np.int32),
        np.array([C0]),
        DELTA,
        h,
        cubic_spline_normalisation(dim, h),
        out,
        rho_ref,
        grad_rho,
        True if dim == 3 else None,
    )
    return out


def kernel_gradient(x, rho, mass, h, dim, nl, targets):
    g = np.zeros((len(x), dim))
    dd.renormalised_density_gradient(
        targets,
        nl.start,
        nl.index,
        x,
        rho,
        mass,
        h,
        cubic_spline_normalisation(dim, h),
        g,
        True if dim == 3 else None,
    )
    return g


@pytest.mark.parametrize("dim", [2, 3])
def test_renormalised_gradient_matches_twin_and_is_exact_for_linear_rho(rng, dim):
    x, rho, mass, h = disordered(rng, dim)
    targets, nl, lists = neighbours(x, dim, h)
    g = kernel_gradient(x, rho, mass, h, dim, nl, targets)
    np.testing.assert_allclose(
        g, naive.renormalised_gradient(targets, x, rho, mass, h, dim, lists), rtol=1e-9, atol=1e-6
    )
    slope = (
        np.arange(1, dim + 1) * 100.0
    )  # kg/m^4: a linear field, reproduced exactly (eq. 8), edges included
    g_lin = kernel_gradient(x, RHO0 + x @ slope, mass, h, dim, nl, targets)
    np.testing.assert_allclose(g_lin, np.broadcast_to(slope, g_lin.shape), rtol=1e-9)


@pytest.mark.parametrize(
    "dim,variant", [(2, "molteni"), (2, "fourtakas"), (2, "antuono"), (2, "both"), (3, "both")]
)
def test_density_diffusion_matches_twin(rng, dim, variant):
    """Each optional part alone and together: each is its own compiled specialisation."""
    x, rho, mass, h = disordered(rng, dim)
    targets, nl, lists = neighbours(x, dim, h)
    rho_ref = RHO0 + rng.normal(0, 3, len(x)) if variant in ("fourtakas", "both") else None
    grad = kernel_gradient(x, rho, mass, h, dim, nl, targets) if variant in ("antuono", "both") else None
    got = run_kernel(x, rho, mass, h, dim, nl, targets, rho_ref, grad)
    want = naive.density_diffusion(targets, x, rho, mass, C0, DELTA, h, dim, lists, rho_ref, grad)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


@pytest.mark.parametrize("with_ref", [False, True])
def test_pair_terms_create_no_mass(rng, with_ref):
    """psi_ij is antisymmetric and the weights V_i V_j grad W symmetric: sum_i V_i D_i = 0 (round-off)."""
    x, rho, mass, h = disordered(rng, 2)
    targets, nl, _ = neighbours(x, 2, h)
    rho_ref = RHO0 + rng.normal(0, 3, len(x)) if with_ref else None
    d = run_kernel(x, rho, mass, h, 2, nl, targets, rho_ref)
    vol = mass / rho
    assert abs(np.sum(vol * d)) < 1e-12 * np.sum(np.abs(vol * d))


def hydrostatic_column(dim):
    """A still column 30 dx deep on a lattice, with mirror images below the floor (as the solver's
    image walls make them: x' = mirrored, rho' = rho of the source), densities from the hydrostatic
    start (inverse Tait law of rho0 g (H - z), solver/initial_state.py)."""
    dx = 0.01
    h = 1.3 * dx
    nx, nz = (12, 30) if dim == 2 else (6, 30)
    axes = [(np.arange(nx) + 0.5) * dx] * (dim - 1) + [(np.arange(nz) + 0.5) * dx]
    fluid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    depth = nz * dx
    near = fluid[:, -1] < 2.2 * h
    image = fluid[near].copy()
    image[:, -1] *= -1.0
    x = np.vstack([fluid, image])
    src = np.concatenate([np.arange(len(fluid)), np.flatnonzero(near)])  # image -> its source
    gravity = np.zeros(dim)
    gravity[-1] = -G
    ref = np.zeros(len(x))
    dd.hydrostatic_reference_density(
        len(fluid),
        fluid,
        np.zeros(len(fluid), np.int32),
        gravity,
        depth,
        np.array([RHO0]),
        np.array([B]),
        np.array([GAMMA]),
        ref,
    )
    ref = ref[src]  # images copy rho_ref from their sources, like rho
    rho = ref.copy()  # at rest: rho = rho^H
    mass = np.full(len(x), RHO0 * dx**dim)
    targets, nl, lists = neighbours(x, dim, h)
    fluid_rows = np.arange(len(fluid), dtype=np.int64)
    return x, rho, ref, mass, h, nl, targets, fluid_rows, lists, depth


@pytest.mark.parametrize("dim", [2, 3])
def test_hydrostatic_variant_is_exactly_zero_in_a_still_column_and_molteni_is_not(dim):
    """Fourtakas et al. (2019): in hydrostatic equilibrium the dynamic density is zero, so the flux is
    zero, floor images included: every pair term is exactly 0 - 0; the sum over a row is zero up to the
    reassociation that fastmath allows (the compiler may split the pair sum into partial sums of
    rho and rho^H, ~1e-13 of the plain term here), so the bound is 1e-10 of the plain term's size.
    The plain Molteni & Colagrossi term diffuses the stratified density: at the free surface
    (truncated support) the top row gains density from the denser water below."""
    x, rho, ref, mass, h, nl, targets, rows, _, depth = hydrostatic_column(dim)
    np.testing.assert_allclose(  # the reference is the hydrostatic start of solver/initial_state.py
        ref[rows], naive.hydrostatic_density(x[rows, -1], depth, RHO0, B, GAMMA, G), rtol=1e-13
    )
    out = np.zeros(len(x))
    dd.density_diffusion(
        rows,
        nl.start,
        nl.index,
        x,
        rho,
        mass,
        np.zeros(len(x), np.int32),
        np.array([C0]),
        DELTA,
        h,
        cubic_spline_normalisation(dim, h),
        out,
        ref,
        None,
        True if dim == 3 else None,
    )
    molteni = run_kernel(x, rho, mass, h, dim, nl, targets)[rows]
    # the surface rows change density at a rate of order delta h c0 rho0 g / c0^2 / dx (first-order in the
    # density step across a truncated support): far from round-off
    scale = DELTA * h * C0 * RHO0 * G / C0**2 / 0.01
    assert np.max(np.abs(out[rows])) < 1e-10 * scale
    surface = x[rows, -1] > depth - 2 * h
    assert np.max(np.abs(molteni[surface])) > 0.1 * scale
    top = x[rows, -1] > depth - 0.01
    assert np.all(molteni[top] > 0.1 * scale)  # the top row gains density from the denser water below


def test_antuono_correction_cancels_the_interior_of_a_linear_column():
    """Antuono et al. (2010): the renormalised-gradient correction makes psi vanish for a linear field:
    away from the surface and the floor, the still column (nearly linear rho) sees ~no diffusion;
    the plain term does not vanish where the support is truncated."""
    x, rho, ref, mass, h, nl, targets, rows, _, depth = hydrostatic_column(2)
    grad = kernel_gradient(x, rho, mass, h, 2, nl, targets)
    corrected = run_kernel(x, rho, mass, h, 2, nl, targets, None, grad)[rows]
    plain = run_kernel(x, rho, mass, h, 2, nl, targets)[rows]
    interior = (x[rows, -1] > 3 * h) & (x[rows, -1] < depth - 3 * h)
    # the Tait profile is not exactly linear: curvature d2rho/dz2 ~ rho0 (g/c0^2)^2 (1/gamma - 1)
    curv = RHO0 * (G / C0**2) ** 2
    assert np.max(np.abs(corrected[interior])) < 10 * DELTA * h * C0 * curv
    assert np.max(np.abs(plain[~interior])) > 1e3 * np.max(np.abs(corrected[interior]))
