"""The package as a user installs it (issue 13): a wheel built from the repository, installed
into a fresh venv, run from a directory that is not the repository.

To stay fast the venv gets the project's dependencies from this .venv through a .pth line
(only a path: the editable install of this repository there is not activated, and the wheel's
own copy in the new venv's site-packages comes first on sys.path); the wheel itself is
installed without dependencies. Every `scoursph` command then has to find its scenes,
defaults and verification data inside the installed package.
"""

import os
import subprocess
import sys
import sysconfig
import textwrap
from pathlib import Path

import pytest
from conftest import ROOT


def _run(cmd, cwd, env, timeout=600):
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout)
    assert proc.returncode == 0, f"{' '.join(map(str, cmd))}\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    return proc


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("install")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["NUMBA_NUM_THREADS"] = "1"
    _run(
        [sys.executable, "-m", "pip", "wheel", str(ROOT), "--no-deps", "-q", "-w", str(tmp / "dist")],
        tmp,
        env,
    )
    wheel = next((tmp / "dist").glob("scoursph-*.whl"))
    venv = tmp / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)], tmp, env)
    python = venv / "bin" / "python"
    purelib = Path(
        subprocess.check_output(
            [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"], text=True
        ).strip()
    )
    (purelib / "_scoursph_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    _run(
        [sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "-q", str(wheel)],
        tmp,
        env,
    )
    work = tmp / "elsewhere"
    work.mkdir()
    return venv, work, env


@pytest.mark.slow
def test_installed_package_is_imported_from_the_venv_not_the_repository(installed):
    venv, work, env = installed
    out = _run(
        [venv / "bin" / "python", "-c", "import solver, verification; print(solver.__file__)"], work, env
    )
    assert str(venv) in out.stdout and str(ROOT) not in out.stdout


@pytest.mark.slow
def test_installed_package_finds_every_data_file_it_reads(installed):
    """Each reference the verification cases read, loaded from the installed package."""
    venv, work, env = installed
    code = textwrap.dedent(
        """
        from verification import column_collapse as cc, dam_break as db, soil_self_weight as ssw
        from verification.common import study_row
        assert sorted(db.openfoam_series()) == [10, 20, 40]
        assert len(db.experiment_front()[0]) > 10 and len(db.experiment_height()[0]) > 5
        assert study_row(db.STUDY_FILE, db.DEFAULT_RESOLUTION) is not None
        assert {"final_free_surface", "failure_line"} <= set(cc.load_reference())
        assert cc.liggghts_reference() is not None and study_row(cc.STUDY_FILE, 40) is not None
        assert study_row(ssw.STUDY_FILE, 20) is not None
        print("DATA OK", db.__file__)
        """
    )
    out = _run([venv / "bin" / "python", "-c", code], work, env)
    assert "DATA OK" in out.stdout and str(venv) in out.stdout


@pytest.mark.slow
def test_installed_scoursph_runs_a_shipped_scene_by_name_and_verifies(installed):
    venv, work, env = installed
    scoursph = venv / "bin" / "scoursph"
    tiny = ["--set", "scene.spacing=0.005715", "--set", "scene.end_time=0.01", "--quiet", "--threads", "1"]
    run = _run([scoursph, "run", "dam_break_2d", *tiny], work, env)
    assert (work / "runs" / "dam_break_2d" / "particles.h5").is_file(), run.stdout
    explain = _run([scoursph, "run", "column_collapse_2d", "--explain"], work, env)
    assert "soil" in explain.stdout.lower()
    verify = _run([scoursph, "verify", "hydrostatic", "--resolution", "10", "--out", "v"], work, env)
    assert "hydrostatic [PASS]" in verify.stdout and (work / "v" / "hydrostatic_r10.png").is_file()
