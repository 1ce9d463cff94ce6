"""Column collapse (Bui et al. 2008) with the equilibrium image stress against the seed's mirror.

`numerics.image_pressure = "hydrostatic"` gives soil images the static increment of the normal
stress along gravity (solver/physics/boundary.py::add_equilibrium_image_stress), where seed
eq. (23) gives them their source's stress. This runs the collapse scene at the resolution
study's spacings with the option and sets the results beside the committed default study
(resolution_study.csv): runout, failure-line and profile RMS, kinetic energy at the end, wall
time. Writes verification/results/column_collapse/equilibrium_images.md and .csv.

  NUMBA_NUM_THREADS=1 python -m verification.column_collapse_images
"""

from __future__ import annotations

import csv
import os

from . import column_collapse as cc
from .common import machine_load, write_csv

OPTION = {"numerics": {"image_pressure": "hydrostatic"}}
FIELDS = (
    "resolution",
    "spacing_mm",
    "runout_mirror_m",
    "runout_equilibrium_m",
    "failure_rms_mirror_mm",
    "failure_rms_equilibrium_mm",
    "profile_rms_equilibrium_mm",
    "ke_final_over_peak_equilibrium",
    "wall_time_mirror_s",
    "wall_time_equilibrium_s",
)


def rows(resolutions=cc.STUDY_RESOLUTIONS):
    with open(cc.STUDY_FILE) as fh:
        mirror = {int(r["resolution"]): r for r in csv.DictReader(fh)}
    out = []
    for res in resolutions:
        r = cc.run(res, overrides=OPTION)
        s, m = r.series, mirror[res]
        out.append(
            {
                "resolution": res,
                "spacing_mm": 1000 * cc.spacing(res),
                "runout_mirror_m": float(m["runout_m"]),
                "runout_equilibrium_m": s["runout"],
                "failure_rms_mirror_mm": float(m["failure_rms_mm"]),
                "failure_rms_equilibrium_mm": 1000 * s["failure_rms"],
                "profile_rms_equilibrium_mm": 1000 * s["profile_rms"],
                "ke_final_over_peak_equilibrium": s["ke_final_over_peak"],
                "wall_time_mirror_s": float(m["wall_time_s"]),
                "wall_time_equilibrium_s": r.wall_time,
            }
        )
        print(out[-1], flush=True)
    return out


def write(table, out=cc.OUT):
    write_csv(out / "equilibrium_images.csv", table, FIELDS)
    lines = [
        "| dx (mm) | runout, mirror (m) | runout, equilibrium (m) | failure-line RMS, mirror (mm) | "
        "failure-line RMS, equilibrium (mm) | profile RMS, equilibrium (mm) | KE final/peak, equilibrium | "
        "wall time, mirror / equilibrium (s) |",
        "|" + "---|" * 8,
    ]
    for r in table:
        lines.append(
            f"| {r['spacing_mm']:g} | {r['runout_mirror_m']:.4f} | {r['runout_equilibrium_m']:.4f} | "
            f"{r['failure_rms_mirror_mm']:.1f} | {r['failure_rms_equilibrium_mm']:.1f} | "
            f"{r['profile_rms_equilibrium_mm']:.1f} | {r['ke_final_over_peak_equilibrium']:.1e} | "
            f"{r['wall_time_mirror_s']:.0f} / {r['wall_time_equilibrium_s']:.0f} |"
        )
    text = (
        "# Column collapse: equilibrium image stress against the seed's mirror images\n\n"
        "Mirror columns: the committed resolution study (resolution_study.csv). Wall time: stepping only, "
        "one "
        f"process, NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'default')}, {machine_load()}.\n"
        "Reproduce: `NUMBA_NUM_THREADS=1 python -m verification.column_collapse_images`\n\n"
        + "\n".join(lines)
        + "\n"
    )
    (out / "equilibrium_images.md").write_text(text)
    print(text)


if __name__ == "__main__":
    import sys

    from .common import script_parser

    script_parser(sys.modules[__name__]).parse_args()
    write(rows())
