"""The pore water's density diffusion (solver/physics/seepage_pore_diffusion.py, numerics.pore_density_
diffusion = "antuono") against its NumPy twin (tests/naive_density_diffusion.py), and the properties it
is chosen for: blind to quadratic fields (no spurious permeability), full strength on the odd-even mode
that the SPH gradient does not see, no mass created, free water and walls untouched."""

import naive_density_diffusion as naive
import numpy as np
import pytest
from conftest import disordered_lattice
from test_density_diffusion import C0, DELTA, RHO0, neighbours

from solver.kernels import cubic_spline_normalisation
from solver.physics import seepage_pore_diffusion as pd

N = 0.4


def run(x, rho, mass, fraction, h, dim, nl, targets, rho_ref=None, fixed=None, scaled=True):
    norm = cubic_spline_normalisation(dim, h)
    is3d = True if dim == 3 else None
    grad = np.zeros((len(x), dim))
    scaled = True if scaled else None
    pd.pore_density_gradient(
        targets, nl.start, nl.index, x, rho, mass, fraction, h, norm, grad, rho_ref, fixed, is3d, scaled
    )  # fmt: skip
    out = np.zeros(len(x))
    pd.pore_density_diffusion(
        targets, nl.start, nl.index, x, rho, mass, np.zeros(len(x), np.int32), fraction, grad, np.array([C0]),
        DELTA, h, norm, out, rho_ref, fixed, is3d, scaled,
    )  # fmt: skip
    return out, grad


def bed(rng, dim, jitter=0.15):
    """Pore water (mixture: apparent density n rho) under free water, the upper third free."""
    dx = 0.01
    h = 1.3 * dx
    x = disordered_lattice(12 if dim == 2 else 6, dim, dx, rng, jitter)
    fraction = np.where(x[:, -1] < x[:, -1].max() * 0.66, N, 1.0)
    rho = fraction * (RHO0 + rng.normal(0, 5, len(x)))
    mass = fraction * RHO0 * dx**dim
    return x, rho, mass, fraction, h


@pytest.mark.parametrize(
    "dim,ref,walls,scaled", [(2, False, False, True), (2, True, True, False), (3, True, False, True)]
)
def test_matches_twin(rng, dim, ref, walls, scaled):
    """scaled: the mixture's water_fraction (apparent density); else the seed's pore_label (a mark only)."""
    x, rho, mass, fraction, h = bed(rng, dim)
    if not scaled:  # the seed's pore water is at its true density
        rho, mass = rho / fraction, mass / fraction
    targets, nl, lists = neighbours(x, dim, h)
    rho_ref = RHO0 + rng.normal(0, 3, len(x)) if ref else None
    fixed = rng.random(len(x)) < 0.1 if walls else None
    got, grad = run(x, rho, mass, fraction, h, dim, nl, targets, rho_ref, fixed, scaled)
    want, want_grad = naive.pore_density_diffusion(targets, x, rho, mass, fraction, C0, DELTA, h, dim, lists,
                                                   rho_ref, fixed, scaled)  # fmt: skip
    np.testing.assert_allclose(grad, want_grad, rtol=1e-9, atol=1e-9 * np.abs(want_grad).max())
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    free = (fraction >= 1.0) | (fixed if fixed is not None else False)
    assert np.all(got[free] == 0.0) and np.any(got[~free] != 0.0)


def test_blind_to_a_quadratic_pore_pressure_and_damps_the_odd_even_mode():
    """On a lattice (interior rows whose neighbours have full supports too) a quadratic dynamic density,
    a consolidation or seepage profile, gets no diffusion (Antuono's psi cancels pair by pair: what is
    left is round-off), where the plain delta-SPH Laplacian gives it delta h c0 lap q; the checkerboard
    (-1)^(i+j) eps, whose renormalised gradient is zero, gets the full plain Laplacian: it decays (the
    rate opposes it everywhere)."""
    dx, dim = 0.01, 2
    h = 1.3 * dx
    axes = [(np.arange(20) + 0.5) * dx] * 2
    x = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 2)
    fraction = np.full(len(x), N)
    mass = N * RHO0 * dx**2
    targets, nl, _ = neighbours(x, dim, h)
    inner = np.all((x > 6 * dx) & (x < 14 * dx), axis=1)  # 2 h + 2 h = 5.2 dx from the edges
    curv = 300.0  # kg/m^5: q = c (x^2 + 2 y^2) / 2, lap q = 3 c (q varies by ~12 kg/m^3)
    q = RHO0 + 20.0 * x[:, 0] + 0.5 * curv * (x[:, 0] ** 2 + 2 * x[:, 1] ** 2)
    # masses from the start density (m = rho dx^2, as the solver's starts set them): V = dx^2 on the lattice
    out, _ = run(x, N * q, N * q * dx**2, fraction, h, dim, nl, targets)
    plain = DELTA * h * C0 * N * 3 * curv
    assert np.max(np.abs(out[inner])) < 1e-9 * plain
    # with one mass for all (V varies by the density's ~1 %) the cancellation is not exact: ~5e-5 of plain
    out, _ = run(x, N * q, np.full(len(x), mass), fraction, h, dim, nl, targets)
    assert np.max(np.abs(out[inner])) < 1e-3 * plain
    k = np.round(x / dx - 0.5).astype(int).sum(axis=1)
    eps = 0.5
    rho = N * (RHO0 + eps * (-1.0) ** k)
    out, grad = run(x, rho, np.full(len(x), mass), fraction, h, dim, nl, targets)
    assert np.max(np.abs(grad[inner])) < 1e-9 * eps / dx
    assert np.all(out[inner] * (-1.0) ** k[inner] < -0.5 * DELTA * h * C0 * N * eps / dx**2)


def test_pair_terms_create_no_mass_among_pore_water_of_one_fraction(rng):
    x, rho, mass, fraction, h = bed(rng, 2)
    targets, nl, _ = neighbours(x, 2, h)
    out, _ = run(x, rho, mass, fraction, h, 2, nl, targets)
    vol = mass / rho
    assert abs(np.sum(vol * out)) < 1e-12 * np.sum(np.abs(vol * out))


def test_option_builds_only_when_asked():
    """Off by default; on, both terms build for a saturated bed."""
    from solver.materials import build_material_table
    from solver.physics.seepage_pore_diffusion import PoreDensityDiffusion as Rate
    from solver.physics.seepage_pore_diffusion import PoreDensityGradient as Gradient
    from verification import seepage_bed_at_rest as case

    scene = case.scene(10, "mixture")
    mats = build_material_table(scene)
    assert Rate.build(scene, mats) is None and Gradient.build(scene, mats) is None
    from verification.common import scene_from_file

    tank = scene_from_file("hydrostatic_tank_2d.toml", **{"numerics.pore_density_diffusion": "antuono"})
    assert Rate.build(tank, build_material_table(tank)) is None  # no pore water: no term, asked or not
    assert Gradient.build(tank, build_material_table(tank)) is None
    on = case.scene(10, "mixture", pore_density_diffusion="antuono")
    assert Rate.build(on, mats) is not None and Gradient.build(on, mats) is not None
