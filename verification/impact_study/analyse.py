"""Plateau statistics of saved series: sd, sd about a cubic trend, dominant frequencies, the bulk's
correlation with the sensor, and the plateau sd after moving averages of several widths.

python -m verification.impact_study.analyse RUN.npz [RUN.npz ...]
"""

import sys

import numpy as np

from verification import impact_pressure as ip

W_SCALE = np.sqrt(9.81 / 0.3)


def main():
    for path in sys.argv[1:]:
        d = np.load(path)
        t, p = d["t_star"], d["p_star"]
        if len(t) < 10:
            print(path, str(d["status"]))
            continue
        g, f, raw = ip.filtered(t, p[:, 1])
        w = (g >= 3) & (g <= 5.5)
        c = np.polyfit(g[w], f[w], 3)
        r = f[w] - np.polyval(c, g[w])
        dt = g[1] - g[0]
        spec = np.abs(np.fft.rfft(r * np.hanning(len(r))))
        fr = np.fft.rfftfreq(len(r), dt) * W_SCALE
        top = fr[np.argsort(spec)[::-1][:3]]
        line = (
            f"{path}: {str(d['status'])[:30]}, refl {int(d['reflections'])}, steps {int(d['steps'])}, "
            f"cpu {float(d['cpu']):.0f} s; s2 mean {f[w].mean():.3f} sd {f[w].std():.3f} "
            f"(about cubic {r.std():.3f}); top Hz {np.round(top).astype(int)}"
        )
        if "bulk" in d.files and len(d["bulk"]) == len(t):
            gb = np.interp(g, t, d["bulk"])
            wb = gb[w] - np.polyval(np.polyfit(g[w], gb[w], 3), g[w])
            line += f"; bulk sd {wb.std():.3f}, corr {np.corrcoef(wb, r)[0, 1]:.2f}"
        sds = []
        for tau in (0.001, 0.005, 0.01, 0.02, 0.05):
            width = max(1, int(round(tau * ip.SAMPLE_RATE)))
            ff = np.convolve(np.interp(g, t, p[:, 1]), np.ones(width) / width, mode="same")
            sds.append(f"{tau * 1000:g}ms {ff[w].std():.3f}")
        print(line + "; sd after " + ", ".join(sds))


if __name__ == "__main__":
    main()
