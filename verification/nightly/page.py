"""The nightly page: one static HTML file, no script, no external resource (figures are
embedded as base64 PNG), readable offline and testable in a real browser
(tests/test_report_browser.py). The checks table has one row (class "check") per case metric.
"""

from __future__ import annotations

import base64
import html
import math
from pathlib import Path

STYLE = """
body { font-family: sans-serif; margin: 1.5em; color: #222; max-width: 1300px; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.85em; }
th, td { border: 1px solid #bbb; padding: 3px 6px; vertical-align: top; }
th { background: #eee; }
td.num { text-align: right; font-family: monospace; }
tr.FAIL td, li.problem { background: #fde2e2; }
tr.PASS td.verdict { color: #176317; font-weight: bold; }
tr.FAIL td.verdict { color: #a00; font-weight: bold; }
tr.KNOWN td { background: #fff3d6; } tr.KNOWN td.verdict { color: #8a5a00; }
.banner { padding: 0.6em 1em; font-size: 1.2em; font-weight: bold; }
.banner.ok { background: #dff3df; } .banner.bad { background: #fbd5d5; }
img { max-width: 100%; border: 1px solid #ddd; margin: 0.3em 0; }
pre { background: #f6f6f6; padding: 0.5em; overflow-x: auto; font-size: 0.8em; }
.small { font-size: 0.85em; color: #555; }
"""


def esc(v):
    return html.escape(str(v))


def fmt(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.4g}" if math.isfinite(v) else str(v)
    if isinstance(v, int):
        return str(v)
    if v is None or v == "":
        return "–"
    return str(v)


def img(data, alt):
    return f'<img src="data:image/png;base64,{base64.b64encode(data).decode()}" alt="{esc(alt)}">'


def img_file(path, alt):
    path = Path(path)
    if not path.is_file():
        return f'<p class="small">figure {esc(path.name)} missing</p>'
    return img(path.read_bytes(), alt)


def table(header, rows, cls="", row_classes=None):
    out = [
        f'<table class="{cls}"><thead><tr>' + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr></thead>"
    ]
    out.append("<tbody>")
    for i, r in enumerate(rows):
        rc = f' class="{esc(row_classes[i])}"' if row_classes else ""
        cells = "".join(
            f'<td class="num">{esc(fmt(v))}</td>'
            if isinstance(v, (int, float))
            else f"<td>{esc(fmt(v))}</td>"
            for v in r
        )
        out.append(f"<tr{rc}>{cells}</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def checks_table(records):
    rows = [
        '<table id="checks"><thead><tr><th>case</th><th>metric</th><th>value</th><th>tolerance</th>'
        "<th>tolerance source</th><th>verdict</th></tr></thead><tbody>"
    ]
    for name, rec in records.items():
        for c in rec.get("run", {}).get("checks", []):
            verdict = "PASS" if c["passed"] else "FAIL"
            known = c.get("known_failure")
            shown = verdict
            if known:
                verdict = "KNOWN" if not c["passed"] else "FAIL"
                shown = (
                    f"known failure: {known}" if not c["passed"] else "PASS, but listed as a known failure"
                )
            rows.append(
                f'<tr class="check {verdict}" data-case="{esc(name)}">'
                f"<td>{esc(name)}</td><td>{esc(c['metric'])}</td>"
                f'<td class="num">{esc(fmt(c["value"]))}</td><td class="num">{esc(fmt(c["tolerance"]))}</td>'
                f'<td>{esc(c["source"])}</td><td class="verdict">{esc(shown)}</td></tr>'
            )
    rows.append("</tbody></table>")
    return "\n".join(rows)


def case_section(name, rec, case_dir):
    run = rec.get("run", {})
    proc = rec.get("process", {})
    parts = [
        f'<h3 id="case-{esc(name)}">{esc(name)} <span class="small">({esc(rec.get("module", ""))}): '
        f"{esc(rec.get('status', '?'))}</span></h3>"
    ]
    if "resolution" in run:
        parts.append(
            f"<p>resolution {esc(run['resolution'])}, {esc(run['particles'])} particles, "
            f"{esc(run['steps'])} steps; "
            f"stepping {fmt(run.get('wall_time_s'))} s wall, {fmt(run.get('cpu_time_s'))} s CPU; "
            f"the whole case process (imports, compile, run, study) {fmt(proc.get('wall_s'))} s wall, "
            f"{fmt(proc.get('cpu_s'))} s CPU, load {fmt(proc.get('load_1min_before'))} → "
            f"{fmt(proc.get('load_1min_after'))}</p>"
        )
    for part in ("import", "run", "study"):
        err = rec.get(part, {}).get("error")
        if err:
            parts.append(f"<p><b>{part} raised:</b></p><pre>{esc(err)}</pre>")
    if rec.get("crash"):
        parts.append(f"<p><b>crashed:</b></p><pre>{esc(rec['crash'])}</pre>")
    if run.get("notes"):
        parts.append("<ul>" + "".join(f"<li>{esc(n)}</li>" for n in run["notes"]) + "</ul>")
    for fig in run.get("figures", []):
        parts.append(img_file(case_dir / fig, f"{name}: {Path(fig).name}"))
    for t in run.get("tables", []):
        parts.append(
            f"<p><b>{esc(t.get('title', ''))}</b></p>" + table(t.get("header", []), t.get("rows", []))
        )
    return "\n".join(parts)


def cost_section(name, rec, figure_png, planned):
    study = rec.get("study", {})
    rows, refs = study.get("rows", []), rec.get("reference_costs", [])
    parts = [f"<h3>{esc(name)}</h3>"]
    if planned:
        parts.append(f'<p class="small">{esc(planned)}</p>')
    if study.get("error"):
        parts.append("<p>study raised (see the case above)</p>")
    if rec.get("status") == "crashed":
        parts.append("<p>no result: the case crashed (see above)</p>")
        return "\n".join(parts)
    if not rows:
        run = rec.get("run", {})
        parts.append(
            "<p>no resolution study tonight; the single run: "
            f"{fmt(run.get('wall_time_s'))} s wall, {fmt(run.get('cpu_time_s'))} s CPU</p>"
        )
        return "\n".join(parts)
    if figure_png:
        parts.append(img(figure_png, f"{name}: error against wall and CPU time"))
    header = list(rows[0])
    parts.append(table(header, [[r.get(h) for h in header] for r in rows], cls="study"))
    if refs:
        rh = list(refs[0])
        parts.append(
            "<p>reference code on the same axes:</p>" + table(rh, [[r.get(h) for h in rh] for r in refs])
        )
    return "\n".join(parts)


def side_by_side(b):
    """The change against the baseline commit's build timed side by side, with its gate."""
    ref = b.get("reference_build") or {}
    if "change" in ref:
        return f"{ref['change']:+.1%} (+{ref['threshold']:.1%})"
    return f"not measured: {ref['error']}" if "error" in ref else "–"


def bench_section(bench):
    if not bench:
        return (
            "<p>No benchmark summary tonight (run <code>make bench-check</code> first, or "
            "<code>make nightly</code>).</p>"
        )
    rows, classes = [], []
    for b in bench.get("benchmarks", []):
        verdict = "FAIL" if b.get("regressed") else ("skipped" if b.get("skipped") else "PASS")
        classes.append(verdict)
        change = (
            (b["ratio"] / b["baseline_ratio"] - 1) if b.get("ratio") and b.get("baseline_ratio") else None
        )
        rows.append(
            [
                b["name"],
                b.get("what", ""),
                b.get("value"),
                b.get("unit", ""),
                b.get("calibration_s"),
                b.get("ratio"),
                b.get("baseline_ratio"),
                f"{change:+.1%}" if change is not None else "–",
                f"+{b['threshold']:.1%}" if b.get("threshold") is not None else "–",
                side_by_side(b),
                b.get("attempts", 1),
                verdict if not b.get("skipped") else f"skipped: {b['skipped']}",
            ]
        )
    head = (
        f"<p>gate run {esc(bench.get('date', ''))} on {esc(bench.get('host', ''))}, load "
        f"{fmt(bench.get('load_1min'))}, {fmt(bench.get('wall_s'))} s; baselines: "
        f"{esc(bench.get('baseline_source', ''))}. The ratio divides a benchmark's time by the calibration "
        "kernel timed interleaved with it (benchmarks/calibration.py); the gate compares ratios, not "
        f"times (estimator: {esc(bench.get('estimator', '?'))}; docs/benchmarks.md). A benchmark past its "
        "gate is measured again alone, up to twice (attempts), and fails only if every attempt is past. "
        "The steps are also timed against the baseline commit's own build, alternating processes "
        "(benchmarks/reference_build.py); where that was measured, it decides the verdict.</p>"
    )
    return head + table(
        [
            "benchmark",
            "what",
            "value",
            "unit",
            "calibration (s)",
            "ratio",
            "baseline ratio",
            "change",
            "gate",
            "against the baseline build (gate)",
            "attempts",
            "verdict",
        ],
        rows,
        cls="bench",
        row_classes=classes,
    )


def render(ctx):
    """The page from the report's context (report.py builds it)."""
    meta, records, problems = ctx["meta"], ctx["records"], ctx["problems"]
    ok = not problems
    n_checks = sum(len(r.get("run", {}).get("checks", [])) for r in records.values())
    n_fail = sum(1 for r in records.values() for c in r.get("run", {}).get("checks", []) if not c["passed"])
    n_known = sum(
        1
        for r in records.values()
        for c in r.get("run", {}).get("checks", [])
        if not c["passed"] and c.get("known_failure")
    )
    out = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        '<link rel="icon" href="data:,">',
        f"<title>ScourSPH nightly {esc(meta['date'][:10])}</title><style>{STYLE}</style></head><body>",
        f"<h1>ScourSPH nightly verification, {esc(meta['date'])}</h1>",
        f'<div id="verdict" class="banner {"ok" if ok else "bad"}">'
        + ("Everything passed; nothing moved." if ok else f"{len(problems)} problem(s): see below")
        + "</div>",
        f"<p>commit <code>{esc(meta['commit'])}</code>"
        f"{' (with uncommitted changes)' if meta.get('dirty') else ''}"
        f" on {esc(meta.get('branch', ''))}; host {esc(meta['host'])} ({esc(meta['cpus'])} cores), "
        "1-min load "
        f"{fmt(meta['load_1min'])} at the start, {fmt(ctx.get('load_end'))} at the end. "
        f"{len(records)} cases, {n_checks} checks, {n_fail} failed ({n_known} of them known failures).</p>",
        f"<p>{esc(ctx['timing_text'])}</p>",
        '<h2 id="problems">Problems</h2>',
    ]
    if problems:
        out.append(
            "<ul>"
            + "".join(
                f'<li class="problem"><b>{esc(p["kind"])}</b>: {esc(p["what"])}: {esc(p["why"])}</li>'
                for p in problems
            )
            + "</ul>"
        )
    else:
        out.append("<p>none</p>")
    out += ['<h2 id="checks-heading">Every case and metric</h2>', checks_table(records)]
    out.append('<h2 id="cases">Cases</h2>')
    for name, rec in records.items():
        out.append(case_section(name, rec, ctx["out_dir"] / name))
    out.append('<h2 id="cost">What accuracy costs in time</h2>')
    out.append(
        '<p class="small">Error against stepping wall time and CPU time (time.process_time: all threads '
        "of the "
        "case's process; one Numba thread per case unless stated), one point per resolution of the study. "
        "Wall time follows the machine's load; CPU time of a one-thread run barely does.</p>"
    )
    for name, rec in records.items():
        out.append(cost_section(name, rec, ctx["cost_figures"].get(name), ctx["plans"].get(name, "")))
    out.append('<h2 id="trend">Trend over the nights</h2>')
    out.append(f'<p class="small">{esc(ctx["trend_text"])}</p>')
    for name, fig in ctx["trend_figures"].items():
        out.append(img(fig, f"trend: {name}"))
    out.append('<h2 id="benchmarks">Benchmarks</h2>')
    out.append(bench_section(ctx.get("bench")))
    out.append(
        f'<p class="small">results.json beside this page holds every number shown. {esc(ctx["footer"])}</p>'
    )
    out.append("</body></html>")
    return "\n".join(out)
