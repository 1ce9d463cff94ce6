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
