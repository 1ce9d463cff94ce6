"""`scoursph verify` reports failure in its exit status (issue 13): a failed study, a case that
cannot be imported, a case that raises, missing reference data; errors on standard error."""

import importlib
import itertools
import json
import shutil
import textwrap
from pathlib import Path

import numpy as np
import pytest

from verification import dam_break, registry

CASE = """
import math
from verification.common import CaseResult, Check
DEFAULT_RESOLUTION = 1
STUDY_RESOLUTIONS = (1, 2)

def run(resolution, out_dir=None):
    res = CaseResult("{name}", resolution, 1, 1, 0.0, {{}})
    res.checks = [Check("value", {value}, 1.0, "test")]
    return res

def study(out_dir=None):
    {study}
"""


MADE = itertools.count()  # module names unique in the whole session (sys.modules caches them)


@pytest.fixture
def cases(tmp_path, monkeypatch):
    """Fake case modules registered in place of the real ones."""
    monkeypatch.syspath_prepend(str(tmp_path))

    def make(**specs):
        table = {}
        for name, (value, study) in specs.items():
            module = f"fake_{name}_{next(MADE)}"  # a new module each time: no stale import
            (tmp_path / f"{module}.py").write_text(
                textwrap.dedent(CASE).format(name=name, value=value, study=study)
            )
            table[name] = module
        importlib.invalidate_caches()
        monkeypatch.setattr(registry, "CASES", table)

    return make


GOOD_STUDY = "return [{'resolution': 1, 'error': 0.1, 'wall_time_s': 1.0}]"
NAN_STUDY = "return [{'resolution': 1, 'error': math.nan, 'wall_time_s': 1.0}]"


def test_all_passes_only_when_every_case_passes(cases, tmp_path, capsys):
    cases(a=(0.5, GOOD_STUDY), b=(0.5, GOOD_STUDY))
    assert registry.run_cases("all", tmp_path) == 0
    cases(a=(0.5, GOOD_STUDY), b=(2.0, GOOD_STUDY))
    assert registry.run_cases("all", tmp_path) == 1
    assert "b [FAIL]" in capsys.readouterr().out


def test_study_exit_status_reflects_a_non_finite_error(cases, tmp_path, capsys):
    cases(a=(0.5, GOOD_STUDY))
    assert registry.run_cases("a", tmp_path, study=True) == 0
    cases(a=(0.5, NAN_STUDY))
    assert registry.run_cases("a", tmp_path, study=True) == 1
    assert "[FAIL] resolution 1: error = nan" in capsys.readouterr().out
    cases(a=(0.5, "return []"))
    assert registry.run_cases("a", tmp_path, study=True) == 1


def test_study_that_raises_fails_and_the_others_still_run(cases, tmp_path, capsys):
    cases(a=(0.5, "raise RuntimeError('blew up at t = 0.1 s')"), b=(0.5, GOOD_STUDY))
    assert registry.run_cases("all", tmp_path, study=True) == 1
    out = capsys.readouterr()
    assert "verify a: RuntimeError: blew up" in out.err and "b: resolution study" in out.out


def test_study_writes_under_out_not_into_the_package(cases, tmp_path):
    cases(
        a=(
            0.5,
            "import pathlib; pathlib.Path(out_dir).mkdir(parents=True); " + GOOD_STUDY,
        )
    )
    registry.run_cases("a", tmp_path / "v", study=True)
    assert (tmp_path / "v" / "a").is_dir()


def test_a_case_that_cannot_be_imported_is_reported_not_dropped(cases, tmp_path, capsys, monkeypatch):
    cases(a=(0.5, GOOD_STUDY))
    monkeypatch.setitem(registry.CASES, "broken", "fake_no_such_module")
    assert registry.run_cases("all", tmp_path) == 1
    out = capsys.readouterr()
    assert "verify broken: the case cannot be imported" in out.err and "a [PASS]" in out.out


def test_unknown_case_is_bad_input_on_stderr(tmp_path, capsys):
    assert registry.run_cases("no_such_case", tmp_path) == 2
    out = capsys.readouterr()
    assert "unknown verification case" in out.err and out.out == ""


def test_dam_break_openfoam_data_missing_is_an_error(tmp_path, monkeypatch):
    """The OpenFOAM checks read the runs the manifest lists: a missing file raises (and fails
    `verify dam_break`) instead of the checks silently disappearing."""
    case = tmp_path / "openfoam_dam_break_2d"
    original = dam_break.OPENFOAM_CASE
    shutil.copytree(original / "data", case / "data")
    shutil.copy(original / "manifest.json", case / "manifest.json")
    monkeypatch.setattr(dam_break, "OPENFOAM_CASE", case)
    monkeypatch.setattr(dam_break, "OPENFOAM", case / "data")
    assert sorted(dam_break.openfoam_series()) == [10, 20, 40]
    (case / "data" / "openfoam_dx40.csv").unlink()
    with pytest.raises(FileNotFoundError, match="openfoam_dx40.csv"):
        dam_break.openfoam_series()
    (case / "manifest.json").unlink()
    with pytest.raises(FileNotFoundError, match="manifest"):
        dam_break.openfoam_series()
    manifest = json.loads((original / "manifest.json").read_text())
    manifest["runs"] = {}
    (case / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(FileNotFoundError, match="no runs"):
        dam_break.openfoam_series()


def test_dam_break_checks_fail_loudly_without_openfoam_data(tmp_path, monkeypatch):
    """Through the checks themselves: a result whose OpenFOAM data are gone raises."""
    monkeypatch.setattr(dam_break, "OPENFOAM_CASE", tmp_path)
    T = np.linspace(0, dam_break.T_END, 121)
    series = {"T": T, "Z": 1 + 1.5 * T, "tau": T / np.sqrt(2), "H": np.clip(1 - 0.1 * T, 0, 1)}
    res = dam_break.CaseResult("dam_break", 20, 800, 1, 0.0, series)
    with pytest.raises(FileNotFoundError):
        dam_break.checks(res)


def test_a_case_module_has_a_help_and_refuses_a_bad_resolution(capsys):
    """`python -m verification.CASE --help` prints its usage (it raised a ValueError traceback), and a
    resolution that is not a positive integer exits 2 naming the argument, before anything runs."""
    from verification import common, seepage_darcy

    with pytest.raises(SystemExit) as done:
        common.case_main(seepage_darcy, ["--help"])
    assert done.value.code == 0 and "resolution" in capsys.readouterr().out
    for bad in (["fine"], ["0"], ["-3"]):
        with pytest.raises(SystemExit) as done:
            common.case_main(seepage_darcy, bad)
        err = capsys.readouterr().err
        assert done.value.code == 2 and "resolution" in err


SCRIPTS = sorted(
    p.stem for p in (Path(registry.__file__).parent).glob("*.py") if '__name__ == "__main__"' in p.read_text()
)


@pytest.mark.filterwarnings("ignore:.*found in sys.modules:RuntimeWarning")  # runpy: already imported
@pytest.mark.parametrize("name", SCRIPTS)
def test_every_verification_script_answers_help(name, monkeypatch, capsys):
    """`python -m verification.X --help` prints a usage and exits 0 for every script (one started a
    simulation, three raised a traceback), run in-process as `-m` would."""
    import runpy
    import sys

    monkeypatch.setattr(sys, "argv", [name, "--help"])
    with pytest.raises(SystemExit) as done:
        runpy.run_module(f"verification.{name}", run_name="__main__", alter_sys=True)
    assert done.value.code in (0, None) and "usage:" in capsys.readouterr().out
