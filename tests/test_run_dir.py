"""A run never deletes what ScourSPH did not write (issue 13): the output directory is claimed
with a marker; a non-empty directory without it is refused (exit 2, nothing written); an
earlier run is replaced only with --overwrite, and then only the run's own files go."""

import json
import os
import subprocess

import pytest
from conftest import ENV, SCOURSPH

from solver.output import run_dir
from solver.output.run_dir import MARKER, RunDirError

TINY = ["--set", "scene.spacing=0.005715", "--set", "scene.end_time=0.02", "--quiet", "--threads", "1"]


def scoursph_run(cwd, *args):
    return subprocess.run(
        [*SCOURSPH, "run", "dam_break_2d", *TINY, *args],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=cwd,
        timeout=300,
    )


def tree(path):
    """Every file under path with its content: what must survive a refused run untouched."""
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def home_like(path):
    """A directory as a user's home or project looks: files, a hidden file, and folders named
    like the run's own (snapshots/, vtk/) holding the user's files."""
    path.mkdir(exist_ok=True)
    (path / "thesis.tex").write_text("years of work")
    (path / ".bashrc").write_text("export X=1")
    (path / "snapshots").mkdir()
    (path / "snapshots" / "000000.h5").write_text("a user's file that happens to look like a snapshot")
    (path / "vtk").mkdir()
    (path / "vtk" / "holiday.png").write_bytes(b"\x89PNG")
    (path / "run.json").write_text('{"mine": true}')
    return path


def assert_refused(proc, directory, reason):
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    line = proc.stderr.strip()
    assert len(line.splitlines()) == 1 and line.startswith("scoursph: error:"), line
    assert str(directory) in line and reason in line, line


def test_out_dot_with_the_users_files_is_refused(tmp_path):
    home_like(tmp_path)
    before = tree(tmp_path)
    proc = scoursph_run(tmp_path, "--out", ".")
    assert_refused(proc, ".", "not a ScourSPH run directory")
    assert tree(tmp_path) == before


@pytest.mark.parametrize("overwrite", [False, True])
def test_home_like_directory_is_refused_even_with_overwrite(tmp_path, overwrite):
    home = home_like(tmp_path / "home")
    before = tree(home)
    proc = scoursph_run(tmp_path, "--out", str(home), *(["--overwrite"] if overwrite else []))
    assert_refused(proc, home, "never deletes files it did not write")
    assert tree(home) == before


def test_earlier_run_is_kept_without_overwrite_and_replaced_with_it(tmp_path):
    out = tmp_path / "run"
    first = scoursph_run(tmp_path, "--out", str(out), "--set", "output.interval=0.005")
    assert first.returncode == 0, first.stderr
    marker = json.loads((out / MARKER).read_text())
    assert marker["scene"] == "dam_break_2d" and marker["solver"] == "ScourSPH"
    assert len(list((out / "snapshots").glob("*.h5"))) == 5  # t = 0, 0.005, ..., 0.02
    (out / "notes.txt").write_text("my notes on this run")
    (out / "snapshots" / "keep.txt").write_text("mine")
    before = tree(out)

    again = scoursph_run(tmp_path, "--out", str(out))
    assert_refused(again, out, "holds an earlier ScourSPH run")
    assert "--overwrite" in again.stderr
    assert tree(out) == before

    replaced = scoursph_run(tmp_path, "--out", str(out), "--overwrite")  # interval 0.01: 3 snapshots
    assert replaced.returncode == 0, replaced.stderr
    assert sorted(p.name for p in (out / "snapshots").glob("*.h5")) == ["000000.h5", "000001.h5", "000002.h5"]
    assert len(list((out / "vtk").glob("*.vtp"))) == 3  # the first run's 000003-4 are gone
    assert (out / "notes.txt").read_text() == "my notes on this run"
    assert (out / "snapshots" / "keep.txt").read_text() == "mine"


def test_refusal_comes_before_any_work_and_writes_nothing(tmp_path):
    (tmp_path / "a_file").write_text("x")
    proc = scoursph_run(tmp_path, "--out", str(tmp_path / "a_file"))
    assert_refused(proc, tmp_path / "a_file", "not a directory")
    assert sorted(os.listdir(tmp_path)) == ["a_file"]


# -- the module's API (in process) ----------------------------------------------------------
def test_claim_and_clear_touch_only_the_runs_files(tmp_path):
    out = run_dir.claim(tmp_path / "r", "demo")
    assert run_dir.read_marker(out)["scene"] == "demo"
    for name in ("particles.h5", "run.json", "scene.toml", "final.png", "particles.pvd"):
        (out / name).write_text("x")
    (out / "snapshots").mkdir()
    (out / "snapshots" / "000000.h5").write_text("x")
    (out / "snapshots" / "mine.h5").write_text("keep")
    (out / "extra").mkdir()
    (out / "extra" / "000000.vtp").write_text("keep")
    with pytest.raises(RunDirError, match="--overwrite"):
        run_dir.claim(out, "demo")
    run_dir.claim(out, "demo", mode="overwrite")
    assert tree(out).keys() == {MARKER, "snapshots/mine.h5", "extra/000000.vtp"}


def test_empty_and_missing_directories_are_claimed_and_continue_needs_a_run(tmp_path):
    (tmp_path / "empty").mkdir()
    run_dir.check(tmp_path / "empty")
    run_dir.check(tmp_path / "missing" / "deeper")
    with pytest.raises(RunDirError, match="no such run"):
        run_dir.check(tmp_path / "missing", mode="continue")
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "f").write_text("x")
    with pytest.raises(RunDirError, match="not a ScourSPH run"):
        run_dir.check(tmp_path / "other", mode="continue")
    out = run_dir.claim(tmp_path / "r", "demo")
    (out / "run.json").write_text("{}")
    run_dir.claim(out, "demo", mode="continue")  # a restart keeps the outputs
    assert (out / "run.json").exists()
