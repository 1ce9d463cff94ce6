"""Slow, obviously-correct NumPy twins of the sand-with-a-state kernels (solver/physics/sand_state.py),
written from the relations (Bolton 1986; Li & Wang 1998) and the general return-mapping formula
dl = f / (df/dsigma : D : dg/dsigma) in the in-plane principal frame (full matrices, numpy.linalg)."""

import numpy as np
from naive_soil import to_matrix, to_voigt


def critical_void_ratio(p, e_gamma, lam, xi, p_a):
    return e_gamma - lam * (max(p, 0.0) / p_a) ** xi


def bolton_index(e, p, e_min, e_max, e_gamma, lam, xi, p_a, q):
    """Bolton's I_R = I_D (Q - ln p') - R written with the critical line in place of R's line:
    I_D (Q - ln p') - R = (e_line - e)(Q - ln p') / (e_max - e_min), e_line = e_c(p'); clipped to [-4, 4]."""
    i_r = (
        (critical_void_ratio(p, e_gamma, lam, xi, p_a) - e)
        * (q - np.log(max(p, 1.0) / 1e3))
        / (e_max - e_min)
    )
    return float(np.clip(i_r, -4.0, 4.0))


def plane_strain_return(p, s6, sin_phi, sin_psi, c, k, g):
    """Mohr-Coulomb in the x-y plane with the potential of dilatancy psi; returns (p, s6, dvol)."""
    sigma = -p * np.eye(3) + to_matrix(s6)  # tension positive
    cos_phi = np.sqrt(1 - sin_phi**2)
    if p < -c * cos_phi / sin_phi:
        return -c * cos_phi / sin_phi, np.zeros(6), None
    if 0.5 * np.trace(-sigma[:2, :2]) < -c * cos_phi / sin_phi:  # the in-plane mean beyond the apex
        return None
    w, v = np.linalg.eigh(-sigma[:2, :2])  # in-plane principal stresses, compression positive, ascending
    s3, s1 = w
    f = 0.5 * (s1 - s3) - 0.5 * (s1 + s3) * sin_phi - c * cos_phi
    if f <= 0:
        return p, np.array(s6, float), 0.0
    lam = k - 2 * g / 3
    d = lam * np.ones((3, 3)) + 2 * g * np.eye(3)  # principal (1, 3, zz), compression positive
    df = np.array([0.5 - 0.5 * sin_phi, -0.5 - 0.5 * sin_phi, 0.0])
    dg = np.array([0.5 - 0.5 * sin_psi, -0.5 - 0.5 * sin_psi, 0.0])  # plastic strain, compression positive
    dl = f / (df @ d @ dg)
    new = np.array([s1, s3, -sigma[2, 2]]) - dl * (d @ dg)
    if new[0] < new[1]:
        return None  # past the apex: the twin does not follow (tests/test_sand_state.py checks it by hand)
    rot = np.eye(3)
    rot[:2, :2] = v[:, ::-1]  # columns: directions of s1, s3
    comp = rot @ np.diag([new[0], new[1], 0.0]) @ rot.T
    comp[2, 2] = new[2]
    comp[0, 2] = comp[2, 0] = -sigma[0, 2]
    comp[1, 2] = comp[2, 1] = -sigma[1, 2]
    p_new = np.trace(comp) / 3
    return p_new, to_voigt(-comp + p_new * np.eye(3)), -dl * dg.sum()  # dilation positive
