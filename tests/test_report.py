"""The nightly report (`scoursph report`, verification/nightly/) without a browser: a failing or
crashing case does not stop the others, the exit status and the Problems list say which, the
page has one checks row per case metric, and the history flags a metric that moved by more
than a quarter of its tolerance. The run (tests/report_run.py, ~20 s) is shared with the browser test."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from report_run import EXPECTED_CHECKS, shared_report_run

from verification.nightly import collect, history, plots
from verification.nightly.report import problems_of

ROOT_TESTS = Path(__file__).resolve().parent


@pytest.fixture(scope="module")
def report_run(tmp_path_factory):
    return shared_report_run(tmp_path_factory)


def test_every_case_reported_and_failures_isolated(report_run):
    res = report_run.results
    assert report_run.returncode == 1, report_run.output
    status = {name: rec["status"] for name, rec in res["cases"].items()}
    assert status == {
        "small_hydro": "passed",
        "synthetic": "passed",
        "failing": "failed",
        "known": "passed",
        "raising": "crashed",
        "segfault": "crashed",
    }
    kinds = {(p["kind"], p["what"]) for p in res["problems"]}
    assert ("case failed", "failing") in kinds
    assert ("case crashed", "raising") in kinds
    assert ("case crashed", "segfault") in kinds
    assert any("SIGSEGV" in p["why"] for p in res["problems"] if p["what"] == "segfault")
    assert "RuntimeError: synthetic failure" in next(
        p["why"] for p in res["problems"] if p["what"] == "raising"
    )


def test_page_has_one_row_per_case_metric_and_no_external_resource(report_run):
    text = report_run.page.read_text()
    rows = re.findall(r'<tr class="check (PASS|FAIL|KNOWN)"', text)
    assert (
        len(rows)
        == EXPECTED_CHECKS
        == sum(len(r.get("run", {}).get("checks", [])) for r in report_run.results["cases"].values())
    )
    assert rows.count("FAIL") == 1 and rows.count("KNOWN") == 1
    assert "known failure: a known failure of the test double" in text
    assert "<script" not in text
    assert not re.search(r'(src|href)="(https?:)?//', text), "the page must work offline"
    assert (report_run.root / "latest" / "index.html").is_file()


def test_cpu_time_and_study_rows_recorded(report_run):
    rec = report_run.results["cases"]["small_hydro"]
    assert rec["run"]["cpu_time_s"] > 0 and rec["run"]["wall_time_s"] > 0
    assert rec["process"]["cpu_s"] > 0
    assert [r["resolution"] for r in rec["study"]["rows"]] == [10, 20]
    assert all(r["cpu_time_s"] > 0 for r in rec["study"]["rows"])


def test_seeded_previous_night_flags_the_moved_metric(report_run):
    flags = report_run.results["flags"]
    moved = [f for f in flags if f["kind"] == "metric moved"]
    assert [f["what"] for f in moved] == ["synthetic :: first synthetic metric"]
    speed = [f for f in flags if f["kind"] == "speed regression"]
    assert [f["what"] for f in speed] == ["water_step"]
    lines = history.load(report_run.history)
    assert len(lines) == 2 and lines[-1]["commit"] and lines[-1]["host"]
    assert lines[-1]["benchmarks"]["water_step"]["regressed"] is True


def test_flags_rule():
    prev = {
        "date": "d0",
        "commit": "c0",
        "metrics": {"a :: m": {"value": 1.0, "tolerance": 1.0, "passed": True}},
    }
    tonight = {"metrics": {"a :: m": {"value": 1.2, "tolerance": 1.0, "passed": False}}, "benchmarks": {}}
    assert history.flags(tonight, prev) == []  # 0.2 < a quarter of 1.0
    tonight["metrics"]["a :: m"]["value"] = 1.3
    assert [f["what"] for f in history.flags(tonight, prev)] == ["a :: m"]
    tonight["metrics"]["a :: m"]["value"] = "nan"  # a metric that became NaN moved
    assert len(history.flags(tonight, prev)) == 1
    assert history.flags(tonight, None) == []


def test_problems_name_the_failed_check():
    rec = {
        "status": "failed",
        "run": {"checks": [{"metric": "m", "value": 2.0, "tolerance": 1.0, "passed": False}]},
    }
    (p,) = problems_of({"c": rec}, [])
    assert p["what"] == "c" and "m = 2 exceeds 1" in p["why"]


def test_known_failure_that_passes_is_flagged_like_a_strict_xfail():
    check = {"metric": "m", "value": 0.5, "tolerance": 1.0, "passed": True, "known_failure": "why"}
    rec = {"run": {"checks": [check]}}
    rec["status"] = collect.status(rec)
    assert rec["status"] == "failed"
    (p,) = problems_of({"c": rec}, [])
    assert "known failure" in p["why"]
    check["passed"] = False  # failing as expected: the case passes
    assert collect.status(rec) == "passed"


def test_trend_scaling_of_exact_requirements():
    assert plots.scaled({"value": 0.0, "tolerance": 0.0}) == 0.0
    assert plots.scaled({"value": 3.0, "tolerance": 0.0}) == plots.CLIP
    assert plots.scaled({"value": 0.5, "tolerance": 2.0}) == 0.25


def test_results_json_is_strict_json(report_run):
    json.loads((report_run.page.parent / "results.json").read_text(), parse_constant=lambda c: 1 / 0)


def test_a_killed_case_says_how():
    import signal

    assert "SIGXCPU" in collect._ended(-signal.SIGXCPU) and "CPU-time limit" in collect._ended(
        -signal.SIGXCPU
    )
    assert collect._ended(3) == "process exited with status 3"


def test_cases_side_by_side_keep_their_own_cpu_time(tmp_path, monkeypatch):
    """Two busy cases run at once (jobs=2). Each one's CPU time must be its own (wait4 of that
    child), not the sum over the children that ended meanwhile (RUSAGE_CHILDREN differences):
    busy minus idle is BUSY_CPU_S, which a double count would make about twice that."""
    from report_busy import BUSY_CPU_S

    monkeypatch.setenv("PYTHONPATH", str(ROOT_TESTS))
    cases = {"idle": "report_busy:Idle", "busy_a": "report_busy:Busy", "busy_b": "report_busy:Busy"}
    started = []
    records = collect.run_all(
        cases, tmp_path, timeout=600, jobs=2, progress=started.append, cost={"idle": 0.0, "busy_a": 2.0}
    )
    assert list(records) == list(cases)  # the order of the registry, whatever ran first
    assert [m for m in started if m.endswith("...")][0].startswith("report: busy_b")  # unknown cost: first
    assert all(r["status"] == "passed" for r in records.values()), records
    idle = records["idle"]["process"]["cpu_s"]
    for name in ("busy_a", "busy_b"):
        extra = records[name]["process"]["cpu_s"] - idle
        assert 0.9 * BUSY_CPU_S < extra < 1.5 * BUSY_CPU_S, (name, extra)


def test_a_hung_case_is_killed_at_its_timeout(tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", str(ROOT_TESTS))
    rec = collect.run_case("hang", "report_busy:Hang", tmp_path / "hang", timeout=5.0)
    assert rec["status"] == "crashed" and "timed out after 5 s" in rec["crash"]
    assert rec["process"]["wall_s"] < 60
