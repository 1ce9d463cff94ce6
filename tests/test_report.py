"""The nightly report (`scoursph report`, verification/nightly/) without a browser: a failing or
crashing case does not stop the others, the exit status and the Problems list say which, the
page has one checks row per case metric, and the history flags a metric that moved by more
than a quarter of its tolerance. The run (tests/report_run.py, ~20 s) is shared with the browser test."""

from __future__ import annotations

import json
import re

import pytest
from report_run import EXPECTED_CHECKS, shared_report_run

from verification.nightly import collect, history, plots
from verification.nightly.report import problems_of


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
