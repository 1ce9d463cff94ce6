"""All verification cases, for `scoursph verify CASE|all` and the nightly report.

A case module provides DEFAULT_RESOLUTION, STUDY_RESOLUTIONS, run(resolution, out_dir)
returning a CaseResult, and study(out_dir=...) returning rows of (error, wall time) per
resolution.

Exit status of `run_cases`: 0 only if every case ran and passed; 1 if a case failed a check,
could not be imported, raised, or (study) produced a non-finite error; 2 for an unknown case
name. Errors go to standard error, one line each; the PASS/FAIL report to standard output.
"""

from __future__ import annotations

import importlib
import inspect
import sys
from pathlib import Path

CASES = {
    "dam_break": "verification.dam_break",
    "hydrostatic": "verification.hydrostatic",
    "column_collapse": "verification.column_collapse",
    "soil_self_weight": "verification.soil_self_weight",
    "impact_pressure": "verification.impact_pressure",
    "seepage_bed_at_rest": "verification.seepage_bed_at_rest",
    "seepage_darcy": "verification.seepage_darcy",
    "seepage_terzaghi": "verification.seepage_terzaghi",
    "seepage_critical_gradient": "verification.seepage_critical_gradient",
    "seepage_sheet_pile": "verification.seepage_sheet_pile",
    "overflow_nappe_rigid_bed": "verification.overflow_nappe_rigid_bed",  # issue 11 item 8, vs OpenFOAM
    "sediment_threshold": "verification.sediment_threshold",  # issue 24 item 3, Shields onset
    "granular_incline": "verification.granular_incline",  # issue 24 item 1, mu(I) Bagnold profile
    "jet_scour": "verification.jet_scour",  # issue 24 item 3, plane jet scour depth against time
    "mobile_bed_dam_break": "verification.mobile_bed_dam_break",  # issue 24 item 3, Spinewine & Zech set-up
    "sand_element": "verification.sand_element",  # issue 31 item 3, a sand with a state at a material point
}
# Cases only the nightly report runs (after CASES): `scoursph verify all` and `make verify` leave them out
NIGHTLY_CASES = {
    "stability_matrix": "verification.stability_nightly",  # issue 14's matrix within a budget
}


def _error(message):
    print(f"scoursph: error: {message}", file=sys.stderr, flush=True)


def case_module(name):
    if name not in CASES:
        raise KeyError(f"unknown verification case '{name}' (known: {', '.join(CASES)}, all)")
    return importlib.import_module(CASES[name])


def run_cases(which, out_dir, resolution=None, study=False, quiet=False):
    """Run one case or all; print pass/fail per metric; exit status 0 only if all pass."""
    if which != "all" and which not in CASES:
        _error(f"verify: unknown verification case '{which}' (known: {', '.join(CASES)}, all)")
        return 2
    names = list(CASES) if which == "all" else [which]
    all_passed = True
    out_dir = Path(out_dir)
    for name in names:
        try:
            mod = case_module(name)
        except Exception as exc:  # a case that cannot even be imported is a failure, never skipped
            _error(f"verify {name}: the case cannot be imported: {type(exc).__name__}: {exc}")
            all_passed = False
            continue
        try:
            passed = _study(name, mod, out_dir) if study else _run(name, mod, out_dir, resolution)
        except Exception as exc:  # a blow-up or missing reference data: this case failed
            _error(f"verify {name}: {type(exc).__name__}: {exc}")
            passed = False
        all_passed &= passed
    return 0 if all_passed else 1


def _run(name, mod, out_dir, resolution):
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
    return res.passed


def _study(name, mod, out_dir):
    """A resolution study, written under out_dir/name (never into the installed package).
    It fails if it produced no rows or a non-finite number (a run that blew up raises)."""
    kwargs = {}
    if "out_dir" in inspect.signature(mod.study).parameters:
        kwargs["out_dir"] = out_dir / name
    rows = mod.study(**kwargs)
    from .common import study_failures

    failures = study_failures(rows)
    print(f"{name}: resolution study (error and wall time side by side) [{'FAIL' if failures else 'PASS'}]")
    for row in rows or []:
        print(
            "  "
            + ", ".join(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}" for k, v in row.items())
        )
    for failure in failures:
        print(f"  [FAIL] {failure}")
    return not failures
