"""The Lobovsky et al. (2014) dam-break impact, H = 300 mm, as a measurement: the tank's sensors, the
measured records, and the reduction of any wall-pressure record to the impact case's metrics.

The SPH case (verification/impact_pressure.py, whose docstring defines the metrics and their
tolerances) and the interFoam reference of the same tank (openfoam_lobovsky_impact/: run.py's manifest
metrics, corner.py, compare.py) reduce their records with these same functions, so that SPH,
experiment and reference pass through the same filter. The records are the files of
verification/data (README.md there), read as data; nothing here imports the verification package.
p* = p / (rho0 g H), t* = t sqrt(g / H).
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

# the experiment's records (verification/data, shipped with the verification package beside this one)
DATA = Path(__file__).resolve().parent.parent / "verification" / "data"
# the interFoam reference of the same tank: its manifest.json and data/
OPENFOAM_CASE = Path(__file__).resolve().parent / "openfoam_lobovsky_impact"

H = 0.3
G = 9.81
RHO0 = 1000.0
SENSORS_Y = (0.003, 0.015, 0.030, 0.080)  # m, sensor centres 1-4 (data README)
SAMPLE_RATE = 20000.0  # Hz, the sensors'
FILTER = 1.0e-3  # s, centred moving average applied to SPH and experiment alike
PLATEAU = (3.0, 5.5)
IMPACT_LEVEL = 0.5
TIME_SCALE = math.sqrt(H / G)
# t* about the impact time at sensor 2: the first-impact window of the pressure impulse and the acoustic peak
# (verification/impact_pressure.py, metric 5): from before the front reaches the lowest sensor to past the
# model's acoustic period 4H/c0 = 0.28 and the measured impact's duration (~0.45, Froude-scaled from the
# H = 600 mm medians)
IMPULSE_WINDOW = (-0.1, 0.5)


def _read_data(name):
    """Rows of one of the experiment's CSV files (comment lines starting with # skipped) as dicts."""
    with open(DATA / name) as fh:
        lines = [ln for ln in fh if not ln.startswith("#")]
    return list(csv.DictReader(lines))


def acoustic_window(c0):
    """tau_ac = 4 H / c0 (s): the period of the quarter-wave acoustic mode of a water layer of depth H,
    the slowest vertical mode of the model's artificially slow sound (verification/impact_pressure.py)."""
    return 4.0 * H / c0


def filtered(t_star, p_star, width_s=FILTER):
    """Interpolate to the sensors' 20 kHz and apply a centred moving average of width_s seconds
    (1 ms: the sensor-scale filter; acoustic_window(c0): the plateau's)."""
    dt_star = (1.0 / SAMPLE_RATE) / TIME_SCALE
    grid = np.arange(t_star[0], t_star[-1], dt_star)
    resampled = np.interp(grid, t_star, p_star)
    width = max(1, int(round(width_s * SAMPLE_RATE)))
    kernel = np.ones(width) / width
    # divided by the kernel's share inside the record: no pull toward 0 at the record's ends
    inside = np.convolve(np.ones_like(resampled), kernel, mode="same")
    return grid, np.convolve(resampled, kernel, mode="same") / inside, resampled


def impact_time(t_star, p_star):
    above = np.flatnonzero(p_star > IMPACT_LEVEL)
    return float(t_star[above[0]]) if len(above) else float("nan")


def window_mean_sd(t_star, p_star):
    w = (t_star >= PLATEAU[0]) & (t_star <= PLATEAU[1])
    return float(np.mean(p_star[w])), float(np.std(p_star[w]))


def experiment():
    """Event 5 per sensor (t*, p*), the sensor-2 band (t*, lo, median, hi) and Table 2 peaks."""
    events = []
    for s in range(1, 5):
        rows = _read_data(f"lobovsky2014_h300_event5_sensor{s}.csv")
        events.append(
            (np.array([float(r["t_star"]) for r in rows]), np.array([float(r["p_star"]) for r in rows]))
        )
    rows = _read_data("lobovsky2014_h300_sensor2_percentiles.csv")
    band = tuple(np.array([float(r[k]) for r in rows]) for k in ("t_star", "p2_5", "median", "p97_5"))
    rho_g_h_mbar = RHO0 * G * H / 100.0
    peaks = [
        {k: float(r[k]) / rho_g_h_mbar for k in ("median_mbar", "p2_5_mbar", "p97_5_mbar")}
        for r in _read_data("lobovsky2014_h300_peak_statistics.csv")
    ]
    return events, band, peaks


def openfoam_reference():
    """{run label: {"cells_per_H", "top", "walls", "t_star", "p_star"[n, 4]}} of every interFoam run the
    reference case's manifest lists (reference_cases/openfoam_lobovsky_impact). Missing files are an
    error, never a silently dropped comparison."""
    manifest = OPENFOAM_CASE / "manifest.json"
    if not manifest.is_file():
        raise FileNotFoundError(f"OpenFOAM reference manifest missing: {manifest}")
    out = {}
    for label, r in json.loads(manifest.read_text())["runs"].items():
        path = OPENFOAM_CASE / "data" / Path(r["outputs"]["sensors"]).name
        if not path.is_file():
            raise FileNotFoundError(f"OpenFOAM reference data missing (listed in {manifest}): {path}")
        arr = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
        out[label] = {k: r[k] for k in ("cells_per_H", "top", "walls")}
        out[label].update(t_star=arr[:, 1], p_star=arr[:, 2:6])
    return out


def band_statistics(band, c0=None):
    """The sensor-2 band's numbers for the checks. With c0 (the model's sound speed, for the acoustic
    filter) also the first-impact impulse and acoustic peak of its 2.5 %, median and 97.5 % curves, each
    with the window at the median curve's impact time. Those are statistics of per-sample percentiles,
    not percentiles of the repetitions' impulses (not published in the files here): averaging over the
    window narrows a spread that is independent between samples, so the band's spread bounds the
    repetitions' from above (a lenient tolerance, stated where it is used)."""
    t, lo, med, hi = band
    w = (t >= PLATEAU[0]) & (t <= PLATEAU[1])
    out = {
        "impact_earliest": impact_time(t, hi),
        "impact_latest": impact_time(t, lo),
        "plateau_median": float(np.mean(med[w])),
        "plateau_half_width": float(0.5 * np.mean(hi[w] - lo[w])),
    }
    if c0 is not None:
        t_impact = impact_time(*filtered(t, med)[:2])
        for name, curve in (("lo", lo), ("median", med), ("hi", hi)):
            grid, f, _ = filtered(t, curve)
            out[f"impulse_{name}"] = impulse(grid, f, t_impact)
            grid_ac, f_ac, _ = filtered(t, curve, acoustic_window(c0))
            out[f"peak_ac_{name}"] = acoustic_peak(grid_ac, f_ac, t_impact)
    return out


def impact_window(t_star, t_impact):
    """The samples of the first-impact window IMPULSE_WINDOW about t_impact (t*)."""
    return (t_star >= t_impact + IMPULSE_WINDOW[0]) & (t_star <= t_impact + IMPULSE_WINDOW[1])


def impulse(t_star, p_star, t_impact):
    """Pressure impulse of the first impact, int p* dt* over IMPULSE_WINDOW about t_impact
    (verification/impact_pressure.py, metric 5); nan if the record does not cover the window."""
    if not np.isfinite(t_impact) or t_star[-1] < t_impact + IMPULSE_WINDOW[1] - 1e-9:
        return float("nan")
    w = impact_window(t_star, t_impact)
    return float(np.trapezoid(p_star[w], t_star[w]))


def acoustic_peak(t_star, p_star_ac, t_impact):
    """The largest acoustically filtered p* in the first-impact window (verification/impact_pressure.py,
    metric 5)."""
    if not np.isfinite(t_impact) or t_star[-1] < t_impact + IMPULSE_WINDOW[1] - 1e-9:
        return float("nan")
    return float(p_star_ac[impact_window(t_star, t_impact)].max())


def metrics(run):
    """The case's numbers from a simulate() result: impact time, peaks and the first-impact pressure
    impulse from the 1 ms-filtered series; plateau mean and sd and the first-impact peak after the
    acoustic filter (tau_ac = 4 H / c0), and the 1 ms-filtered plateau sd beside it (reported, not
    checked). The impulse window is placed at each record's own impact time at sensor 2."""
    out = {"status": run["status"], "reflections": run["reflections"]}
    t, p = run["t_star"], run["p_star"]
    if len(t) < 2:
        return out
    tau_ac = acoustic_window(run["c0"])
    out["acoustic_window_s"] = tau_ac
    t_impact = impact_time(*filtered(t, p[:, 1])[:2])
    for k in range(len(SENSORS_Y)):
        grid, f, raw = filtered(t, p[:, k])
        grid_ac, f_ac, _ = filtered(t, p[:, k], tau_ac)
        out[f"impact_s{k + 1}"] = impact_time(grid, f)
        out[f"peak_s{k + 1}"] = float(f.max())
        out[f"peak_raw_s{k + 1}"] = float(raw.max())
        out[f"impulse_s{k + 1}"] = impulse(grid, f, t_impact)
        out[f"peak_ac_s{k + 1}"] = acoustic_peak(grid_ac, f_ac, t_impact)
        if grid[-1] >= PLATEAU[1] - 1e-9:
            out[f"plateau_sd_1ms_s{k + 1}"] = window_mean_sd(grid, f)[1]
            out[f"plateau_mean_s{k + 1}"], out[f"plateau_sd_s{k + 1}"] = window_mean_sd(grid_ac, f_ac)
    return out
