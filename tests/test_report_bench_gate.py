"""The benchmark gate's logic (benchmarks/gate.py), without timing anything: every gate
benchmark is known to the gate, a ratio past the threshold is a regression and one within is
not, a skipped placeholder is not, a benchmark that failed to run is, and the controlled
slowdown makes a call at least its fraction longer (a lower bound of a busy wait, which no
load can break)."""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))

import gate  # noqa: E402
import slowdown  # noqa: E402


def test_gate_lists_every_benchmark_of_bench_gate():
    names = re.findall(r"^def test_(\w+)\(", (ROOT / "benchmarks" / "bench_gate.py").read_text(), re.M)
    assert tuple(names) == gate.GATE


def _run(ratio, ratio_cpu=None):
    """A run whose water step takes `ratio` (wall) and `ratio_cpu` (CPU) calibrations every round."""
    rounds = {
        "wall": [ratio] * 5,
        "cal_wall": [1.0] * 5,
        "cpu": [ratio_cpu or ratio] * 5,
        "cal_cpu": [1.0] * 5,
    }
    info = {"what": "w", "value": ratio, "value_cpu": ratio_cpu, "unit": "s", "rounds": rounds}
    missing = {
        "two_phase_step": "skipped: not built yet",
        "soil_step": "failed: see the output",
    }
    return {"found": {"water_step": info}, "missing": missing}


BASE = {
    "benchmarks": {
        "water_step": {
            "wall": {"median": 1.0, "threshold": 0.05},
            "cpu_paired": {"median": 2.0, "threshold": 0.05},
        }
    }
}


def test_ratio_past_threshold_is_a_regression():
    rows = {r["name"]: r for r in gate.compare(_run(1.06), BASE, "wall")}
    assert rows["water_step"]["regressed"] and abs(rows["water_step"]["change"] - 0.06) < 1e-12
    rows = {r["name"]: r for r in gate.compare(_run(1.04), BASE, "wall")}
    assert not rows["water_step"]["regressed"]
    assert not rows["two_phase_step"]["regressed"] and "not built yet" in rows["two_phase_step"]["skipped"]
    assert rows["soil_step"]["regressed"] and rows["soil_step"]["error"]


def test_cpu_clock_uses_cpu_ratio():
    rows = {r["name"]: r for r in gate.compare(_run(1.0, 2.2), BASE, "cpu_paired")}
    assert rows["water_step"]["regressed"]  # 2.2 / 2.0 = +10 % > 5 %


def test_no_baseline_gates_nothing():
    rows = {r["name"]: r for r in gate.compare(_run(5.0), None, "wall")}
    assert not rows["water_step"]["regressed"]


def test_estimators_of_interleaved_rounds():
    info = {
        "value": 2.0,
        "rounds": {
            "wall": [2.0, 4.0, 3.0],
            "cal_wall": [1.0, 2.0, 1.0],
            "cpu": [1.0, 1.0, 1.0],
            "cal_cpu": [1.0, 1.0, 1.0],
        },
    }
    r = gate.ratios(info)
    assert r["wall"] == 3.0 / 1.0 and r["wall_min"] == 2.0 and r["wall_paired"] == 2.0 and r["cpu"] == 1.0
    assert set(gate.ratios({"value": 390.0, "rounds": {"wall": [390.0]}}).values()) == {390.0}  # a size


def test_spread_is_robust_to_one_slow_run():
    sp = gate.spread([1.0, 1.01, 0.99, 1.0, 1.3])  # one run in a slow phase of the host
    assert sp["median"] == 1.0 and abs(sp["max_dev_rel"] - 0.3) < 1e-12
    assert sp["mad_rel"] < 0.02 < sp["std_rel"]


def test_controlled_slowdown_lengthens_a_call_by_at_least_its_fraction():
    t0, c0 = time.perf_counter(), time.process_time()
    while time.perf_counter() - t0 < 0.02:
        pass
    total = slowdown.spin_after(t0, c0, 0.10)
    assert total >= 0.022


def test_a_flag_is_confirmed_by_re_measuring(monkeypatch):
    """A benchmark past its threshold is measured again (alone); a transient slow run passes on
    the retry, a real slowdown stays past the threshold in every attempt."""
    for first, later, flagged, attempts in ((1.2, 1.01, False, 2), (1.2, 1.15, True, 1 + gate.RETRIES)):
        calls = iter([_run(first)] * gate.PROCESSES + [_run(later)] * gate.RETRIES)
        monkeypatch.setattr(
            gate,
            "run_suite",
            lambda slowdown=None, select=None, c=calls: {
                **next(c),
                "wall_s": 1.0,
                "output": "",
                "returncode": 0,
            },
        )
        s, _ = gate.gated_run(BASE, ROOT / "benchmarks" / "baselines" / "gate.json", estimator="wall")
        row = next(r for r in s["benchmarks"] if r["name"] == "water_step")
        assert row["regressed"] is flagged and row["attempts"] == attempts


def test_a_measurement_keeps_the_faster_process(monkeypatch):
    """One measurement is the lowest ratio of PROCESSES processes (by DEFAULT_ESTIMATOR): a process
    caught in one of the host's slow phases does not count unless every process was; a benchmark
    that failed in any process stays missing."""
    runs = iter([_run(1.3), _run(1.02)] + [_run(1.0)] * (gate.PROCESSES - 2))
    monkeypatch.setattr(
        gate,
        "run_suite",
        lambda slowdown=None, select=None: {**next(runs), "wall_s": 1.0, "output": "", "returncode": 0},
    )
    m = gate.measure(processes=2)
    assert gate.ratio_of(m["found"]["water_step"], gate.DEFAULT_ESTIMATOR) == 1.02
    assert m["missing"]["soil_step"].startswith("failed") and m["wall_s"] == 2.0


def test_leave_one_out_judges_each_unchanged_run_by_the_others():
    """Nine runs within 1 % and one 10 % slower: only that one is flagged by the others' baseline
    (MAD-based spread 0.74 % -> threshold 3.0 %)."""
    ratios = [1.0, 1.01, 0.99, 1.005, 0.995, 1.0, 1.01, 0.99, 1.0, 1.1]
    result = gate.leave_one_out([_run(r) for r in ratios], "wall")
    assert [k for k, _, flagged in result if flagged] == [9]
    assert abs(result[9][1]["water_step"] - 0.1) < 1e-12


import reference_build  # noqa: E402

REF_BASE = {
    **BASE,
    "reference_build": {"commit": "0" * 40, "pairs": 3, "benchmarks": {"water_step": {"threshold": 0.05}}},
}


def _gate_with_side_by_side(monkeypatch, calibration_ratio, reference_ratio):
    """A gate run whose water step has `calibration_ratio` against the calibration kernel and
    `reference_ratio` against the baseline commit's build timed side by side."""
    monkeypatch.setattr(
        gate,
        "run_suite",
        lambda slowdown=None, select=None: {
            **_run(calibration_ratio),
            "wall_s": 1.0,
            "output": "",
            "returncode": 0,
        },
    )
    monkeypatch.setattr(reference_build, "reference_tree", lambda commit: ROOT)
    monkeypatch.setattr(
        reference_build,
        "measurement",
        lambda name, tree, slowdown=None, pairs=3: {
            "ratio": reference_ratio,
            "pair_ratios": [reference_ratio],
        },
    )
    s, _ = gate.gated_run(REF_BASE, ROOT / "benchmarks" / "baselines" / "gate.json", estimator="wall")
    return s, next(r for r in s["benchmarks"] if r["name"] == "water_step")


def test_the_baseline_build_side_by_side_decides_a_step_benchmark(monkeypatch):
    """A slow phase of the host moves the calibration ratio (+20 %) but not the step against the
    baseline commit's own build (+1 %): not a regression, and no retries; a real 10 % slowdown
    shows against the baseline build and is flagged, whatever the calibration says."""
    s, row = _gate_with_side_by_side(monkeypatch, 1.2, 1.01)
    assert row["calibration_regressed"] and not row["regressed"] and row["attempts"] == 1
    assert "water_step" not in s["regressed"] and abs(row["reference_build"]["change"] - 0.01) < 1e-12
    s, row = _gate_with_side_by_side(monkeypatch, 1.0, 1.10)
    assert (
        not row["calibration_regressed"]
        and row["regressed"]
        and s["regressed"] == ["water_step", "soil_step"]
    )


def test_without_the_baseline_commit_the_calibration_verdict_stands(monkeypatch):
    def no_tree(commit):
        raise RuntimeError("cannot export the baseline commit 000000000000: not in this clone")

    monkeypatch.setattr(
        gate,
        "run_suite",
        lambda slowdown=None, select=None: {**_run(1.2), "wall_s": 1.0, "output": "", "returncode": 0},
    )
    monkeypatch.setattr(reference_build, "reference_tree", no_tree)
    s, _ = gate.gated_run(REF_BASE, ROOT / "benchmarks" / "baselines" / "gate.json", estimator="wall")
    row = next(r for r in s["benchmarks"] if r["name"] == "water_step")
    assert row["regressed"] and "not in this clone" in row["reference_build"]["error"]


def test_side_by_side_ratio_is_the_median_over_pairs_of_their_rounds(monkeypatch):
    """Per round, current / baseline build; a pair's median over its rounds, and the median over the
    pairs: one disturbed call or one disturbed pair does not move it."""
    pairs = iter(
        [
            [(1.0, 1.1), (1.0, 1.1), (1.0, 2.0)],  # a call of the current build preempted
            [(1.0, 1.1), (2.0, 1.1), (1.0, 1.1)],  # a call of the baseline build preempted
            [(1.0, 0.9), (1.0, 0.9), (1.0, 0.9)],  # a pair reading 10 % off for its whole life
        ]
    )
    monkeypatch.setattr(reference_build, "alternating_times", lambda *a, **k: next(pairs))
    m = reference_build.measurement("water_step", ROOT, ROOT, pairs=3)
    assert abs(m["ratio"] - 1.1) < 1e-12 and abs(m["pair_ratios"][2] - 0.9) < 1e-12


def test_side_by_side_child_that_cannot_start_says_which_and_why(tmp_path):
    """A build whose benchmark cannot start (here a tree with no benchmarks/) stops the measurement
    with the benchmark, the tree and the child's own last error line, instead of hanging."""
    with pytest.raises(RuntimeError, match=r"water benchmark in .* did not start: .*No module named"):
        reference_build.alternating_times("water_step", tmp_path, ROOT, rounds=2)
