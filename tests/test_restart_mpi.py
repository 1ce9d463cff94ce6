"""Checkpoint and restart under real `mpirun` (issue 14 items 3 and 4): bit for bit on the same
rank count, within the round-off bound (tests/roundoff.py) across rank counts (2 -> 1 and
1 -> 2), and SIGTERM to the launcher or to one rank stops every rank with a checkpoint."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import roundoff
from test_restart import (
    DAM,
    DAM_SET,
    _checkpoint_state,
    _names,
    _scene_file,
    _snapshots,
    assert_same_checkpoint,
    assert_same_series,
    one_thread,  # noqa: F401 - a fixture
)

from solver.output.checkpoint import list_checkpoints
from solver.run import run_scene
from solver.scene import load_scene

pytestmark = pytest.mark.mpi

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
MPIRUN = BIN / "mpirun"
A = 0.05715
TIMEOUT = 180
# recut every 25 steps whatever the imbalance (as tests/test_mpi.py): the restart must replay
# the cuts in force, and later recuts must fall on the same steps
MPI_SET = DAM_SET + ["parallel.rebalance_every=25", "parallel.imbalance_threshold=1.0"]
# a hung rank is detected, not a speed measured (as KILLED_RANK_BOUND in tests/test_mpi.py)
STOP_BOUND = 60.0  # s

if not MPIRUN.exists():
    if os.environ.get("SCOURSPH_REQUIRE_MPI", "") == "1":
        pytest.fail(f"no mpirun at {MPIRUN}, and SCOURSPH_REQUIRE_MPI=1", pytrace=False)
    pytest.skip("no mpirun in the venv (pip install mpich)", allow_module_level=True)


def _env():
    return dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT))


def _cli(ranks, *args):
    cmd = [sys.executable, "-m", "scoursph.cli", "run", *map(str, args), "--threads", "1", "--quiet"]
    return ([str(MPIRUN), "-n", str(ranks)] if ranks > 1 else []) + cmd


def _run(ranks, *args):
    r = subprocess.run(_cli(ranks, *args), capture_output=True, text=True, env=_env(), timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr[-3000:]
    return r


def assert_within_roundoff(serial_run, other_run):
    """Every snapshot of other_run within the round-off bound of the serial run's (the bound for
    the whole run's simulated time and steps, the largest)."""
    s, o = _snapshots(serial_run), _snapshots(other_run)
    assert [(t, k) for t, k, _ in s] == [(t, k) for t, k, _ in o]  # same dt every step
    t_end, steps, last = s[-1]
    state = {"x": last["position"], "v": last["velocity"], "steps": steps}
    tol_x, tol_v, tol_rho = roundoff.roundoff_tolerances(
        state, {"t": t_end, "steps": steps}, A / 30, 1000.0, 15.0, 1000.0 * 9.81 * 2 * A, 0.01
    )
    worst = {"x": 0.0, "v": 0.0, "rho": 0.0}
    for (_, _, fs), (_, _, fo) in zip(s, o):
        np.testing.assert_array_equal(fs["id"], fo["id"])
        worst["x"] = max(worst["x"], float(np.abs(fs["position"] - fo["position"]).max()))
        worst["v"] = max(worst["v"], float(np.abs(fs["velocity"] - fo["velocity"]).max()))
        worst["rho"] = max(worst["rho"], float(np.abs(fs["density"] - fo["density"]).max()))
    print(
        f"restart across rank counts: worst |difference| {worst}, "
        f"bounds {tol_x:.3g} {tol_v:.3g} {tol_rho:.3g}"
    )
    assert worst["x"] <= tol_x and worst["v"] <= tol_v and worst["rho"] <= tol_rho, worst


def test_restart_on_two_ranks_and_across_rank_counts(tmp_path, one_thread):  # noqa: F811
    scene_path = _scene_file(tmp_path, DAM, MPI_SET)
    serial = tmp_path / "serial"
    run_scene(load_scene(scene_path), serial, quiet=True)
    two = tmp_path / "two"
    _run(2, scene_path, "--out", two)
    names = _names(two)
    assert names == _names(serial) and len(names) == 3
    with h5py.File(two / "checkpoints" / names[0], "r") as f:
        assert int(f.attrs["ranks"]) == 2 and "decomposition" in f

    # the same rank count: bit for bit, ranks included (the cuts are replayed)
    again = tmp_path / "two_again"
    shutil.copytree(two, again)
    _run(2, scene_path, "--restart", again, "--checkpoint", names[0])
    assert_same_series(two, again)
    assert_same_checkpoint(two / "checkpoints" / names[-1], again / "checkpoints" / names[-1])

    # 2 ranks -> serial, and serial -> 2 ranks: the serial run's answer to round-off
    down = tmp_path / "two_to_one"
    shutil.copytree(two, down)
    _run(1, scene_path, "--restart", down, "--checkpoint", names[0])
    assert_within_roundoff(serial, down)
    up = tmp_path / "one_to_two"
    shutil.copytree(serial, up)
    _run(2, scene_path, "--restart", up, "--checkpoint", names[0])
    assert_within_roundoff(serial, up)
    _, state = _checkpoint_state(up / "checkpoints" / names[-1])
    assert len(state["ranks"]) == 2
    segments = json.loads((up / "run.json").read_text())["segments"]
    assert [s["mpi_ranks"] for s in segments] == [1, 2]


def _rank_pids(root_pid):
    """{rank: pid} of the MPI ranks under the launcher (Linux /proc; as in tests/test_mpi.py)."""
    from test_mpi import _rank_pids as pids

    return pids(root_pid)


@pytest.mark.parametrize("target", ["mpirun", "rank 1"])
def test_sigterm_under_mpirun_stops_every_rank_with_a_checkpoint(tmp_path, target):
    """SIGTERM to the launcher (as a batch system's time limit sends it) or to one rank only:
    every rank stops after the same step, one checkpoint is written, no rank hangs (bounded
    wait). (Restarts of 2-rank checkpoints are checked above; an interrupted checkpoint is
    written like any other, and tests/test_restart.py restarts one bit for bit.)"""
    sets = MPI_SET + ["scene.end_time=0.03", "output.interval=0.01", "output.checkpoint_interval=0.002"]
    scene_path = _scene_file(tmp_path, DAM, sets)
    run = tmp_path / "run"
    proc = subprocess.Popen(
        _cli(2, scene_path, "--out", run),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
        start_new_session=True,  # the test can end the whole job if it hangs
    )
    try:
        end = time.monotonic() + TIMEOUT
        while not _names(run):
            assert proc.poll() is None, proc.communicate()[1][-3000:]
            assert time.monotonic() < end, "no checkpoint appeared"
            time.sleep(0.05)
        ranks = _rank_pids(proc.pid)
        assert sorted(ranks) == [0, 1], ranks
        os.kill(proc.pid if target == "mpirun" else ranks[1], signal.SIGTERM)
        t_signal = time.monotonic()
        try:
            _, err = proc.communicate(timeout=STOP_BOUND)
        except subprocess.TimeoutExpired:
            pytest.fail(f"job still running {STOP_BOUND} s after SIGTERM to {target}")
        elapsed = time.monotonic() - t_signal
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    print(f"SIGTERM to {target}: job ended {elapsed:.2f} s later, status {proc.returncode}")
    alive = [p for p in ranks.values() if Path(f"/proc/{p}").exists() and _not_zombie(p)]
    assert not alive, f"ranks alive after the launcher ended: {alive}"
    assert proc.returncode == 143, err[-3000:]
    newest = list_checkpoints(run)[-1]
    assert f"checkpoint written to {newest}" in err, err[-3000:]
    assert err.count("scoursph: interrupted by SIGTERM") == 1  # the root's line only
    with h5py.File(newest, "r") as f:
        assert int(f.attrs["ranks"]) == 2 and 0 < float(f.attrs["t"]) < 0.03


def _not_zombie(pid):
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
