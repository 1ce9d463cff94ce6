"""All verification cases, for `scoursph verify CASE|all` and the nightly report.

A case module provides DEFAULT_RESOLUTION, STUDY_RESOLUTIONS, run(resolution, out_dir)
returning a CaseResult, and study() returning rows of (error, wall time) per resolution.
"""

from __future__ import annotations

import importlib
from pathlib import Path

CASES = {
    "dam_break": "verification.dam_break",
    "hydrostatic": "verification.hydrostatic",
    "column_collapse": "verification.column_collapse",
    "soil_self_weight": "verification.soil_self_weight",
    "impact_pressure": "verification.impact_pressure",
}


def case_module(name):
    if name not in CASES:
        raise KeyError(f"unknown verification case '{name}' (known: {', '.join(CASES)})")
    return importlib.import_module(CASES[name])


def available():
    out = []
    for name, mod in CASES.items():
        try:
            importlib.import_module(mod)
            out.append(name)
        except ModuleNotFoundError:
            pass
    return out


def run_cases(which, out_dir, resolution=None, study=False, quiet=False):
    """Run one case or all; print pass/fail per metric; exit status 0 only if all pass."""
    names = available() if which == "all" else [which]
    try:
        modules = {n: case_module(n) for n in names}
    except (KeyError, ModuleNotFoundError) as exc:
        print(f"scoursph: error: {exc}")
        return 2
    all_passed = True
    out_dir = Path(out_dir)
    for name, mod in modules.items():
        if study:
            rows = mod.study()
            print(f"{name}: resolution study (error and wall time side by side)")
            for row in rows:
                print(
                    "  "
                    + ", ".join(
                        f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in row.items()
                    )
                )
            continue
        res = mod.run(resolution or mod.DEFAULT_RESOLUTION, out_dir=out_dir)
        verdict = "PASS" if res.passed else "FAIL"
        print(
            f"{name} [{verdict}]: resolution {res.resolution}, {res.particles} particles, {res.steps} steps, "
            f"{res.wall_time:.1f} s wall"
        )
        for check in res.checks:
            print(check.line())
        for note in res.notes:
            print(f"  note: {note}")
        if res.figure:
            print(f"  figure: {res.figure}")
        all_passed &= res.passed
    return 0 if all_passed else 1
