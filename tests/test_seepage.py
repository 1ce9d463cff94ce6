"""The water-soil coupling (solver/physics/seepage.py): every kernel against its NumPy twin
(tests/naive_seepage.py), pair forces equal and opposite, the plan, scene refusals, --explain."""

import subprocess

import naive_seepage
import numpy as np
import pytest
from conftest import ENV, SCOURSPH, disordered_lattice, rectangle_block, water_and_sand_scene, write_scene

from solver.kernels import cubic_spline_normalisation
from solver.materials import Phase
from solver.neighbors import CellGrid, CellList
from solver.physics.seepage import (
    lattice_gradient_normalisation,
    pore_pressure_at_soil,
    row_chunks,
    seepage_on_soil,
    seepage_on_water,
)
from solver.plan import build_plan, explain
from solver.scene import parse_scene
from solver.simulation import Simulation

N_SOIL, N_POROSITY = 0.4, 0.4


# THREE_D: the 3D compilations of the optional variants (linear p^, the corrected pair, the one-soil
# switch) cost ~10 s each in a cold CI run; the kernels loop over the dimension, so make test holds
# them in 2D and holds the plain 3D coupling (forces, storage, p~, p^), and the nightly all of them.
VARIANT_DIMS = [(2, None), (2, 1), pytest.param(3, None, marks=pytest.mark.nightly)]


def two_phase(rng, dim=2, n_side=10, dx=0.01):
    """Soil (material 1, two soil materials: ids 1 and 2) and water (material 0) on two jittered
    lattices over the same square, random velocities, densities and pressures."""
    h = 1.3 * dx
    xs = disordered_lattice(n_side, dim, dx, rng)
    xw = disordered_lattice(n_side, dim, dx, rng)
    x = np.vstack([xw, xs])
    nw, ns = len(xw), len(xs)
    water, soil = np.arange(nw), np.arange(nw, nw + ns)
    material = np.zeros(nw + ns, dtype=np.int32)
    material[soil] = 1 + (rng.random(ns) < 0.3)  # two soil materials
    v = rng.normal(0, 0.2, (nw + ns, dim))
    rho = np.where(material == 0, 400.0, 1600.0) * (1 + rng.normal(0, 0.01, nw + ns))
    mass = np.where(material == 0, 400.0, 1600.0) * dx**dim
    p = rng.uniform(0.0, 2000.0, nw + ns)
    phase = np.where(material == 0, 0, 1).astype(np.int32)
    radius = 2 * h * 1.1
    cells = CellList(CellGrid.covering(np.zeros(dim), np.full(dim, n_side * dx), radius, pad=radius))
    cells.bin(x, len(x))
    on_soil = cells.neighbour_list(x, soil.astype(np.int64), radius, phase, 0)
    on_water = cells.neighbour_list(x, water.astype(np.int64), radius, phase, 1)
    drag = np.array([0.0, 0.16 * 9810 / 1e-3, 0.16 * 9810 / 1e-4])
    solid = np.array([0.0, 0.6, 0.7])
    grain = np.array([0.0, 2650.0, 2500.0])
    return dict(
        x=x, v=v, rho=rho, mass=mass, p=p, material=material, water=water, soil=soil, h=h, dim=dim,
        radius=radius, on_soil=on_soil, on_water=on_water, drag=drag, solid=solid, grain=grain,
        norm=cubic_spline_normalisation(dim, h),
    )  # fmt: skip


def _chunks(nl, n_chunks):
    """Row chunks as on n_chunks threads (always an array: chunks=None would be one more compiled variant)."""
    return row_chunks(nl.unsigned()[0], n_chunks)


def _pore(s, chunks=3, pairs=False):
    """p~ on the soil rows; with pairs, also the per-pair V W and V W'/r the pass leaves for the soil side."""
    pore = np.zeros(len(s["x"]))
    nl = s["on_soil"]
    vw, vf = (np.full(nl.pairs(), np.nan) for _ in range(2))
    pore_pressure_at_soil(
        nl.targets, *nl.unsigned(), s["x"], s["mass"] / s["rho"], s["p"], s["h"], s["norm"], pore,
        True if s["dim"] == 3 else None, _chunks(nl, chunks), vw, vf,
    )  # fmt: skip
    return (pore, vw, vf) if pairs else pore


def _rates(s, mixture=True, storage=True, wall=None, one_soil=None, linear=None, kappa=0.0, chunks=3):
    """Both sides in the solver's order: p~ at the soil, the water side (which writes p^ on the
    water rows in the mixture form), then the soil side; each pass in `chunks` chunks of rows (as
    on that many threads) and the soil side reading the pairs' V W and V W'/r of the p~ pass
    (mixture), as the solver does. Returns acc, drho, the two relaxation rates and the pore
    pressure field (p~ on soil rows, p^ on water rows)."""
    n, dim = len(s["x"]), s["dim"]
    acc, drho = np.zeros((n, dim)), np.zeros(n)
    pore, vw, vf = _pore(s, chunks, pairs=True) if mixture else (None, None, None)
    is3d = True if dim == 3 else None
    solid = s["solid"] if mixture else np.zeros(3)
    corr = np.zeros((n, 6)) if kappa > 0 else None
    vol = s["mass"] / s["rho"]
    lam_w = seepage_on_water(
        s["on_water"].targets, *s["on_water"].unsigned(), s["x"], s["v"], s["rho"], s["mass"], vol,
        s["material"], s["drag"], solid, s["grain"], s["h"], s["norm"], acc, drho if storage else None,
        s["p"] if mixture else None, pore, is3d, wall, one_soil, linear, corr, kappa,
        _chunks(s["on_water"], chunks),
    )  # fmt: skip
    lam_s = seepage_on_soil(
        s["on_soil"].targets, *s["on_soil"].unsigned(), s["x"], s["v"], s["rho"], s["mass"], vol,
        s["material"], s["drag"], solid, s["h"], s["norm"], acc, pore, is3d, wall, corr,
        _chunks(s["on_soil"], chunks), vw, vf,
    )  # fmt: skip
    if kappa > 0:
        s["corr"] = corr
    return acc, drho, lam_s, lam_w, pore


@pytest.mark.parametrize("dim", [2, 3])
def test_pore_pressure_at_soil_matches_twin(rng, dim):
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    expected = naive_seepage.pore_pressure_at_soil(
        s["soil"], s["water"], s["x"], s["rho"], s["mass"], s["p"], s["h"], dim, s["radius"]
    )
    np.testing.assert_allclose(_pore(s)[s["soil"]], expected[s["soil"]], rtol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_pore_pressure_at_water_matches_twin(rng, dim):
    """p^ on water rows from the soil's p~ (the buoyancy pair's water side, written by the water
    side of the coupling), p itself for water with no soil within reach (one water particle moved
    far away); soil rows keep p~."""
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    s["x"][0] += 10.0
    radius = s["radius"]
    cells = CellList(CellGrid.covering(np.full(dim, -1.0), np.full(dim, 11.0), radius, pad=radius))
    cells.bin(s["x"], len(s["x"]))
    phase = np.where(s["material"] == 0, 0, 1).astype(np.int32)
    s["on_soil"] = cells.neighbour_list(s["x"], s["soil"].astype(np.int64), radius, phase, 0)
    s["on_water"] = cells.neighbour_list(s["x"], s["water"].astype(np.int64), radius, phase, 1)
    expected = naive_seepage.pore_pressure_at_water(
        s["water"], s["soil"], s["x"], s["rho"], s["mass"], s["p"], _pore(s), s["h"], dim, radius
    )
    pore = _rates(s)[4]
    np.testing.assert_allclose(pore, expected, rtol=1e-12)
    assert pore[0] == s["p"][0]


@pytest.mark.parametrize("dim,one_soil", VARIANT_DIMS)
def test_linear_pore_pressure_at_water_matches_twin(rng, dim, one_soil):
    """numerics.pore_pressure_at_water = "linear": p^ the value at x_a of the weighted linear fit of
    the soil's p~ (the kernel's closed-form normal equations against the twin's np.linalg.solve), and
    the forces built on it equal and opposite."""
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    if one_soil is not None:
        s["material"][s["soil"]] = one_soil
    acc, _, _, _, pore = _rates(s, storage=False, one_soil=one_soil, linear=True)
    expected = naive_seepage.pore_pressure_at_water(
        s["water"],
        s["soil"],
        s["x"],
        s["rho"],
        s["mass"],
        s["p"],
        _pore(s),
        s["h"],
        dim,
        s["radius"],
        linear=True,
    )
    np.testing.assert_allclose(pore, expected, rtol=1e-10)
    shepard = _rates(s, storage=False, one_soil=one_soil)[4]
    assert np.abs(pore - shepard)[s["water"]].max() > 1.0  # the switch does something
    momentum_rate = (s["mass"][:, None] * acc).sum(axis=0)
    assert np.abs(momentum_rate).max() <= 1e-14 * (s["mass"][:, None] * np.abs(acc)).sum()


def test_linear_pore_pressure_is_exact_at_a_bed_surface():
    """A bed's free surface under water (water rows continuing above the soil's top row), p~ linear
    in y (still water: p = gamma_w (H - y)): the Shepard p^ of the water just above the bed reads the
    pressure of the soil below it, about gamma_w h too high; the linear fit reads the water's own to
    the ridge's bias (RIDGE), wherever the soil neighbours span two rows or more."""
    from solver.physics.seepage import RIDGE

    dim, dx = 2, 0.01
    h = 1.3 * dx
    xs = (np.stack(np.meshgrid(np.arange(10), np.arange(6), indexing="ij"), -1).reshape(-1, 2) + 0.5) * dx
    xw = (np.stack(np.meshgrid(np.arange(10), np.arange(9), indexing="ij"), -1).reshape(-1, 2) + 0.5) * dx
    x = np.vstack([xw, xs])
    nw = len(xw)
    water, soil = np.arange(nw), np.arange(nw, len(x))
    material = np.zeros(len(x), dtype=np.int32)
    material[soil] = 1
    rho = np.where(material == 0, 400.0, 1600.0)
    mass = rho * dx**dim
    gamma = 9810.0
    p = gamma * (0.1 - x[:, 1])
    radius = 2 * h * 1.1
    pore = np.where(material == 1, p, 0.0)  # p~ on the soil: exact
    exact, shepard = (
        naive_seepage.pore_pressure_at_water(water, soil, x, rho, mass, p, pore, h, dim, radius, linear=lin)
        for lin in (True, False)
    )
    above = water[(xw[:, 1] > 0.06) & (xw[:, 1] < 0.07) & (xw[:, 0] > 2 * dx) & (xw[:, 0] < 8 * dx)]
    assert np.abs(shepard[above] - p[above]).min() > 0.5 * gamma * dx
    assert np.abs(exact[above] - p[above]).max() < 10 * RIDGE * gamma * dx


def _expected(s, mixture, water=None):
    """The twins' pore pressures (p~ on soil, p^ on water rows; None in the seed form) and the
    coupling's accelerations and relaxation rates over the water particles `water` (all of them
    by default)."""
    water = s["water"] if water is None else water
    dim, radius = s["dim"], s["radius"]
    solid = s["solid"] if mixture else np.zeros(3)
    pore = None
    if mixture:
        pore = naive_seepage.pore_pressure_at_soil(
            s["soil"], s["water"], s["x"], s["rho"], s["mass"], s["p"], s["h"], dim, radius
        )
        pore = naive_seepage.pore_pressure_at_water(
            s["water"], s["soil"], s["x"], s["rho"], s["mass"], s["p"], pore, s["h"], dim, radius
        )
    acc, lam_s, lam_w = naive_seepage.seepage_accelerations(
        s["soil"], water, s["x"], s["v"], s["rho"], s["mass"], s["material"], pore, pore, s["drag"], solid,
        s["h"], dim, radius,
    )  # fmt: skip
    return pore, acc, lam_s, lam_w


@pytest.mark.parametrize("dim,mixture", [(2, True), (2, False), (3, True)])
def test_seepage_forces_and_storage_match_twin(rng, dim, mixture):
    """The three passes (p~ at soil, water side with p^ and storage, soil side) against the twins
    written pair by pair from the equations: the pore pressures, both sides' forces (the buoyancy
    with p^_a - p~_b), the relaxation rates and Biot's storage."""
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    acc, drho, lam_s, lam_w, pore = _rates(s, mixture=mixture, storage=mixture)
    exp_pore, exp_acc, exp_ls, exp_lw = _expected(s, mixture)
    if mixture:
        np.testing.assert_allclose(pore, exp_pore, rtol=1e-12)
    scale = np.abs(exp_acc).max()
    np.testing.assert_allclose(acc, exp_acc, rtol=1e-11, atol=1e-13 * scale)
    assert lam_s == pytest.approx(exp_ls, rel=1e-12) and lam_w == pytest.approx(exp_lw, rel=1e-12)
    if mixture:
        exp_drho = naive_seepage.storage(
            s["water"], s["soil"], s["x"], s["v"], s["rho"], s["mass"], s["material"], s["grain"], s["h"],
            dim, s["radius"],
        )  # fmt: skip
        np.testing.assert_allclose(drho, exp_drho, rtol=1e-10, atol=1e-12 * np.abs(exp_drho).max())
    else:
        assert not drho.any()


@pytest.mark.parametrize("dim", [2, pytest.param(3, marks=pytest.mark.nightly)])  # THREE_D
def test_one_soil_material_switch_gives_the_general_result(rng, dim):
    """seepage_on_water(one_soil=id), the compile-time switch for scenes with one soil material,
    equals the per-neighbour material lookup (to round-off: fastmath may hoist a reciprocal)."""
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    s["material"][s["soil"]] = 1
    (acc0, drho0, _, lam0, pore0), (acc1, drho1, _, lam1, pore1) = (
        _rates(s, one_soil=one) for one in (None, 1)
    )
    np.testing.assert_allclose(acc1, acc0, rtol=1e-14, atol=1e-15 * np.abs(acc0).max())
    np.testing.assert_allclose(drho1, drho0, rtol=1e-14, atol=1e-15 * np.abs(drho0).max())
    np.testing.assert_allclose(pore1, pore0, rtol=1e-14)
    assert lam1 == pytest.approx(lam0, rel=1e-14)


def test_wall_particles_take_no_part_in_the_coupling(rng):
    """Water particles flagged as walls (fixed water blocks) neither push nor are pushed: the rates
    equal the twin's over the other water particles alone (docs/seepage.md, "Pore water along a
    wall"); they still get p^ (an output) and the soil still sees them in p~."""
    s = two_phase(rng)
    wall = np.zeros(len(s["x"]), dtype=bool)
    wall[s["water"][rng.random(len(s["water"])) < 0.3]] = True
    acc, drho, _, _, pore = _rates(s, wall=wall)
    free = s["water"][~wall[s["water"]]]
    exp_pore, exp_acc, _, _ = _expected(s, True, free)
    np.testing.assert_allclose(pore, exp_pore, rtol=1e-12)
    np.testing.assert_allclose(acc, exp_acc, rtol=1e-11, atol=1e-13 * np.abs(exp_acc).max())
    assert not drho[wall].any() and drho[free].any()


@pytest.mark.parametrize("mixture", [True, False])
def test_pair_forces_are_equal_and_opposite(rng, mixture):
    """sum_i m_i a_i over both phases = 0 to round-off: both sides sum the same pair terms, the
    water side split around p^_a, which it computes in the same loop (docs/seepage.md)."""
    s = two_phase(rng)
    acc = _rates(s, mixture=mixture, storage=False)[0]
    momentum_rate = (s["mass"][:, None] * acc).sum(axis=0)
    scale = (s["mass"][:, None] * np.abs(acc)).sum()
    assert np.abs(momentum_rate).max() <= 1e-14 * scale


def test_row_chunks_split_the_work_evenly():
    """row_chunks: contiguous chunks covering every row once, each within one row's work (pairs + 1)
    of an even share, also when a third of the rows have no pairs (water above a bed)."""
    rng = np.random.default_rng(3)
    counts = np.concatenate([rng.integers(10, 30, 700), np.zeros(300, np.int64)])
    start = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    for n_chunks in (1, 2, 3, 8):
        bounds = row_chunks(start.view(np.uint64), n_chunks)
        assert bounds[0] == 0 and bounds[-1] == len(counts) and (np.diff(bounds) >= 0).all()
        work = np.array([start[hi] - start[lo] + hi - lo for lo, hi in zip(bounds[:-1], bounds[1:])])
        assert np.abs(work - work.sum() / n_chunks).max() <= counts.max() + 1


def test_chunks_change_nothing(rng):
    """The pair loops' results do not depend on how the rows are chunked over threads (each row's
    sums are the same, bit for bit). The soil side's two paths (V W and V W'/r read from the p~
    pass in the mixture, computed in the seed form) are each held to the NumPy twin by the tests
    above and below; a mixture call with the computed path would compile a variant the solver never
    uses (~10 s of CI)."""
    s = two_phase(rng)
    kappa = KAPPA[2]
    one = _rates(s, kappa=kappa, chunks=1)
    for chunks in (2, 5):
        other = _rates(s, kappa=kappa, chunks=chunks)
        for a, b in zip(one, other):
            np.testing.assert_array_equal(a, b)


KAPPA = {2: lattice_gradient_normalisation(2, 1.3), 3: lattice_gradient_normalisation(3, 1.3)}


@pytest.mark.parametrize("dim,one_soil", VARIANT_DIMS)
def test_corrected_buoyancy_matches_twin(rng, dim, one_soil):
    """The corrected mixture (buoyancy pair with L_a = kappa M_a^-1, Bonet & Lok 1999, blended to I
    where the soil support is cut) against the twin: L_a on every water row, both sides' forces;
    the drag, the relaxation rates, p^ and the storage are those of the uncorrected coupling."""
    s = two_phase(rng, dim, n_side=10 if dim == 2 else 5)
    if one_soil is not None:
        s["material"][s["soil"]] = one_soil
    acc, drho, lam_s, lam_w, pore = _rates(s, kappa=KAPPA[dim], one_soil=one_soil)
    plain = _rates(s, one_soil=one_soil)
    corr = naive_seepage.pair_correction(
        s["water"], s["soil"], s["x"], s["rho"], s["mass"], s["h"], dim, s["radius"], KAPPA[dim]
    )
    sym = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]
    for a in s["water"]:
        got = np.eye(3)
        for k, (i, j) in enumerate(sym):
            got[i, j] = got[j, i] = s["corr"][a, k]
        np.testing.assert_allclose(got[:dim, :dim], corr[a], rtol=1e-10, atol=1e-12)
    blended = [a for a in s["water"] if not np.allclose(corr[a], np.eye(dim))]
    assert len(blended) >= 10  # the correction is reached, not only the identity (a 5^3 cube is mostly edge)
    expected = naive_seepage.corrected_accelerations(
        s["soil"], s["water"], s["x"], s["v"], s["rho"], s["mass"], s["material"], pore, s["drag"],
        s["solid"], s["h"], dim, s["radius"], corr,
    )  # fmt: skip
    np.testing.assert_allclose(acc, expected, rtol=1e-10, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_allclose(pore, plain[4], rtol=1e-13)  # fastmath may reorder the extra sums
    np.testing.assert_allclose(drho, plain[1], rtol=1e-12, atol=1e-13 * np.abs(plain[1]).max())
    assert lam_s == pytest.approx(plain[2], rel=1e-13) and lam_w == pytest.approx(plain[3], rel=1e-13)


def test_corrected_pair_forces_are_equal_and_opposite(rng):
    """L_a multiplies each pair's vector on both sides (the soil side reads it from the water row):
    sum_i m_i a_i = 0 to round-off, as without the correction."""
    s = two_phase(rng)
    acc = _rates(s, storage=False, kappa=KAPPA[2])[0]
    momentum_rate = (s["mass"][:, None] * acc).sum(axis=0)
    assert np.abs(momentum_rate).max() <= 1e-14 * (s["mass"][:, None] * np.abs(acc)).sum()


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.0, 0.25), (0.0, 0.5), (0.3, 0.45)])
def test_corrected_pair_reads_the_lattice_normalisation_at_any_offset(offset):
    """docs/seepage.md, case 2: pore water on a lattice offset from the skeleton's, a linear p,
    at rest. Uncorrected, the pair's force on the water reads (1 - n) M grad p, M from 1.0105 I
    (coincident) to diag(1.020, 0.985) (half a dx off); corrected it reads (1 - n) kappa grad p,
    kappa = 1.0105, what the water's own pass reads on its lattice, so their difference is kappa n
    grad p at every offset."""
    dx, n_side, dim = 0.01, 14, 2
    i, j = np.meshgrid(np.arange(n_side), np.arange(n_side), indexing="ij")
    xs = (np.stack([i.ravel(), j.ravel()], axis=1) + 0.5) * dx
    xw = xs + np.array(offset) * dx
    x = np.vstack([xw, xs])
    nw = len(xw)
    material = np.r_[np.zeros(nw, np.int32), np.ones(nw, np.int32)]
    rho = np.where(material == 0, 400.0, 1600.0)
    grad = np.array([300.0, -1000.0])
    h = 1.3 * dx
    s = dict(
        x=x, v=np.zeros_like(x), rho=rho, mass=rho * dx**dim, p=x @ grad, material=material,
        water=np.arange(nw), soil=np.arange(nw, 2 * nw), h=h, dim=dim,
        norm=cubic_spline_normalisation(dim, h), drag=np.array([0.0, 1e6, 1e6]),
        solid=np.array([0.0, 0.6, 0.6]), grain=np.array([0.0, 2650.0, 2650.0]),
    )  # fmt: skip
    radius = 2 * h * 1.01
    cells = CellList(CellGrid.covering(np.zeros(dim), np.full(dim, n_side * dx), radius, pad=radius))
    cells.bin(x, len(x))
    s["on_soil"] = cells.neighbour_list(x, s["soil"].astype(np.int64), radius, material, 0)
    s["on_water"] = cells.neighbour_list(x, s["water"].astype(np.int64), radius, material, 1)
    centre = int(np.argmin(np.linalg.norm(xw - 0.5 * n_side * dx, axis=1)))
    read = {}
    for kappa in (0.0, KAPPA[2]):
        acc = _rates(s, storage=False, kappa=kappa)[0]
        read[kappa] = acc[centre] * rho[centre] / 0.6  # the pair's force per unit volume / (1 - n)
    # to 1e-5: the Shepard p~ and p^ of a linear p are exact only to ~1e-6 off the lattice points
    np.testing.assert_allclose(read[KAPPA[2]], KAPPA[2] * grad, rtol=1e-5)
    if offset[1] == 0.5:
        assert read[0.0][1] == pytest.approx(0.985 * grad[1], rel=1e-3)


BOX = (
    water_and_sand_scene(
        "two_phase_box",
        0.01,
        0.05,
        "[0.2, 0.2]",
        "[0.0, 0.0]",
        walls=False,
        friction_angle="30.0",
        seepage="{form}",
    )  # fmt: skip
    + rectangle_block("bed", "sand", "[0.05, 0.05]", "[0.15, 0.15]", "saturated = true")
    + rectangle_block("jet", "water", "[0.05, 0.15]", "[0.15, 0.19]")
)


@pytest.mark.parametrize("form", ["mixture", "seed"])
def test_closed_two_phase_box_conserves_momentum(form):
    """No walls, no gravity: a saturated square hit by a block of water moving at 1 m/s. Every
    term is a pair force (water-water, soil-soil, water-soil), so the total momentum stays at its
    initial value to round-off over 200 steps (the seepage pass alone is tested above)."""
    scene = parse_scene(__import__("tomllib").loads(BOX.replace("{form}", form)), "box.toml")
    sim = Simulation(scene)
    ps = sim.particles
    n = ps.n_owned
    jet = ps["material"][:n] == 0
    jet &= ps["x"][:n, 1] > 0.15
    ps["v_half"][:n][jet] = [0.0, -1.0]
    ps["v"][:n][jet] = [0.0, -1.0]
    p0 = (ps["mass"][:n, None] * ps["v_half"][:n]).sum(axis=0)
    for _ in range(200):
        sim.step()
    n = ps.n_owned
    p1 = (ps["mass"][:n, None] * ps["v_half"][:n]).sum(axis=0)
    scale = float((ps["mass"][:n] * np.linalg.norm(ps["v_half"][:n], axis=1)).sum())
    assert np.abs(p1 - p0).max() <= 1e-12 * abs(p0[1])
    assert scale > 0.1 * abs(p0[1])  # the water really hit the bed and moved it
    soil = ps["material"][:n] == 1
    assert np.abs(ps["v_half"][:n][soil]).max() > 1e-3


def test_seepage_terms_only_with_water_and_soil():
    """The plan: the coupling's terms and fields exist only in a scene with water and soil; the
    water-only and soil-only plans are those of main before the coupling (no seepage name, field
    or dt limit)."""
    from verification.column_collapse import scene_at
    from verification.common import scene_from_file

    names = {"pore pressure at soil", "seepage on soil", "seepage on water"}
    for scene in (scene_from_file("hydrostatic_tank_2d.toml"), scene_at(0.01, end_time=0.01)):
        plan = build_plan(scene)
        assert not names & {t.name for t in plan.terms}
        assert names <= set(plan.absent)
        assert not {"pore_pressure", "water_fraction", "pair_correction"} & set(plan.fields)
        assert "seepage drag" not in [c.name for c in plan.constraints]
        assert (Phase.WATER, Phase.SOIL) not in plan.pairs and (Phase.SOIL, Phase.WATER) not in plan.pairs
    box = lambda form: parse_scene(__import__("tomllib").loads(BOX.replace("{form}", form)), "box.toml")
    mix, seed = build_plan(box("mixture")), build_plan(box("seed"))
    assert names <= {t.name for t in mix.terms}
    assert "pore pressure at soil" not in {t.name for t in seed.terms}  # no buoyancy in the seed's form
    assert {"seepage on soil", "seepage on water"} <= {t.name for t in seed.terms}
    for plan in (mix, seed):
        assert (Phase.SOIL, Phase.WATER) in plan.pairs and (Phase.WATER, Phase.SOIL) in plan.pairs
        assert "seepage drag" in [c.name for c in plan.constraints]
    assert "pore_pressure" in mix.fields and "pore_pressure" not in seed.fields
    assert "pair_correction" in mix.fields and "pair_correction" not in seed.fields  # mixture buoyancy only


def test_explain_shows_the_seepage_terms_their_equations_and_exchanged_fields():
    scene = parse_scene(__import__("tomllib").loads(BOX.replace("{form}", "mixture")), "box.toml")
    text = explain(build_plan(scene), scene)
    for expected in (
        "pore pressure at soil: soil <- water",
        "seepage on soil: soil <- water",
        "seepage on water: water <- soil",
        "C = n^2 gamma_w / k",
        "pore pressure at water p^_a = sum_b V_b p~_b W_ab / sum_b V_b W_ab over soil b",
        "pore pressure on the skeleton -(1 - n) V_a V_b (p^_a - p~_b) grad W",
        "Biot storage",
        "seepage drag [dt <= cfl.drag / (lambda_soil + lambda_water)]",
        "pore_pressure",
    ):
        assert expected in text, expected
    seed = parse_scene(__import__("tomllib").loads(BOX.replace("{form}", "seed")), "box.toml")
    assert "C = n gamma_w / k" in explain(build_plan(seed), seed)
    # p~ exchanged once written (with the fields of an earlier reader, before 'seepage on water'), then
    # p^ before the soil side reads it
    refreshed = [ln for ln in text.splitlines() if "every step, before" in ln and "pore_pressure" in ln]
    assert len(refreshed) == 2 and "before 'seepage on soil'" in refreshed[1], refreshed


@pytest.mark.parametrize(
    "edit,key,reason",
    [
        ("porosity = 0.4\n", "materials.sand.porosity", "required when the scene has water"),
        ("permeability = 1.0e-3\n", "materials.sand.permeability", "required when the scene has water"),
        ("porosity = 1.0\n", "materials.sand.porosity", "less than 1"),
        ("porosity = 0.0\n", "materials.sand.porosity", "greater than 0"),
        ("permeability = 0.0\n", "materials.sand.permeability", "greater than 0"),
        ("permeability = -1e-3\n", "materials.sand.permeability", "greater than 0"),
    ],
)
def test_scene_refusals_name_the_key(tmp_path, edit, key, reason):
    text = BOX.replace("{form}", "mixture")
    original = "porosity = 0.4\n" if edit.startswith("porosity") else "permeability = 1.0e-3\n"
    text = text.replace(original, "" if edit == original else edit)
    path = write_scene(tmp_path, text)
    r = subprocess.run(
        SCOURSPH + ["run", str(path), "--out", str(tmp_path / "o")], capture_output=True, text=True, env=ENV
    )
    assert r.returncode == 2, r.stderr
    assert key in r.stderr and reason in r.stderr and str(path) in r.stderr, r.stderr
    assert not (tmp_path / "o").exists()
