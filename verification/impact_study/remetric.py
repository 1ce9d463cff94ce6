"""Recompute the impact case's metrics (verification.impact_pressure.metrics) from saved series.

python -m verification.impact_study.remetric RUN.npz ...   (c0 from the run's mat.sound_speed_factor)
"""

import json
import math
import sys

import numpy as np

from verification import impact_pressure as ip

KEYS = (
    "status",
    "reflections",
    "impact_s2",
    "peak_s2",
    "plateau_mean_s1",
    "plateau_mean_s2",
    "plateau_sd_s1",
    "plateau_sd_s2",
    "plateau_sd_1ms_s2",
)


def load(path):
    d = np.load(path)
    mat = json.loads(str(d["mat"])) if "mat" in d.files else {}
    c0 = mat.get("sound_speed_factor", 10.0) * math.sqrt(2 * ip.G * ip.H)
    return d, {
        "status": str(d["status"]),
        "reflections": int(d["reflections"]),
        "t_star": d["t_star"],
        "p_star": d["p_star"],
        "c0": c0,
    }


if __name__ == "__main__":
    for path in sys.argv[1:]:
        d, run = load(path)
        m = ip.metrics(run)
        print(path, {k: (round(m[k], 3) if isinstance(m.get(k), float) else m.get(k)) for k in KEYS})
