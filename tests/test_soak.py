"""Soak, CI size (issue 14; the full soak is `python -m verification.soak`): a run writing many
snapshots keeps its memory flat, leaks no file handle, and every snapshot reads back.

The dam break at a/10 to 4x its end time with a snapshot every 4 ms (331 snapshots, each an HDF5
file, a VTK file and a rewrite of the series and ParaView index), with the defaults: since issue 15
they hold the water through the impact (with the seed's scheme it blows up at t = 0.81 s at a/10;
before issue 15 this test needed water alpha = 0.1 and hydrostatic images).
"""

import pytest

from verification import soak

OPTIONS = []  # the defaults (issue 15)


@pytest.mark.slow
def test_soak_ci_size(tmp_path):
    res = soak.soak(
        spacing_ratio=10, factor=4, out_dir=tmp_path / "run", sets=[*OPTIONS, "output.interval=0.004"]
    )
    assert res.status == "completed", res.status
    assert res.read_ok, res.read_error
    assert res.snapshots == res.expected_snapshots == 331
    assert res.growth < soak.GROWTH_LIMIT, (res.rss_warm_mb, res.rss_max_mb)
    assert res.fd_last <= res.fd_first, (res.fd_first, res.fd_last)
