"""The impact case's first-impact statistics (verification/impact_pressure.py, metric 5) on synthetic records:
the pressure impulse does not see a water hammer's height, only the momentum it carries; the acoustic peak
of a short spike is its impulse per acoustic period. No simulation: milliseconds."""

import numpy as np
import pytest

from verification import impact_pressure as ip

C0 = 10.0 * np.sqrt(2 * ip.G * ip.H)  # the case's sound speed


def record(hammer, t_impact=2.4, load=1.0, end=3.2):
    """p*(t*): zero before t_impact, then `load`, plus a water hammer of height `hammer` over 0.01 t* followed
    by its rarefaction (-hammer over the next 0.01 t*), sampled every 1e-4 t* (finer than the sensors)."""
    t = np.arange(1.8, end, 1e-4)
    p = np.where(t >= t_impact, load, 0.0)
    p = p + np.where((t >= t_impact) & (t < t_impact + 0.01), hammer, 0.0)
    p = p - np.where((t >= t_impact + 0.01) & (t < t_impact + 0.02), hammer, 0.0)
    return t, p


@pytest.mark.parametrize("hammer", [0.0, 10.0, 50.0])
def test_impulse_is_blind_to_the_water_hammer(hammer):
    """The hammer and its rarefaction integrate out: the impulse is the load times the window after impact
    (0.5 t*), whatever the spike's height, where the 1 ms peak grows with it."""
    t, p = record(hammer)
    grid, f, _ = ip.filtered(t, p)
    assert ip.impulse(grid, f, 2.4) == pytest.approx(1.0 * ip.IMPULSE_WINDOW[1], rel=2e-3)
    assert f.max() == pytest.approx(1.0 + hammer, rel=0.05)


def test_acoustic_peak_of_a_spike_is_its_impulse_per_acoustic_period():
    """A lone spike (no load, no rarefaction) of impulse S: after the moving average over tau_ac its peak is
    S / tau_ac (t* units), the largest impulse over one acoustic period per unit time."""
    t = np.arange(1.8, 3.2, 1e-4)
    p = np.where((t >= 2.4) & (t < 2.41), 20.0, 0.0)  # impulse 0.2
    grid, f, _ = ip.filtered(t, p, ip.acoustic_window(C0))
    tau_star = ip.acoustic_window(C0) / ip.TIME_SCALE
    assert ip.acoustic_peak(grid, f, 2.4) == pytest.approx(0.2 / tau_star, rel=0.02)


def test_short_record_gives_no_impulse():
    """A record that stops inside the window (a stopped run) gives nan, never a truncated impulse."""
    t, p = record(10.0, end=2.7)
    grid, f, _ = ip.filtered(t, p)
    assert np.isnan(ip.impulse(grid, f, 2.4))
    assert np.isnan(ip.acoustic_peak(grid, f, 2.4))


def test_band_impulses_are_ordered():
    """The measured band's 2.5 / 50 / 97.5 % curves give ordered impulses and acoustic peaks (the check's
    reference and its spread)."""
    _, band, _ = ip.experiment()
    ref = ip.band_statistics(band, C0)
    assert ref["impulse_lo"] < ref["impulse_median"] < ref["impulse_hi"]
    assert ref["peak_ac_lo"] < ref["peak_ac_median"] < ref["peak_ac_hi"]
