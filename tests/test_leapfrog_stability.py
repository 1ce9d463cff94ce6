"""The stability analysis behind the known still-water defect (verification/leapfrog_stability.py)."""

import numpy as np

from verification.leapfrog_stability import amplification, spectral_radius, staggered_amplification


def test_analysis_reproduces_the_symplectic_leapfrog():
    """Check of the analysis itself: the staggered (symplectic) leap-frog is neutrally stable
    for omega dt < 2, |G| = 1 to round-off."""
    for w in (0.1, 0.5, 1.0, 1.9):
        assert abs(spectral_radius(staggered_amplification(w)) - 1.0) < 1e-12


def test_seed_scheme_grows_undamped_and_needs_dissipation():
    """The seed's half-step scheme with predicted rates amplifies an undamped acoustic mode
    (|G| > 1); artificial viscosity alpha = 0.1 damps it at omega dt = 0.3, alpha = 0.01 not."""
    assert spectral_radius(amplification(0.3, 0.0)) > 1.0
    assert spectral_radius(amplification(0.3, 0.01)) > 1.0
    assert spectral_radius(amplification(0.3, 0.1)) < 1.0
    # growth falls steeply with the step: halving dt cuts the growth per unit time
    g1 = np.log(spectral_radius(amplification(0.5)))
    g2 = 2 * np.log(spectral_radius(amplification(0.25)))
    assert g2 < g1 / 4


def test_whole_step_density_is_neutral_and_damped_only_by_the_dissipative_terms():
    """rho at whole steps with one rate evaluation per step (numerics.leapfrog = "symplectic_density",
    and the proposed midpoint-continuity kick-drift-kick, which is the same linear map): |G| = 1 without
    damping up to omega dt < 2, < 1 with AV or density diffusion (issue 15's growth table)."""
    from verification.leapfrog_stability import whole_step_density_amplification

    for w in (0.1, 0.5, 1.0, 1.5):
        assert abs(spectral_radius(whole_step_density_amplification(w)) - 1.0) < 1e-12
        assert spectral_radius(whole_step_density_amplification(w, alpha=0.01)) < 1.0
        assert spectral_radius(whole_step_density_amplification(w, diffusion=0.1)) < 1.0


def test_dualsphysics_symplectic_is_not_neutral_for_the_acoustic_pair():
    """DualSPHysics' predictor-corrector updates rho with the rate at the predicted half step: for the
    linear acoustic pair it is the explicit midpoint rule, |G|^2 = 1 + (omega dt)^4 / 4 without damping."""
    from verification.leapfrog_stability import dualsphysics_symplectic_amplification

    for w in (0.1, 0.5, 1.0):
        g = spectral_radius(dualsphysics_symplectic_amplification(w))
        assert abs(g**2 - (1 + w**4 / 4)) < 1e-12
