"""How the SPH failure line of the column collapse depends on its definition.

verification/column_collapse.py defines the SPH failure line (the boundary of Bui et al.'s
undisturbed zone) as, per initial row, the largest final x of the particles that moved less
than max(dx, 5 mm). The threshold is this project's choice: the experimental line was drawn on
the photograph of the final deposit (digitised data verification/data/bui2008_profile.csv). This
tabulates the RMS and signed x error against the experimental line for several thresholds,
with the boundary particle taken at its final or its initial position.

Input: an npz with x0, x (by particle id) and dx, as written by
verification/column_collapse_artificial_stress.py (positions_r{R}_eps{eps}.npz).

  python -m verification.column_collapse_failure_line verification/results/column_collapse/positions_r25_eps0.5.npz
"""

from __future__ import annotations

import sys

import numpy as np

from . import column_collapse as cc

THRESHOLDS = (0.001, 0.002, 0.003, 0.005, 0.010, 0.020)     # m


def boundary(x0, x, dx, threshold, initial=False):
    """Per initial row, the right-most particle that moved less than `threshold`, at its final
    (or initial) position, + dx/2; sorted by height."""
    moved = np.linalg.norm(x - x0, axis=1)
    pos = x0 if initial else x
    rows = np.round(x0[:, 1] / dx).astype(int)
    xs, ys = [], []
    for r in np.unique(rows):
        sel = (moved < threshold) & (rows == r)
        if sel.any():
            k = np.flatnonzero(sel)[np.argmax(pos[sel, 0])]
            xs.append(pos[k, 0] + 0.5 * dx)
            ys.append(pos[k, 1])
    o = np.argsort(ys)
    return np.array(xs)[o], np.array(ys)[o]


def table(x0, x, dx, thresholds=THRESHOLDS):
    fail = cc.load_reference()["failure_line"]
    rows = []
    for thr in thresholds:
        for initial in (False, True):
            fx, fy = boundary(x0, x, dx, thr, initial)
            err = np.interp(fail[:, 1], fy, fx) - fail[:, 0] if len(fx) > 1 else np.full(len(fail), np.nan)
            rows.append((thr, "initial" if initial else "final", float(np.sqrt(np.mean(err ** 2))), float(np.mean(err)), err))
    return rows


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    d = np.load(argv[0])
    x0, x, dx = d["x0"], d["x"], float(d["dx"])
    fail = cc.load_reference()["failure_line"]
    print(f"dx = {dx * 1000:g} mm; experimental heights (mm): {np.round(1000 * fail[:, 1]).astype(int).tolist()}")
    print("| threshold (mm) | position | RMS (mm) | mean (mm) | error per height (mm) |\n|---|---|---|---|---|")
    for thr, pos, rms, mean, err in table(x0, x, dx):
        print(f"| {thr * 1000:g} | {pos} | {rms * 1000:.1f} | {mean * 1000:+.1f} | {np.round(1000 * err).astype(int).tolist()} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
