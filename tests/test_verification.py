"""The verification cases at CI resolution: every check must pass (tolerances and their
sources live in the case modules)."""

import pytest

from verification import dam_break, hydrostatic


@pytest.mark.slow
def test_dam_break_matches_experiment_ritter_and_openfoam(tmp_path):
    res = dam_break.run(dam_break.DEFAULT_RESOLUTION, out_dir=tmp_path)
    assert res.figure.is_file()
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)


@pytest.mark.slow
def test_still_water_stays_hydrostatic(tmp_path):
    res = hydrostatic.run(hydrostatic.DEFAULT_RESOLUTION, out_dir=tmp_path)
    failed = [c.line() for c in res.checks if not c.passed]
    assert not failed, "\n".join(failed)
