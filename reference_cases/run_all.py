"""Regenerate all full reference data (long: see reference_cases/README.md).

    python -m reference_cases.run_all [--only openfoam|seepage|nappe|impact|liggghts] [--meshes 20 40]
                                      [--nice 10]

OpenFOAM: the dam break on every mesh in --meshes (serial) and on the coarsest
mesh with 2 ranks; the steady seepage under a sheet pile (laplacianFoam and
porousSimpleFoam, T/10 to T/80, about 1 min); the overflow nappe of the scour set-up at
q = 0.06 and 0.11 on its three meshes (5, 3.33, 2.5 mm, serial); the Lobovsky impact tank (H/20, H/40,
H/60 and the closed-top and slip-wall variants at H/20 and H/40, then the comparison). LIGGGHTS: heap
calibration, the reference collapse at the calibrated friction plus the sensitivity collapses
(calibrate.py), and the reference collapse again on 2 ranks. The steps run one at a time; their wall
times go to reference_cases/run_all.json.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

from reference_cases import _common as C

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=["openfoam", "seepage", "nappe", "impact", "liggghts"], default=None)
    ap.add_argument(
        "--meshes",
        type=int,
        nargs="+",
        default=[20, 40],
        help="cells per column width a for the OpenFOAM mesh study",
    )
    ap.add_argument("--no-parallel", action="store_true", help="skip the 2-rank runs")
    ap.add_argument("--nice", type=int, default=0)
    a = ap.parse_args(argv)
    if a.nice:
        os.nice(a.nice)
    steps = []
    t_all = time.perf_counter()

    def step(name, fn):
        t0 = time.perf_counter()
        fn()
        steps.append({"step": name, "wall_s": round(time.perf_counter() - t0, 1)})
        print(f"[run_all] {name}: {steps[-1]['wall_s']} s", flush=True)

    if a.only in (None, "openfoam"):
        from reference_cases.openfoam_dam_break_2d import run as F

        for n in a.meshes:
            step(f"openfoam dx{n} np1", lambda n=n: F.run_case(n, 1, keep_fields=False))
        if not a.no_parallel:
            n = min(a.meshes)
            step(f"openfoam dx{n} np2", lambda: F.run_case(n, 2, keep_fields=False))
    if a.only in (None, "seepage"):
        from reference_cases.openfoam_seepage_2d import run as P

        step("openfoam seepage (sheet pile, mesh study)", lambda: P.run_all())
    if a.only in (None, "nappe"):
        from reference_cases.openfoam_overflow_nappe import run as N

        for q in N.STUDY_Q:
            for dx in N.STUDY_DX_MM:
                step(
                    f"openfoam nappe q{q} dx{dx:.3g}mm",
                    lambda q=q, dx=dx: N.run_case(q, dx, keep_fields=False),
                )
    if a.only in (None, "impact"):
        from reference_cases.openfoam_lobovsky_impact import compare as LC
        from reference_cases.openfoam_lobovsky_impact import run as L

        for n, top, walls in L.STUDY:
            step(
                f"openfoam impact h{n} {top} {walls}",
                lambda n=n, t=top, w=walls: L.run_case(n, top=t, walls=w),
            )
        step("openfoam impact comparison", lambda: LC.main([]))
    if a.only in (None, "liggghts"):
        from reference_cases.liggghts_column_collapse_2d import calibrate as K
        from reference_cases.liggghts_column_collapse_2d import run as R

        step("liggghts calibration + reference + sensitivity", lambda: K.calibrate())
        if not a.no_parallel:

            def par():
                mus, mur = R.calibrated()
                R.run_collapse(R.Params(sliding=mus, rolling=mur), ranks=2, official=True)

            step("liggghts reference np2", par)

    total = round(time.perf_counter() - t_all, 1)
    record = {
        "date_utc": C.now_iso(),
        "argv": sys.argv[1:],
        "steps": steps,
        "total_wall_s": total,
        "host": C.host_facts(),
    }
    path = HERE / "run_all.json"
    data = json.loads(path.read_text()) if path.exists() else {}
    data[a.only or "all"] = record
    path.write_text(json.dumps(data, indent=2) + "\n")
    print(f"[run_all] total {total} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
