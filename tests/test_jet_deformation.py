"""The plunging jet's bed-deformation probe (verification/jet_deformation.py): Darcy's steady head
against the closed form it sums, the heave check's factor of safety from it, and a short probe run."""

import numpy as np
import pytest

from verification import jet_deformation as jd

L, D = 0.63, 0.105  # m: the plunging layer (solver/scenes/scour_plunging_saturated.toml)


def midpoints(n):
    return (np.arange(n) + 0.5) * L / n


@pytest.mark.parametrize("mode", [0, 1, 7])
def test_steady_head_is_the_single_mode_solution(mode):
    """A load H + A cos(k pi x / L) on the top, no flow through the base and the ends: Laplace's
    solution is H + A cos(k pi x / L) cosh(k pi y / L) / cosh(k pi D / L) (separation of variables).
    The DCT of the sampled load is exact at the samples, so the series must match to round-off."""
    x = midpoints(126)
    y = np.linspace(0.0, D, 8)
    k = mode * np.pi / L
    load = 0.2 + 0.03 * np.cos(k * x)
    h, dh = jd.steady_head(x, load, depth=D, length=L, y=y)
    exact = 0.2 + 0.03 * np.cos(k * x)[:, None] * (np.cosh(k * y) / np.cosh(k * D))[None, :]
    d_exact = 0.03 * np.cos(k * x)[:, None] * (k * np.sinh(k * y) / np.cosh(k * D))[None, :]
    assert np.max(np.abs(h - exact)) < 1e-12
    assert np.max(np.abs(dh - d_exact)) < 1e-10


def test_steady_head_of_a_jet_load_drains_down_under_it_and_up_beside_it():
    """A raised head over 0.15-0.25 m (the jet's landing): the water flows down under the load
    (dh/dy > 0 there: the head rises towards the top) and comes back up beside it, and the head at
    the base lies between the load's smallest and largest value (the maximum principle)."""
    x = midpoints(126)
    load = np.where((x > 0.15) & (x < 0.25), 0.33, 0.105)
    h, dh = jd.steady_head(x, load, depth=D, length=L, y=np.array([0.0, 0.05]))
    under = (x > 0.18) & (x < 0.22)
    beside = (x > 0.27) & (x < 0.32)
    assert np.all(dh[under, 1] > 0.0) and np.all(dh[beside, 1] < 0.0)
    assert load.min() < h[:, 0].min() and h[:, 0].max() < load.max()


def test_probe_run_writes_its_record(tmp_path):
    """The probe at 10 mm for 0.02 s: the record names its command, the samples carry the split
    of the hole (eroded part, sinkage per depth) and the fields file holds the averaged head."""
    result = jd.run(0.01, 0.02, tag="smoke", every=0.01, out=tmp_path)
    assert result["command"].startswith("python -m verification.jet_deformation run --dx 0.01")
    assert [round(s["t"], 6) for s in result["samples"]] == [0.01, 0.02]
    last = result["samples"][-1]
    assert {"d_jet_mm", "eroded_mm", "at_depth"} <= set(last)
    assert np.isfinite(last["d_jet_mm"])
    assert (tmp_path / "smoke_dx10mm.json").exists() and (tmp_path / "smoke_dx10mm.npz").exists()
