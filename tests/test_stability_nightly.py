"""The stability matrix as a nightly case (verification/stability_nightly.py): which cells a night
runs within its budget, and the three checks of a cell (the matrix's own criteria)."""

import math

from verification import stability_matrix as M
from verification import stability_nightly as S


def _cells():
    """A small fixed matrix: costs are what estimated_cost would give, stubbed by name."""
    return [
        M.Cell("cheap", "f"),
        M.Cell("ci_big", "f", ci=True),
        M.Cell("mid", "f"),
        M.Cell("known", "f"),
        M.Cell("dear", "f"),
        M.Cell("later", "f", placeholder="not built yet"),
    ]


def test_a_night_runs_the_ci_subset_the_known_failures_and_the_cheapest_within_budget(monkeypatch):
    cost = {"cheap": 1e6, "ci_big": 50e6, "mid": 5e6, "known": 30e6, "dear": 40e6, "later": 0.0}
    monkeypatch.setattr(M, "estimated_cost", lambda c: cost[c.name])
    monkeypatch.setattr(M, "KNOWN_FAILURES", {"known": "fails today"})
    run, left = S.tonight(90, _cells())  # 80 M for the must-runs, 10 M left: cheap and mid fit
    assert [c.name for c in run] == ["later", "cheap", "mid", "known", "ci_big"]  # placeholders first
    assert [(c.name, v) for c, v in left] == [("dear", 40e6)]
    run, left = S.tonight(0, _cells())  # no budget: the must-runs still run
    assert {c.name for c in run} == {"later", "ci_big", "known"}


def test_three_checks_per_cell_from_the_matrix_criteria():
    ok = M.CellResult("c", "f", status="completed", t_reached=1.0, end_time=1.0, spacing=0.004)
    ok.deepest_penetration, ok.energy_ratio = 0.001, 0.7
    checks = {c.metric: c for c in S.checks_of(ok)}
    assert set(checks) == {S.metric("c", w) for w in (S.END, S.WALL, S.ENERGY)}
    assert all(c.passed for c in checks.values()) and ok.ok
    assert math.isclose(checks[S.metric("c", S.WALL)].value, 0.25)
    bad = M.CellResult("d", "f", status="blow-up at t = 0.5 s", t_reached=0.5, end_time=0.6, spacing=0.004)
    bad.deepest_penetration, bad.energy_ratio = 0.01, 3.0
    assert not any(c.passed for c in S.checks_of(bad)) and not bad.ok
    assert S.checks_of(M.CellResult("e", "f", status="skipped: not built")) == []


def test_every_known_failure_of_the_matrix_is_a_known_failure_of_the_case():
    for cell in M.KNOWN_FAILURES:
        assert {S.metric(cell, w) for w in (S.END, S.WALL, S.ENERGY)} <= set(S.KNOWN_FAILURES)


def test_the_nightly_lists_the_matrix():
    from verification.registry import CASES, NIGHTLY_CASES

    assert NIGHTLY_CASES["stability_matrix"] == "verification.stability_nightly"
    assert "stability_matrix" not in CASES  # `scoursph verify all` leaves it out


def test_a_night_of_one_tiny_cell_gives_checks_tables_and_a_figure(monkeypatch, tmp_path):
    """run() end to end on a stubbed night: a block dropped for 0.02 s at dx = 10 mm (before it
    lands), a placeholder, and one cell left out."""
    tiny = M.Cell("tiny_drop", "block_drop", lambda: (M.block_drop_scene(0.01, 0.02), M._drop), 0.02)
    later = M.Cell("later", "x", placeholder="not built yet")
    monkeypatch.setattr(S, "tonight", lambda budget: ([later, tiny], [(M.Cell("dear", "f"), 5e6)]))
    res = S.run(0, tmp_path)
    assert [c.metric for c in res.checks] == [S.metric("tiny_drop", w) for w in (S.END, S.WALL, S.ENERGY)]
    assert all(c.passed for c in res.checks), [c.line() for c in res.checks]
    run_table, left_table = res.tables
    assert [r[0] for r in run_table["rows"]] == ["later", "tiny_drop"]
    assert run_table["rows"][1][1] == "pass" and len(run_table["rows"][1]) == len(run_table["header"])
    assert left_table["rows"][0][:2] == ["dear", 5.0]
    assert res.figure.exists() and (tmp_path / "matrix_tonight.md").exists()
