"""Tension cracking resets the density to the cut-off state (issue 14).

A detached grain of cohesionless soil kept losing density by continuity (seed eq. 6) while its
neighbours receded, since the tension cut-off holds p at the cut-off whatever rho is; at
rho -> 0 and below, the artificial viscosity (eq. 19) changed sign and the column collapses of
issue 14 blew up. The history update now puts the crack opening into the density:
rho = rho0 (1 + p_cut / K - eps_vp), eps_vp keeps only the plastic dilatancy (psi).
"""

import numpy as np
import pytest

from solver.materials import YieldModel
from solver.physics.soil_stress import soil_stress_state

K, G = 7.0e5, 3.2e5
RHO0 = 2650.0


def _params(model, phi, c, psi=0.0):
    t, tp = np.tan(np.radians(phi)), np.tan(np.radians(psi))
    a_phi = t / np.sqrt(9 + 12 * t * t)
    return dict(
        bulk=np.array([K]),
        shear=np.array([G]),
        tan_phi=np.array([t]),
        cohesion=np.array([c]),
        alpha_phi=np.array([a_phi]),
        k_c=np.array([3 * c / np.sqrt(9 + 12 * t * t)]),
        alpha_psi=np.array([tp / np.sqrt(9 + 12 * tp * tp)]),
        yield_model=np.array([model], dtype=np.int64),
    )


def _update(rho, s, eps_vp, prm, history=True):
    rho, s, eps_vp = np.array(rho, float), np.array(s, float), np.array(eps_vp, float)
    p = np.zeros(len(rho))
    rows = np.arange(len(rho), dtype=np.int64)
    mat = np.zeros(len(rho), dtype=np.int64)
    soil_stress_state(
        rows,
        rho,
        s,
        mat,
        np.array([RHO0]),
        prm["bulk"],
        prm["shear"],
        prm["tan_phi"],
        prm["cohesion"],
        prm["alpha_phi"],
        prm["k_c"],
        prm["alpha_psi"],
        prm["yield_model"],
        p,
        eps_vp,
        history,
    )
    return rho, s, eps_vp, p


@pytest.mark.parametrize(
    "model, c, p_cut",
    [
        (int(YieldModel.DRUCKER_PRAGER), 0.0, 0.0),
        (int(YieldModel.DRUCKER_PRAGER), 200.0, None),  # apex -k_c / (3 alpha_phi) = -c / tan(phi)
        (int(YieldModel.MOHR_COULOMB), 200.0, None),  # cut-off -c / tan(phi)
    ],
)
def test_cracking_resets_density_to_the_cut_off_state(model, c, p_cut):
    phi = 19.8
    prm = _params(model, phi, c)
    if p_cut is None:
        p_cut = -c / np.tan(np.radians(phi))
    eps0 = 0.01  # plastic dilatancy from before: kept
    rho = [0.05 * RHO0, 0.6 * RHO0, -0.2 * RHO0]  # far stretched, moderately, and already unphysical
    s0 = np.tile([30.0, -30.0, 0.0, 10.0, 0.0, 0.0], (3, 1))
    r, s, e, p = _update(rho, s0, [eps0] * 3, prm)
    rho_cut = RHO0 * (1.0 + p_cut / K - eps0)  # eq. (17) solved for rho at p = p_cut
    np.testing.assert_allclose(r, rho_cut, rtol=1e-12)
    np.testing.assert_array_equal(e, eps0)  # the crack is not plastic dilatancy
    np.testing.assert_allclose(p, p_cut, atol=1e-9 * K)
    # the next stress evaluation from the reset density gives the cut-off pressure again
    _, _, _, p2 = _update(r, s, e, prm, history=False)
    np.testing.assert_allclose(p2, p_cut, atol=1e-9 * K)


def test_recompression_follows_the_same_pressure_as_before():
    """Continuity's rate does not depend on rho_i, so after a crack the same density increment
    gives the same p as the former eps_vp bookkeeping did: only the density changes."""
    prm = _params(int(YieldModel.DRUCKER_PRAGER), 19.8, 0.0)
    rho_stretched = 0.3 * RHO0
    r, s, e, _ = _update([rho_stretched], np.zeros((1, 6)), [0.0], prm)
    d_rho = 0.02 * RHO0  # recompression by continuity
    _, _, _, p_new = _update(r + d_rho, s, e, prm, history=False)
    # former bookkeeping: rho kept, eps_vp += crack opening (p_cut - p_trial) / K
    eps_old = -(K * (rho_stretched / RHO0 - 1.0)) / K
    p_old = K * ((rho_stretched + d_rho) / RHO0 - 1.0 + eps_old)
    assert p_new[0] == pytest.approx(p_old, rel=1e-12)
    assert p_new[0] == pytest.approx(K * 0.02, rel=1e-12)


def test_dilatancy_still_goes_to_eps_vp():
    prm = _params(int(YieldModel.DRUCKER_PRAGER), 30.0, 50.0, psi=10.0)
    rho = RHO0 * (1 + 200.0 / K)  # p = 200 Pa, sheared beyond the cone: plastic flow, no crack
    s0 = np.array([[1000.0, -1000.0, 0.0, 500.0, 0.0, 0.0]])
    r, _, e, p = _update([rho], s0, [0.0], prm)
    assert r[0] == rho  # no crack: density untouched
    assert e[0] > 0.0 and p[0] > 200.0  # dilatancy accumulated, raising p
