"""Soak, CI size (issue 14; the full soak is `python -m verification.soak`): a run writing many
snapshots keeps its memory flat, leaks no file handle, and every snapshot reads back.

The dam break at a/10 to 4x its end time with a snapshot every 2 ms (661 snapshots, each an HDF5
file, a VTK file and a rewrite of the series and ParaView index), with the options under which
the water runs past the impact (artificial viscosity alpha = 0.1 for water, hydrostatic images):
with the seed's settings it blows up at t = 0.81 s at a/10 (issue 15).
"""

import pytest

from verification import soak

OPTIONS = [
    'numerics.image_pressure="hydrostatic"',
    "numerics.artificial_viscosity.water={alpha=0.1,beta=0.0}",
]


@pytest.mark.slow
def test_soak_ci_size(tmp_path):
    res = soak.soak(
        spacing_ratio=10, factor=4, out_dir=tmp_path / "run", sets=[*OPTIONS, "output.interval=0.002"]
    )
    assert res.status == "completed", res.status
    assert res.read_ok, res.read_error
    assert res.snapshots == res.expected_snapshots == 661
    assert res.growth < soak.GROWTH_LIMIT, (res.rss_warm_mb, res.rss_max_mb)
    assert res.fd_last <= res.fd_first, (res.fd_first, res.fd_last)
