"""Share of the plateau variance (sensor 2, t* 3-5.5, 20 kHz resampled, no filter) per frequency band.

python -m verification.impact_study.bands RUN.npz ... [exp]
"""

import sys

import numpy as np

from verification import impact_pressure as ip

EDGES = (0, 10, 30, 60, 120, 250, 500, 1000, 1e9)


def bands(t, p):
    dt = (1.0 / ip.SAMPLE_RATE) / ip.TIME_SCALE
    g = np.arange(t[0], t[-1], dt)
    x = np.interp(g, t, p)
    w = (g >= 3) & (g <= 5.5)
    x = x[w] - x[w].mean()
    spec = np.abs(np.fft.rfft(x)) ** 2
    fr = np.fft.rfftfreq(len(x), 1.0 / ip.SAMPLE_RATE)
    total = spec[1:].sum()
    out = []
    for lo, hi in zip(EDGES[:-1], EDGES[1:]):
        m = (fr > lo) & (fr <= hi)
        out.append(f"{lo:g}-{hi:g} Hz: {np.sqrt(spec[m].sum() / total) * x.std():.3f}")
    return f"sd {x.std():.3f}; sd per band " + ", ".join(out)


for a in sys.argv[1:]:
    if a == "exp":
        ev, _, _ = ip.experiment()
        print("experiment event 5 s2:", bands(*ev[1]))
    else:
        d = np.load(a)
        print(a, bands(d["t_star"], d["p_star"][:, 1]))
