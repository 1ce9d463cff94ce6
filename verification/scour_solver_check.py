"""A study case rerun on this checkout's solver into runs/scour_solver_check/ (not the study's case files),
then its d(t) against the study's committed CSV: how far a solver change moves a run that was not rerun
(docs/history/scour_study_history.md, "What was run").

    python -m verification.scour_solver_check dry 0.11 --end 1.0

Stopped early (SIGINT/SIGTERM), it compares the times reached.
"""

from __future__ import annotations

import argparse
import csv
import sys
import time

from verification.scour_study import DX, RESULTS, ROOT, SCENES, case_name, scene_raw


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("soil", choices=("dry", "saturated"))
    p.add_argument("q", type=float)
    p.add_argument("--end", type=float, default=1.0)
    a = p.parse_args(argv)
    from solver.run import run_scene
    from solver.scene import parse_scene

    name = case_name(a.soil, a.q, DX)
    reference = RESULTS / "cases" / f"{name}_scour.csv"
    if not reference.exists():
        print(f"{reference}: no study run to compare with", file=sys.stderr)
        return 2
    out = ROOT / "runs" / "scour_solver_check" / name
    scene = parse_scene(scene_raw(a.soil, a.q, DX, a.end), SCENES / f"scour_{a.soil}.toml")
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        run_scene(scene, out, quiet=True, overwrite=True)
    except BaseException as exc:  # noqa: BLE001 - stopped or failed: compare what was written
        print(f"stopped: {exc!r}")
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    print(f"{name} to {a.end:g} s: {cpu:.0f} s CPU, {wall:.0f} s wall")
    new = {round(float(r["t_s"]), 6): r for r in csv.DictReader(open(out / "scour.csv"))}
    old = {round(float(r["t_s"]), 6): r for r in csv.DictReader(open(reference))}
    print("t_s | d study (mm) | d now (mm) | x deepest study / now (m) | eroded study / now (cm2)")
    for t in sorted(set(new) & set(old)):
        a_, b = old[t], new[t]
        print(
            f"{t:.3f} | {1e3 * float(a_['depth_m']):.4f} | {1e3 * float(b['depth_m']):.4f} | "
            f"{a_['x_deepest_m']} / {b['x_deepest_m']} | "
            f"{1e4 * float(a_['eroded_area_m2']):.4f} / {1e4 * float(b['eroded_area_m2']):.4f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
