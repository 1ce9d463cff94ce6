"""Checkpoint and restart, interruption (issue 14 items 3 and 4).

A restart reproduces the uninterrupted run bit for bit: every snapshot and every later
checkpoint (the whole state) are compared with np.array_equal, not to a tolerance. The serial
runs are in-process with one Numba thread (the subprocesses use --threads 1: the same compiled
kernels, the same sums); the MPI ones are in tests/test_restart_mpi.py.
"""

from __future__ import annotations

import json
import os
import select
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numba
import numpy as np
import pytest

from scoursph.cli import main
from solver.output.checkpoint import PAUSE_ENV, list_checkpoints
from solver.run import run_scene
from solver.scene import load_scene, scene_to_toml

ROOT = Path(__file__).resolve().parents[1]
DAM = ROOT / "scenes" / "dam_break_2d.toml"
COLUMN = ROOT / "scenes" / "column_collapse_2d.toml"
A = 0.05715
# a/30 (1,800 particles), about 290 steps to 0.012 s with two or three neighbour rebuilds;
# checkpoints every 0.005 s fall between the outputs (every 0.004 s), so a restart starts
# from a step that is not an output time
DAM_SET = [
    f"scene.spacing={A / 30!r}",
    "scene.end_time=0.012",
    "output.interval=0.004",
    "output.checkpoint_interval=0.005",
    "output.vtk=true",
    "output.render=false",
]
# the soil column at 5 mm (800 particles): stresses, plastic strain, no-slip floor images
COLUMN_SET = [
    "scene.spacing=0.005",
    "scene.end_time=0.02",
    "output.interval=0.008",
    "output.checkpoint_interval=0.007",
    "output.render=false",
]


@pytest.fixture
def one_thread():
    """One Numba thread, as the subprocesses run with --threads 1."""
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    yield
    numba.set_num_threads(before)


def _scene_file(tmp, base, sets, name=None):
    """The merged scene with the overrides, written as a scene file (a restart names the same file)."""
    path = tmp / (name or f"{base.stem}_test.toml")
    path.write_text(scene_to_toml(load_scene(base, sets)))
    return path


def _snapshots(run):
    """[(time, step, {field: array})] of a run directory's series, in order."""
    out = []
    with h5py.File(run / "particles.h5", "r") as f:
        times, steps = f["times"][:], f["steps"][:]
    for k, (t, s) in enumerate(zip(times, steps)):
        with h5py.File(run / "snapshots" / f"{k:06d}.h5", "r") as f:
            out.append((float(t), int(s), {name: f[name][:] for name in f}))
    return out


def _checkpoint_state(path):
    with h5py.File(path, "r") as f:
        particles = {name: f["particles"][name][:] for name in f["particles"]}
        state = json.loads(f["meta/state"][()])
    return particles, state


def assert_same_series(a, b):
    sa, sb = _snapshots(a), _snapshots(b)
    assert [(t, s) for t, s, _ in sa] == [(t, s) for t, s, _ in sb]
    for (t, _, fa), (_, _, fb) in zip(sa, sb):
        assert fa.keys() == fb.keys()
        for name in fa:
            assert np.array_equal(fa[name], fb[name]), f"{name} differs at t = {t}"


def assert_same_checkpoint(pa, pb):
    """The whole state: every particle field and the step loop's scalars, bit for bit."""
    xa, sa = _checkpoint_state(pa)
    xb, sb = _checkpoint_state(pb)
    assert xa.keys() == xb.keys()
    for name in xa:
        assert np.array_equal(xa[name], xb[name]), f"checkpoint field {name} differs"
    assert sa["shared"] == sb["shared"]
    assert sa["terms"] == sb["terms"]
    assert sa["run"]["outputs"] == sb["run"]["outputs"]


def _names(run):
    return [p.name for p in list_checkpoints(run)]


def test_restart_from_a_mid_run_checkpoint_is_bit_for_bit(tmp_path, one_thread):
    """Continue a copy of a completed run from its checkpoint between two outputs: the same
    snapshots (values, times, step numbers), the same later checkpoint, the series continued."""
    scene_path = _scene_file(tmp_path, DAM, DAM_SET)
    scene = load_scene(scene_path)
    ref = tmp_path / "ref"
    result = run_scene(scene, ref, quiet=True)
    assert result.sim.rebuilds >= 3  # the restart replays a rebuild and makes later ones
    names = _names(ref)
    assert len(names) == 3  # 0.005, 0.010 and the end (checkpoint_at_end)
    copy = tmp_path / "copy"
    shutil.copytree(ref, copy)
    first = copy / "checkpoints" / names[0]  # the snapshots after it are cut back and written again
    status = main(["run", str(scene_path), "--restart", str(copy), "--checkpoint", names[0], "--quiet"])
    assert status == 0
    assert_same_series(ref, copy)
    assert _names(copy) == names
    assert_same_checkpoint(ref / "checkpoints" / names[1], copy / "checkpoints" / names[1])
    assert_same_checkpoint(ref / "checkpoints" / names[2], copy / "checkpoints" / names[2])
    assert first.exists()
    run = json.loads((copy / "run.json").read_text())
    assert run["status"] == "completed"
    assert [s["from_checkpoint"] for s in run["segments"]] == [None, f"checkpoints/{names[0]}"]
    assert run["steps"] == json.loads((ref / "run.json").read_text())["steps"]
    pvd = (copy / "particles.pvd").read_text()
    assert pvd == (ref / "particles.pvd").read_text()


def test_soil_restart_is_bit_for_bit(tmp_path, one_thread):
    """The soil column: stresses, plastic strain and no-slip images come back exactly."""
    scene_path = _scene_file(tmp_path, COLUMN, COLUMN_SET)
    scene = load_scene(scene_path)
    ref = tmp_path / "ref"
    run_scene(scene, ref, quiet=True)
    names = _names(ref)
    with h5py.File(ref / "checkpoints" / names[0], "r") as f:
        fields = set(f["particles"])
    assert {"stress_dev", "mean_stress", "x_ref", "v_half"} <= fields
    copy = tmp_path / "copy"
    shutil.copytree(ref, copy)
    assert main(["run", str(scene_path), "--restart", str(copy), "--checkpoint", names[0], "--quiet"]) == 0
    assert_same_series(ref, copy)
    assert_same_checkpoint(ref / "checkpoints" / names[-1], copy / "checkpoints" / names[-1])


def test_restart_from_any_step_is_bit_for_bit(tmp_path, one_thread):
    """A signal can stop a run after any step, so a checkpoint written after any step must resume
    exactly: a run with a checkpoint after every step (past two neighbour rebuilds and an output
    time), resumed from every 25th of them (6 restarts spread over the run; every 12th cost twice the
    time in CI), each time reproduces the uninterrupted series."""
    sets = DAM_SET + [
        "scene.end_time=0.006",
        "output.checkpoint_interval=1e-9",
        "output.checkpoint_keep=1000",
    ]
    scene_path = _scene_file(tmp_path, DAM, sets)
    ref = tmp_path / "ref"
    result = run_scene(load_scene(scene_path), ref, quiet=True)
    assert result.sim.rebuilds >= 2
    names = _names(ref)
    assert len(names) == result.sim.step_count  # one after every step
    for name in names[::25]:
        copy = tmp_path / "copy"
        shutil.rmtree(copy, ignore_errors=True)
        shutil.copytree(ref, copy, ignore=shutil.ignore_patterns("checkpoints"))
        (copy / "checkpoints").mkdir()
        shutil.copy(ref / "checkpoints" / name, copy / "checkpoints" / name)
        run_scene(load_scene(scene_path), None, quiet=True, restart=copy, checkpoint=name)
        assert_same_series(ref, copy)


def test_a_completed_run_is_extended_with_a_later_end_time(tmp_path, one_thread):
    scene_path = _scene_file(tmp_path, DAM, DAM_SET + ["output.checkpoint_interval=0"])
    ref = tmp_path / "run"
    run_scene(load_scene(scene_path), ref, quiet=True)
    (end,) = _names(ref)  # only the one at the end
    longer = _scene_file(
        tmp_path, DAM, DAM_SET + ["output.checkpoint_interval=0", "scene.end_time=0.016"], "longer.toml"
    )
    assert main(["run", str(longer), "--restart", str(ref), "--quiet"]) == 0
    series = _snapshots(ref)
    assert [round(t, 9) for t, _, _ in series] == [0.0, 0.004, 0.008, 0.012, 0.016]
    assert _names(ref)[0] == end and len(_names(ref)) == 2


# -- the term interface -----------------------------------------------------------------------------
def test_term_state_is_checkpointed_and_restored(tmp_path, one_thread, monkeypatch):
    """A term that carries state between steps (an inlet's counters, issue 11) gets it back."""
    from solver import plan as plan_module
    from solver.term import Stage, Term

    class StepCounter(Term):
        name = "step counter (test)"
        stage = Stage.AFTER_DRIFT

        @classmethod
        def build(cls, scene, materials):
            return cls()

        def __init__(self):
            super().__init__()
            self.count, self.total = 0, 0.0

        def run(self, ctx):
            self.count += 1
            self.total += ctx.dt / 3.0  # not a round number: restored exactly

        def state(self):
            return {"count": self.count, "total": self.total}

        def restore(self, state):
            self.count, self.total = int(state["count"]), float(state["total"])

    monkeypatch.setattr(plan_module, "TERMS", plan_module.TERMS + (StepCounter,))
    scene_path = _scene_file(tmp_path, DAM, DAM_SET)
    ref = tmp_path / "ref"
    whole = run_scene(load_scene(scene_path), ref, quiet=True).sim.plan.term(StepCounter)
    copy = tmp_path / "copy"
    shutil.copytree(ref, copy)
    resumed = run_scene(load_scene(scene_path), None, quiet=True, restart=copy, checkpoint=_names(ref)[0])
    counter = resumed.sim.plan.term(StepCounter)
    assert (counter.count, counter.total) == (whole.count, whole.total)
    _, state = _checkpoint_state(ref / "checkpoints" / _names(ref)[0])
    assert state["terms"][0]["step counter (test)"]["count"] == state["shared"]["step_count"]


def test_per_rank_term_state_must_say_how_to_regroup():
    from solver.term import Term

    t = Term()
    assert t.regroup_state([{"n": 1}, {"n": 1}], 3) == [{"n": 1}] * 3
    with pytest.raises(ValueError, match="regroup"):
        t.regroup_state([{"n": 1}, {"n": 2}], 1)


# -- bad --restart input: exit 2, naming the problem ------------------------------------------------
@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("small")
    scene_path = _scene_file(tmp, DAM, DAM_SET[:1] + ["scene.end_time=0.002", "output.interval=0.001"])
    run = tmp / "run"
    run_scene(load_scene(scene_path), run, quiet=True)
    return scene_path, run


@pytest.mark.parametrize(
    "case, expected",
    [
        ("missing", "no such run directory"),
        ("not_a_run", "is not a ScourSPH run directory"),
        ("no_checkpoint", "holds no checkpoint"),
        ("unknown_name", "no such checkpoint (--checkpoint 77"),
        ("damaged", "none of its checkpoints is readable"),
        ("other_scene", "the scene differs from the checkpoint's at materials.water.viscosity"),
        ("end_before", "scene.end_time = 0.001 s is before the checkpoint's t = 0.002 s"),
        ("with_out", "--restart continues in the run's own directory"),
        ("checkpoint_alone", "--checkpoint 1: it names a checkpoint of --restart RUN_DIR"),
    ],
)
def test_bad_restart_input_exits_2_naming_the_problem(small_run, tmp_path, capsys, case, expected):
    scene_path, run = small_run
    target = tmp_path / "copy"
    shutil.copytree(run, target)
    args = ["run", str(scene_path), "--restart", str(target), "--quiet"]
    if case == "missing":
        args[3] = str(tmp_path / "nowhere")
    elif case == "not_a_run":
        (tmp_path / "plain").mkdir()
        args[3] = str(tmp_path / "plain")
    elif case == "no_checkpoint":
        shutil.rmtree(target / "checkpoints")
    elif case == "unknown_name":
        args += ["--checkpoint", "77"]
    elif case == "damaged":
        for p in list_checkpoints(target):
            p.write_bytes(b"not HDF5")
    elif case == "other_scene":
        args += ["--set", "materials.water.viscosity=2e-3"]
    elif case == "end_before":
        args += ["--set", "scene.end_time=0.001"]
    elif case == "with_out":
        args += ["--out", str(tmp_path / "elsewhere")]
    elif case == "checkpoint_alone":
        args = ["run", str(scene_path), "--checkpoint", "1", "--quiet"]
    before = sorted(p.relative_to(target) for p in target.rglob("*"))
    assert main(args) == 2
    err = capsys.readouterr().err
    assert err.startswith("scoursph: error:") and expected in err, err
    assert len(err.strip().splitlines()) == 1
    assert sorted(p.relative_to(target) for p in target.rglob("*")) == before  # nothing written


def test_unreadable_newest_checkpoint_falls_back_with_a_warning(small_run, tmp_path, capsys):
    scene_path, run = small_run
    target = tmp_path / "copy"
    shutil.copytree(run, target)
    (target / "checkpoints" / "000999999.h5").write_bytes(b"\0" * 100)  # e.g. a disk error
    assert main(["run", str(scene_path), "--restart", str(target), "--quiet"]) == 0
    assert "skipped unreadable checkpoint" in capsys.readouterr().err


# -- real signals, in subprocesses --------------------------------------------------------------------
def _env(**extra):
    return dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT), **extra)


def _cli(*args):
    return [sys.executable, "-m", "scoursph.cli", "run", *map(str, args), "--threads", "1", "--quiet"]


def _wait_for_line(proc, text, timeout):
    """Read the process's standard error until a line contains `text`; the lines read."""
    lines, end = [], time.monotonic() + timeout
    while time.monotonic() < end:
        ready, _, _ = select.select([proc.stderr], [], [], 0.5)
        if ready:
            line = proc.stderr.readline()
            if not line:
                break
            lines.append(line)
            if text in line:
                return lines
    raise AssertionError(f"no line with {text!r} within {timeout} s: {''.join(lines)[-2000:]}")


def _reference_run(scene_path, out):
    """The uninterrupted run, in a subprocess like the interrupted and the resumed one: the three
    then share one environment. (An in-process reference differed from the subprocesses in the
    last bits inside the whole suite, though not alone; the cause, some state an earlier test
    leaves in the pytest process, was not found.)"""
    r = subprocess.run(
        _cli(scene_path, "--out", out), capture_output=True, text=True, env=_env(), timeout=300
    )
    assert r.returncode == 0, r.stderr[-3000:]


def test_sigkill_while_writing_a_checkpoint_restarts_from_the_previous_one(tmp_path, one_thread):
    """SIGKILL while the second checkpoint is being written (held open by a test hook after its
    data, before its rename): the first stays whole, the restart continues from it and ends
    as the uninterrupted run."""
    scene_path = _scene_file(tmp_path, DAM, DAM_SET)
    ref = tmp_path / "ref"
    _reference_run(scene_path, ref)
    run = tmp_path / "run"
    proc = subprocess.Popen(
        _cli(scene_path, "--out", run),
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=_env(**{PAUSE_ENV: "2:120"}),
    )
    try:
        _wait_for_line(proc, "paused inside checkpoint write 2", timeout=90)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == -signal.SIGKILL
    folder = run / "checkpoints"
    partial = [p.name for p in folder.iterdir() if ".partial" in p.name]
    assert len(partial) == 1 and _names(run) == _names(ref)[:1]
    r = subprocess.run(
        _cli(scene_path, "--restart", run), capture_output=True, text=True, env=_env(), timeout=120
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert not [p for p in folder.iterdir() if ".partial" in p.name]
    assert_same_series(ref, run)
    assert_same_checkpoint(ref / "checkpoints" / _names(ref)[-1], folder / _names(ref)[-1])


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_signal_writes_a_checkpoint_and_the_restart_matches(tmp_path, one_thread, sig):
    """SIGTERM / SIGINT at an arbitrary step: a checkpoint at the end of that step, one clear line,
    exit status 128 + the signal; the restart ends as the uninterrupted run, bit for bit (SIGTERM;
    the SIGINT case stops the same way and is not restarted, to save the test's time)."""
    sets = DAM_SET + ["scene.end_time=0.03", "output.interval=0.01", "output.checkpoint_interval=0.002"]
    scene_path = _scene_file(tmp_path, DAM, sets)
    run = tmp_path / "run"
    proc = subprocess.Popen(
        _cli(scene_path, "--out", run),
        stderr=subprocess.PIPE,
        stdout=subprocess.DEVNULL,
        text=True,
        env=_env(),
    )
    try:
        end = time.monotonic() + 90
        while not _names(run) and time.monotonic() < end and proc.poll() is None:
            time.sleep(0.05)
        assert _names(run), "no checkpoint appeared"
        proc.send_signal(sig)
        t_signal = time.monotonic()
        _, err = proc.communicate(timeout=60)
        print(f"{signal.Signals(sig).name}: stopped {time.monotonic() - t_signal:.2f} s after the signal")
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 128 + sig, err[-3000:]
    name = signal.Signals(sig).name
    assert f"scoursph: {name} received: writing a checkpoint" in err
    last = err.strip().splitlines()[-1]
    newest = list_checkpoints(run)[-1]
    assert last.startswith(f"scoursph: interrupted by {name} at t = ")
    assert f"checkpoint written to {newest}" in last and f"--restart {run}" in last
    status = json.loads((run / "run.json").read_text())["status"]
    assert status.startswith(f"interrupted by {name}")
    with h5py.File(newest, "r") as f:
        t_stop = float(f.attrs["t"])
    assert 0 < t_stop < 0.03
    if sig != signal.SIGTERM:
        return
    ref = tmp_path / "ref"
    _reference_run(scene_path, ref)
    r = subprocess.run(
        _cli(scene_path, "--restart", run), capture_output=True, text=True, env=_env(), timeout=120
    )
    assert r.returncode == 0, r.stderr[-3000:]
    assert_same_series(ref, run)
    assert_same_checkpoint(ref / "checkpoints" / _names(ref)[-1], run / "checkpoints" / _names(ref)[-1])
