"""Write verification/results/impact_pressure/study.{csv,md} and the figures from saved series of
verification/impact_study/series.py (the same simulate() as `python -m verification.impact_pressure --study`,
run one resolution at a time so the runs could share the loaded host with other work).

python -m verification.impact_study.study_from_series RUN_R20.npz RUN_R40.npz [RUN_R80.npz]
"""

import sys

from verification import impact_pressure as ip
from verification.common import save_study, timing_note
from verification.impact_study.remetric import load

KEYS = ip.STUDY_KEYS


def main():
    out = ip.RESULTS / "impact_pressure"
    events, band, _ = ip.experiment()
    rows = []
    for path in sys.argv[1:]:
        d, run = load(path)
        m = ip.metrics(run)
        res = int(round((int(d["particles"]) / 2) ** 0.5))  # the column is 2H x H: 2 R^2 particles
        row = {
            "resolution": res,
            "particles": int(d["particles"]),
            "steps": int(d["steps"]),
            "wall_s": round(float(d["wall"]), 1),
            "cpu_s": round(float(d["cpu"]), 1),
        }
        row.update({k: m.get(k, float("nan")) for k in KEYS})
        rows.append(row)
        ip.plot(run, events, band, out / f"impact_pressure_r{res}.png")
    save_study(
        rows,
        out,
        "study",
        note=timing_note(
            "NUMBA_NUM_THREADS=1 python -m verification.impact_pressure "
            "--study (here: verification/impact_study/series.py per resolution, "
            "then verification/impact_study/study_from_series.py)"
        ),
    )


if __name__ == "__main__":
    main()
