"""The side-by-side verdicts of the 2-rank MPI step and the cold compile (benchmarks/reference_mpi.py,
benchmarks/reference_compile.py, gate.py): timing doubles for the logic (which figure a bout gives,
the median over rounds and pairs, the order and core of each pair, cold minus warm, the slowdown
only in the current build, the per-benchmark verdict and thresholds), and real children for the
failure paths and for the MPI jobs' pinning (both ranks report the core they ran on)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import gate  # noqa: E402
import reference_build  # noqa: E402
import reference_compile  # noqa: E402
import reference_mpi  # noqa: E402
from reference_mpi import Bout  # noqa: E402

MPIRUN = Path(sys.executable).parent / "mpirun"


def test_a_bout_is_the_busiest_ranks_cpu_time_outside_communication():
    b = Bout(wall=0.010, cpu=[0.004, 0.005], comm_cpu=[0.001, 0.0035])
    assert b.estimate("compute") == pytest.approx(0.003)  # rank 0: 4 - 1 ms; rank 1: 5 - 3.5 ms
    assert b.estimate("cpu") == pytest.approx(0.009) and b.estimate("wall") == 0.010


def test_mpi_ratio_is_the_median_over_job_pairs_of_their_rounds(monkeypatch):
    """One disturbed bout or one job pair reading off for its whole life does not move it."""

    def bouts(current, baseline):
        return [(Bout(1.0, [baseline, baseline], [0.0, 0.0]), Bout(1.0, [c, c], [0.0, 0.0])) for c in current]

    runs = iter(
        [
            (bouts([1.1, 1.1, 3.0], 1.0), {}),  # a bout of the current build preempted
            (bouts([1.1, 1.1, 1.1], 1.0), {}),
            (bouts([0.9, 0.9, 0.9], 1.0), {}),  # a job pair 10 % off
        ]
    )
    monkeypatch.setattr(reference_mpi, "alternating_bouts", lambda *a, **k: next(runs))
    m = reference_mpi.measurement(ROOT, ROOT, pairs=3)
    assert m["ratio"] == pytest.approx(1.1) and m["pair_ratios"][2] == pytest.approx(0.9)
    assert set(m["by_estimator"]) == set(reference_mpi.ESTIMATORS)


class _Rank:
    """A rank's socket file that answers every `go` with a fixed line."""

    def __init__(self, answer):
        self.answer, self.sent = answer, []

    def write(self, text):
        self.sent.append(text)

    def flush(self):
        pass

    def readline(self):
        return self.answer


def _job(answers, cores=(0, 1)):
    job = object.__new__(reference_mpi.Job)
    job.root, job.tag, job.cores = ROOT, "current", list(cores)
    job.ranks = [_Rank(a) for a in answers]
    return job


def test_a_bout_sends_go_to_both_ranks_and_reads_their_times():
    job = _job(["0.012 0.005 0.001 0\n", "0.011 0.006 0.002 1\n"])
    b = job.bout(4)
    assert [r.sent for r in job.ranks] == [["go 4\n"], ["go 4\n"]]
    assert b == Bout(0.012, [0.005, 0.006], [0.001, 0.002])


def test_a_rank_off_its_core_stops_the_measurement():
    job = _job(["0.012 0.005 0.001 1\n", "0.011 0.006 0.002 1\n"])
    with pytest.raises(RuntimeError, match=r"ranks ran on cores \[1, 1\], pinned to \[0, 1\]"):
        job.bout(4)


def test_mpi_side_by_side_needs_two_cores(monkeypatch):
    monkeypatch.setattr(reference_mpi.os, "sched_getaffinity", lambda pid: {0})
    with pytest.raises(RuntimeError, match="needs 2 cores"):
        reference_mpi.cores()


def test_compile_pairs_alternate_the_order_on_each_core(monkeypatch):
    calls = []

    def pair(reference, current, cpu, baseline_first, slowdown, mode):
        calls.append((cpu, baseline_first))
        return (10.0, 10.0 * {0: 1.02, 1: 0.99}[cpu])

    monkeypatch.setattr(reference_compile, "pair", pair)
    monkeypatch.setattr(reference_compile, "byte_compile", lambda *trees: None)
    monkeypatch.setattr(reference_compile.os, "sched_getaffinity", lambda pid: {0, 1})
    m = reference_compile.measurement(ROOT, ROOT, pairs=5, streams=2)
    assert sorted(calls) == [(0, False), (0, True), (0, True), (1, False), (1, True)]
    assert m["ratio"] == pytest.approx(1.02) and len(m["pair_ratios"]) == 5


def test_a_compile_pair_is_cold_minus_warm_of_both_builds_on_one_core(monkeypatch):
    """Both cold starts at once, then both warm starts with the same caches; each build its own
    cache; the slowdown only in the current build, as CPU time (the core is shared)."""
    started, seen = [], set()

    def start(n, cache, root, cpu, env, cpu_spin=False):
        phase = "warm" if cache in seen else "cold"
        started.append((phase, str(root), cache, cpu, env.get("SCOURSPH_BENCH_SLOWDOWN"), cpu_spin))
        return (phase, str(root))

    def result_of_all(procs):
        seen.update(c for _, _, c, _, _, _ in started)
        cpu = {("cold", "ref"): 20.0, ("cold", "new"): 23.0, ("warm", "ref"): 1.0, ("warm", "new"): 1.0}
        return [cpu[p] for p in procs]

    monkeypatch.setattr(reference_compile, "start", start)
    monkeypatch.setattr(reference_compile, "_cpu", result_of_all)
    r, n = reference_compile.pair("ref", "new", 1, baseline_first=False, slowdown=0.1)
    assert (r, n) == (19.0, 22.0)
    assert [(p, root) for p, root, *_ in started] == [
        ("cold", "new"),
        ("cold", "ref"),
        ("warm", "new"),
        ("warm", "ref"),
    ]
    assert {cpu for *_, cpu, _, _ in started} == {1}
    caches = {root: {c for _, rt, c, *_ in started if rt == root} for root in ("ref", "new")}
    assert len(caches["ref"]) == len(caches["new"]) == 1 and caches["ref"] != caches["new"]
    assert {root: slow for _, root, _, _, slow, _ in started} == {"new": "0.1", "ref": None}
    assert all(spin for *_, spin in started)


def _gate_run(monkeypatch, reference_ratios):
    """A gate run where the MPI step and the cold compile are past their calibration gates, and the
    side-by-side measurement gives `reference_ratios`; the pairs each measurement was asked for."""
    info = {
        "what": "w",
        "value": 1.5,
        "unit": "s",
        "rounds": {"wall": [1.5], "cal_wall": [1.0], "cpu": [1.5], "cal_cpu": [1.0]},
    }
    run = {"found": {"mpi_two_rank_step": info, "cold_compile": info}, "missing": {}}
    monkeypatch.setattr(
        gate,
        "run_suite",
        lambda slowdown=None, select=None: {**run, "wall_s": 1.0, "output": "", "returncode": 0},
    )
    monkeypatch.setattr(reference_build, "reference_tree", lambda commit: ROOT)
    asked = {}

    def measurement(name, tree, slowdown=None, pairs=None):
        asked[name] = pairs
        return {"ratio": reference_ratios[name], "pair_ratios": [reference_ratios[name]]}

    monkeypatch.setattr(reference_build, "measurement", measurement)
    base = {
        "benchmarks": {n: {"wall": {"median": 1.0, "threshold": 0.2}} for n in run["found"]},
        "reference_build": {
            "commit": "0" * 40,
            "pairs": 3,
            "benchmarks": {
                "mpi_two_rank_step": {"threshold": 0.04, "pairs": 3},
                "cold_compile": {"threshold": 0.03, "pairs": 4},
            },
        },
    }
    s, _ = gate.gated_run(base, ROOT / "benchmarks" / "baselines" / "gate.json", estimator="wall")
    return {r["name"]: r for r in s["benchmarks"]}, s, asked


def test_the_baseline_build_side_by_side_decides_the_mpi_step_and_the_cold_compile(monkeypatch):
    rows, s, asked = _gate_run(monkeypatch, {"mpi_two_rank_step": 1.01, "cold_compile": 1.05})
    assert asked == {"mpi_two_rank_step": 3, "cold_compile": 4}  # each with its own pairs
    assert rows["mpi_two_rank_step"]["calibration_regressed"] and not rows["mpi_two_rank_step"]["regressed"]
    assert rows["cold_compile"]["regressed"] and s["regressed"] == ["cold_compile"]
    assert rows["cold_compile"]["reference_build"]["threshold"] == 0.03


def test_reference_baseline_of_one_benchmark_keeps_the_others(monkeypatch, tmp_path):
    path = tmp_path / "gate.json"
    stored = {"commit": "a" * 40, "reference_build": {"commit": "a" * 40, "pairs": 3, "benchmarks": {}}}
    stored["reference_build"]["benchmarks"]["water_step"] = {"threshold": 0.022}
    path.write_text(json.dumps(stored))
    monkeypatch.setattr(reference_build, "reference_tree", lambda commit: ROOT)
    ratios = iter([1.0, 1.004, 0.996, 1.002, 0.998])
    monkeypatch.setattr(
        reference_build,
        "measurement",
        lambda name, tree, current=None: {
            "ratio": next(ratios),
            "pair_ratios": [1.0],
            "by_estimator": {"wall": 1.0},
        },
    )
    argv = ["reference-baseline", "--baseline", str(path), "-k", "mpi_two", "--runs", "5", "--commit", "HEAD"]
    assert gate.main(argv) == 0
    ref = json.loads(path.read_text())["reference_build"]
    assert ref["benchmarks"]["water_step"] == {"threshold": 0.022}
    mpi = ref["benchmarks"]["mpi_two_rank_step"]
    assert mpi["pairs"] == reference_mpi.PAIRS and mpi["threshold"] == 0.02  # the floor: spread 0.3 %
    assert len(mpi["ratios"]) == 5 and mpi["by_estimator"]["wall"] == [1.0] * 5
    assert len(ref["commit"]) == 40 and ref["commit"] != "a" * 40


def test_a_cold_start_that_fails_says_which_tree_and_why(tmp_path):
    with pytest.raises(RuntimeError, match=r"cold start in .* failed: .*No module named"):
        reference_compile.result(reference_compile.start(100, tmp_path, root=tmp_path))


@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason="no mpirun in the venv (pip install mpich)")
def test_an_mpi_job_that_cannot_start_says_which_and_why(tmp_path, monkeypatch):
    monkeypatch.setattr(reference_mpi, "TIMEOUT", 60)
    with pytest.raises(RuntimeError, match=r"MPI benchmark in .* did not start: .*No module named"):
        reference_mpi.alternating_bouts(tmp_path, ROOT, rounds=1, bout=1)


@pytest.mark.mpi
@pytest.mark.skipif(not MPIRUN.exists(), reason="no mpirun in the venv (pip install mpich)")
def test_two_real_mpi_jobs_take_turns_on_their_pinned_cores(monkeypatch):
    """Two real 2-rank jobs of this tree, 3 bouts each: every bout answers, every rank ran on its
    pinned core (Job.bout checks /proc/self/stat's core), and the idle job slept between turns."""
    if len(reference_mpi.os.sched_getaffinity(0)) < 2:
        pytest.skip("needs 2 cores")
    monkeypatch.setattr(reference_mpi, "PARTICLES", 2_000)
    times, idle = reference_mpi.alternating_bouts(ROOT, ROOT, rounds=3, bout=1)
    assert len(times) == 3 and all(r.wall > 0 and n.wall > 0 for r, n in times)
    assert all(len(r.cpu) == 2 for r, _ in times)
    assert set(idle) == {"baseline", "current"} and all(c < 1.0 for v in idle.values() for c in v)
