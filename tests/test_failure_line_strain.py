"""Strain-based failure line (verification/column_collapse_failure_line.py): the corrected SPH
deformation gradient and the equivalent shear strain on known deformations of a lattice."""

import numpy as np

from verification import column_collapse_failure_line as fl

DX = 0.01


def lattice(nx=20, ny=12):
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    return np.column_stack([(i.ravel() + 0.5) * DX, (j.ravel() + 0.5) * DX])


def test_pairs_match_brute_force():
    X = np.random.default_rng(1).random((300, 2)) * 0.1
    i, j = fl.pairs(X, 0.013)
    d2 = np.sum((X[:, None] - X[None]) ** 2, axis=-1)
    bi, bj = np.nonzero((d2 < 0.013**2) & ~np.eye(len(X), dtype=bool))
    assert set(zip(i.tolist(), j.tolist())) == set(zip(bi.tolist(), bj.tolist()))


def test_rigid_motion_has_zero_strain_everywhere():
    X = lattice()
    th = 0.7
    Q = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    x = X @ Q.T + np.array([0.3, -0.05])
    F = fl.deformation_gradient(X, x, DX)
    assert np.allclose(F, Q, atol=1e-12)  # corrected form: exact for linear maps, also at the edges
    assert fl.shear_strain(F).max() < 1e-12
    # the whole lattice is undisturbed at any threshold: each row's boundary is its last particle
    fx, fy = fl.strain_boundary(X, x, DX, fl.shear_strain(F), 0.01)
    assert len(fx) == 12


def test_simple_shear_matches_green_strain():
    X = lattice()
    g = 0.3
    x = X + np.column_stack([g * X[:, 1], np.zeros(len(X))])
    gamma = fl.shear_strain(fl.deformation_gradient(X, x, DX))
    # E = [[0, g/2], [g/2, g^2/2]], E_zz = 0: sqrt(2 dev(E):dev(E)) = g sqrt(1 + g^2 / 3)
    interior = (X[:, 0] > 3 * DX) & (X[:, 0] < 17 * DX) & (X[:, 1] > 3 * DX) & (X[:, 1] < 9 * DX)
    assert np.allclose(gamma[interior], g * np.sqrt(1 + g * g / 3), rtol=1e-10)
    assert np.allclose(gamma, g * np.sqrt(1 + g * g / 3), rtol=1e-10)  # linear field: exact at the edges too


def test_boundary_is_contiguous_from_the_left_wall():
    X = lattice(10, 3)
    gamma = np.zeros(len(X))
    gamma[(X[:, 0] > 4 * DX) & (X[:, 0] < 5 * DX)] = 1.0  # a strained column at i = 4 ...
    gamma[(X[:, 0] > 7 * DX)] = 0.0  # ... undisturbed again to its right: not counted
    fx, fy = fl.strain_boundary(X, X, DX, gamma, 0.1)
    assert np.allclose(fx, 4 * DX) and len(fx) == 3  # particle i = 3 at 3.5 dx, + dx/2


def test_displacement_line_has_one_point_per_lattice_row():
    """Regression: rows at (i + 1/2) dx binned with np.round merged in pairs (round half to
    even), so the failure line of the collapse used about half the rows."""
    from verification.column_collapse import failure_line

    X = lattice(20, 12)
    fx, fy = failure_line(X, X, DX, threshold=0.005)
    assert len(fx) == 12 and np.allclose(np.sort(fy), (np.arange(12) + 0.5) * DX)
    assert np.allclose(fx, 20 * DX)  # undisturbed: each row's last particle + dx/2
