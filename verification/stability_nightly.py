"""The stability matrix (issue 14, verification/stability_matrix.py) as a case of the nightly report.

The whole matrix is about 3 G particle-steps (hours of CPU on this host), more than a night
affords next to the other cases. Tonight's cells, in a fixed order so that the nights compare:
every cell of the CI subset, every known failure (it must keep failing, like a strict xfail),
and the cheapest remaining cells (by stability_matrix.estimated_cost, particle-steps at the
sound-speed time step) while their total stays within the budget. The budget is this case's
"resolution": millions of estimated particle-steps. The page lists the cells left out with
their estimated cost and their last committed outcome (verification/results/stability_matrix/).

Three checks per cell run, the matrix's own criteria (stability_matrix.CellResult.ok):
end time missed (s) <= 0 (no blow-up), deepest wall penetration / dx <= 0.5, kinetic energy
/ its bound <= 1.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from . import stability_matrix as M
from .common import CaseResult, Check, save_figure

DEFAULT_RESOLUTION = 600  # budget: millions of estimated particle-steps (~10 CPU min on this host)
QUICK_RESOLUTION = 0  # `scoursph report --quick`: the CI subset and the known failures only
NIGHTLY_NOTE = (
    "The 'resolution' of this case is its budget in millions of estimated particle-steps: the CI "
    "subset, the known failures and the cheapest other cells within it; the rest of the matrix is "
    "listed with its cost (`python -m verification.stability_matrix` runs all of it)."
)
COMMITTED = M.OUT / "matrix.csv"

END = "end time missed (s)"
WALL = "deepest wall penetration / dx"
ENERGY = "kinetic energy / its bound"
SOURCES = {
    END: "the run must reach its end time: no BlowUpError (NaN, a particle outside the domain, a wall "
    "crossing deeper than h, time-step collapse; verification/stability_matrix.py)",
    WALL: "dx/2: a particle reflected by less than half a spacing stays in its lattice cell "
    "(tests/test_soil_hard_cases.py, verification/stability_matrix.py)",
    ENERGY: "KE <= F (KE0 + PE0 - PE + E_el0): the total energy never grows; F = 1/(1 - (omega dt)^2/4) "
    "is the leap-frog's slack (verification/stability_matrix.py)",
}
TOLERANCES = {END: 0.0, WALL: 0.5, ENERGY: 1.0}


def metric(cell, what):
    return f"{cell}: {what}"


# a known failure of the matrix fails all three of its checks today (dam_break_r40: blow-up,
# a particle 3.5 dx through the wall, the energy bound exceeded 5e4 times)
KNOWN_FAILURES = {metric(c, w): why for c, why in M.KNOWN_FAILURES.items() for w in (END, WALL, ENERGY)}


def tonight(budget_mps, all_cells=None):
    """(cells to run in order, cells left out with their estimated cost in particle-steps)."""
    all_cells = M.cells() if all_cells is None else all_cells
    costs = {c.name: M.estimated_cost(c) for c in all_cells}
    real = sorted((c for c in all_cells if not c.placeholder), key=lambda c: costs[c.name])
    must = [c for c in real if c.ci or c.name in M.KNOWN_FAILURES]
    spent = sum(costs[c.name] for c in must)
    chosen = {c.name for c in must}
    for c in real:
        if c.name not in chosen and spent + costs[c.name] <= budget_mps * 1e6:
            chosen.add(c.name)
            spent += costs[c.name]
    run = [c for c in all_cells if c.placeholder] + [c for c in real if c.name in chosen]
    left = [(c, costs[c.name]) for c in real if c.name not in chosen]
    return run, left


def checks_of(r):
    if r.status.startswith("skipped"):
        return []
    values = {
        END: max(r.end_time - r.t_reached, 0.0) if not r.completed else 0.0,
        WALL: r.deepest_penetration / r.spacing if r.spacing else math.nan,
        ENERGY: r.energy_ratio,
    }
    return [Check(metric(r.name, w), v, TOLERANCES[w], SOURCES[w]) for w, v in values.items()]


def committed_outcomes(path=COMMITTED):
    """{cell: row} of the committed full-matrix table (its last full run), if any."""
    try:
        with open(path, newline="") as fh:
            return {r["name"]: r for r in csv.DictReader(fh)}
    except OSError:
        return {}


def figure(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ran = [r for r in results if not r.status.startswith("skipped")]
    names = [r.name for r in ran]
    y = range(len(ran))
    fig, axs = plt.subplots(1, 3, figsize=(11, 0.22 * len(ran) + 1.4), sharey=True)
    panels = (
        ("kinetic energy / bound", [r.energy_ratio for r in ran], 1.0),
        ("deepest penetration / dx", [r.deepest_penetration / r.spacing for r in ran], 0.5),
        ("CPU time (s)", [r.cpu_s for r in ran], None),
    )
    for ax, (label, values, bound) in zip(axs, panels):
        colors = ["C3" if not r.ok else "C0" for r in ran]
        ax.barh(list(y), [min(v, 3 * bound) if bound else v for v in values], color=colors)
        if bound:
            ax.axvline(bound, color="k", ls="--", lw=0.8)
            ax.set_xlim(0, 3 * bound)
        ax.set_xlabel(label + (" (clipped at 3x the bound)" if bound else ""), fontsize=8)
        ax.grid(alpha=0.3, axis="x")
    axs[0].set_yticks(list(y), names, fontsize=6)
    axs[0].invert_yaxis()
    fig.suptitle("Stability matrix tonight (red: the cell fails; dashed: the bound)", fontsize=10)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def run(resolution=DEFAULT_RESOLUTION, out_dir=None):
    out = Path(out_dir) if out_dir is not None else M.OUT / "nightly"
    cells, left = tonight(resolution)
    results = []
    for c in cells:
        r = M.run_cell(c)
        results.append(r)
        print(f"{r.name}: {M._row(r)['outcome']} ({r.status}; {r.wall_s:.1f} s wall, {r.cpu_s:.1f} s CPU)")
        M.write_table(results, out, "matrix_tonight")  # a case cut short keeps what it has
    ran = [r for r in results if not r.status.startswith("skipped")]
    res = CaseResult(
        "stability_matrix",
        resolution,
        sum(r.particles for r in ran),
        sum(r.steps for r in ran),
        sum(r.wall_s for r in ran),
        {},
        cpu_time=sum(r.cpu_s for r in ran),
    )
    res.checks = [c for r in results for c in checks_of(r)]
    res.figure = figure(results, out / "stability_matrix.png")
    header = [
        "cell",
        "verdict",
        "particles",
        "steps",
        "t reached / end (s)",
        "wall reflections",
        "deepest penetration / dx",
        "KE / bound",
        "wall time (s)",
        "CPU time (s)",
        "load",
        "status",
    ]
    rows = []
    for r in results:
        row = M._row(r)
        verdict = row["outcome"] + (" (known failure)" if r.name in M.KNOWN_FAILURES else "")
        rows.append(
            [
                r.name,
                verdict,
                r.particles,
                r.steps,
                f"{r.t_reached:.4g} / {r.end_time:g}",
                r.wall_reflections,
                row["deepest_penetration_dx"],
                row["energy_ratio"],
                round(r.wall_s, 1),
                round(r.cpu_s, 1),
                round(r.load, 1),
                r.status,
            ]
        )
    title = f"Cells run tonight ({len(ran)} of {len(ran) + len(left)}; placeholders listed as skipped)"
    res.tables.append({"title": title, "header": header, "rows": rows})
    if left:
        old = committed_outcomes()
        res.tables.append(
            {
                "title": f"Cells left out tonight (budget {resolution} M particle-steps), outcome in "
                f"the committed full-matrix table ({COMMITTED.relative_to(M.ROOT)})",
                "header": [
                    "cell",
                    "estimated M particle-steps",
                    "committed outcome",
                    "committed wall s",
                    "committed CPU s",
                ],
                "rows": [
                    [
                        c.name,
                        round(cost / 1e6, 1),
                        old.get(c.name, {}).get("outcome", "not in the table"),
                        old.get(c.name, {}).get("wall_s", ""),
                        old.get(c.name, {}).get("cpu_s", ""),
                    ]
                    for c, cost in left
                ],
            }
        )
    failed = [r for r in ran if not r.ok]
    res.notes = [
        f"{len(ran)} cells run ({sum(r.particles * r.steps for r in ran) / 1e6:.0f} M particle-steps, "
        f"{res.wall_time:.0f} s wall, {res.cpu_time:.0f} s CPU), {len(failed)} failing "
        f"({', '.join(r.name for r in failed) or 'none'}); {len(left)} left out for time; "
        f"{sum(1 for r in results if r.status.startswith('skipped'))} placeholders.",
    ]
    return res


if __name__ == "__main__":
    import sys

    from .common import case_main

    raise SystemExit(case_main(sys.modules[__name__]))
