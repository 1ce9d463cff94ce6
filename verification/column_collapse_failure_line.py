"""How the SPH failure line of the column collapse depends on its definition.

verification/column_collapse.py defines the SPH failure line (the boundary of Bui et al.'s
undisturbed zone) as, per initial row, the largest final x of the particles that moved less
than max(dx, 5 mm). The threshold is this project's choice: the experimental line was drawn on
the photograph of the final deposit (digitised data verification/data/bui2008_profile.csv). This
tabulates the RMS and signed x error against the experimental line for several thresholds,
with the boundary particle taken at its final or its initial position.

Strain-based variant (`strain_table`): the displacement threshold counts a rigidly translated
block as disturbed. Per particle, the deformation gradient from the initial to the final
positions, F = (sum_j (x_j - x_i) (x) gradW_ij) (sum_j (X_j - X_i) (x) gradW_ij)^-1, with the
cubic-spline gradient on the initial configuration (h = 1.3 dx) and the normalised
(Bonet & Lok 1999 style) correction, so that any linear map is reproduced exactly, also at free
surfaces; Green strain E = (F^T F - I)/2; plane-strain (E_zz = 0) equivalent deviatoric shear
strain gamma = sqrt(2 dev(E):dev(E)) (= g for a small simple shear g). Per initial row, the
undisturbed zone is the contiguous run of particles from the left wall with gamma < threshold;
the boundary is its right-most particle's final x + dx/2. Rows here are floor(y0 / dx) (one
lattice row each).

Input: an npz with x0, x (by particle id) and dx, as written by
verification/column_collapse_artificial_stress.py (positions_r{R}_eps{eps}.npz).

  python -m verification.column_collapse_failure_line
  verification/results/column_collapse/positions_r25_eps0.5.npz
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from . import column_collapse as cc

THRESHOLDS = (0.001, 0.002, 0.003, 0.005, 0.010, 0.020)  # m
STRAIN_THRESHOLDS = (0.01, 0.02, 0.05, 0.1, 0.2, 0.5)  # equivalent shear strain gamma
H_OVER_DX = 1.3  # solver default (defaults.toml numerics.h_over_dx)


def boundary(x0, x, dx, threshold, initial=False):
    """The displacement-threshold line of verification/column_collapse.py, with the boundary
    particle at its final (or initial) position."""
    return cc.failure_line(x0, x, dx, threshold, at_initial=initial)


def table(x0, x, dx, thresholds=THRESHOLDS):
    fail = cc.load_reference()["failure_line"]
    rows = []
    for thr in thresholds:
        for initial in (False, True):
            fx, fy = boundary(x0, x, dx, thr, initial)
            err = np.interp(fail[:, 1], fy, fx) - fail[:, 0] if len(fx) > 1 else np.full(len(fail), np.nan)
            rows.append(
                (
                    thr,
                    "initial" if initial else "final",
                    float(np.sqrt(np.mean(err**2))),
                    float(np.mean(err)),
                    err,
                )
            )
    return rows


def pairs(X, radius):
    """All ordered pairs (i, j), i != j, with |X_i - X_j| < radius: a cell (bucket) search."""
    cell = np.floor((X - X.min(axis=0)) / radius).astype(np.int64)
    nx = int(cell[:, 0].max()) + 3
    key = (cell[:, 1] + 1) * nx + cell[:, 0] + 1
    order = np.argsort(key, kind="stable")
    skey = key[order]
    rows_i, rows_j = [], []
    for oy in (-1, 0, 1):
        for ox in (-1, 0, 1):
            target = key + oy * nx + ox
            lo, hi = np.searchsorted(skey, target, "left"), np.searchsorted(skey, target, "right")
            cnt = hi - lo
            i = np.repeat(np.arange(len(X)), cnt)
            first = np.cumsum(cnt) - cnt  # where each i's block starts in the output
            j = order[np.repeat(lo, cnt) + np.arange(cnt.sum()) - np.repeat(first, cnt)]
            rows_i.append(i)
            rows_j.append(j)
    i, j = np.concatenate(rows_i), np.concatenate(rows_j)
    keep = (i != j) & (np.sum((X[i] - X[j]) ** 2, axis=1) < radius * radius)
    return i[keep], j[keep]


def deformation_gradient(x0, x, dx, h_over_dx=H_OVER_DX):
    """Corrected SPH deformation gradient per particle (2D), gradients on the initial configuration."""
    h = h_over_dx * dx
    i, j = pairs(x0, 2.0 * h)
    dX = x0[j] - x0[i]
    r = np.linalg.norm(dX, axis=1)
    R = r / h
    dwdr = (
        -0.5 * np.clip(2.0 - R, 0.0, None) ** 2 + 2.0 * np.clip(1.0 - R, 0.0, None) ** 2
    ) / h  # cubic spline, unnormalised
    grad = (dwdr / r)[:, None] * (-dX)  # grad_i W(X_i - X_j)
    n = len(x0)
    A = np.zeros((n, 2, 2))
    B = np.zeros((n, 2, 2))
    np.add.at(A, i, (x[j] - x[i])[:, :, None] * grad[:, None, :])
    np.add.at(B, i, dX[:, :, None] * grad[:, None, :])
    return A @ np.linalg.inv(B)


def shear_strain(F):
    """Plane-strain equivalent deviatoric Green shear strain sqrt(2 dev(E):dev(E)), E_zz = 0."""
    E = 0.5 * (np.swapaxes(F, 1, 2) @ F - np.eye(2))
    m = (E[:, 0, 0] + E[:, 1, 1]) / 3.0
    dxx, dyy, dzz, exy = E[:, 0, 0] - m, E[:, 1, 1] - m, -m, 0.5 * (E[:, 0, 1] + E[:, 1, 0])
    return np.sqrt(2.0 * (dxx**2 + dyy**2 + dzz**2 + 2.0 * exy**2))


def strain_boundary(x0, x, dx, gamma, threshold):
    """Per initial row (floor(y0/dx)), the contiguous run from the left wall with gamma <
    threshold; its right-most particle's final x + dx/2 (and final y); sorted by height."""
    rows = np.floor(x0[:, 1] / dx).astype(int)
    xs, ys = [], []
    for r in np.unique(rows):
        idx = np.flatnonzero(rows == r)
        idx = idx[np.argsort(x0[idx, 0])]
        ok = gamma[idx] < threshold
        run = len(ok) if ok.all() else int(np.argmin(ok))
        if run:
            k = idx[run - 1]
            xs.append(x[k, 0] + 0.5 * dx)
            ys.append(x[k, 1])
    o = np.argsort(ys)
    return np.array(xs)[o], np.array(ys)[o]


def strain_table(x0, x, dx, thresholds=STRAIN_THRESHOLDS):
    fail = cc.load_reference()["failure_line"]
    gamma = shear_strain(deformation_gradient(x0, x, dx))
    rows = []
    for thr in thresholds:
        fx, fy = strain_boundary(x0, x, dx, gamma, thr)
        err = np.interp(fail[:, 1], fy, fx) - fail[:, 0] if len(fx) > 1 else np.full(len(fail), np.nan)
        rows.append((thr, float(np.sqrt(np.mean(err**2))), float(np.mean(err)), err))
    return rows


def main(argv=None):
    from .common import script_parser

    parser = script_parser(sys.modules[__name__])
    parser.add_argument("positions", help="an .npz with x0, x (initial and final positions) and dx")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if not Path(args.positions).is_file():
        parser.error(f"argument positions: {args.positions}: no such file")
    d = np.load(args.positions)
    x0, x, dx = d["x0"], d["x"], float(d["dx"])
    fail = cc.load_reference()["failure_line"]
    print(
        f"dx = {dx * 1000:g} mm; experimental heights (mm): "
        f"{np.round(1000 * fail[:, 1]).astype(int).tolist()}"
    )
    print(
        "| threshold (mm) | position | RMS (mm) | mean (mm) | error per height (mm) |\n|---|---|---|---|---|"
    )
    for thr, pos, rms, mean, err in table(x0, x, dx):
        print(
            f"| {thr * 1000:g} | {pos} | {rms * 1000:.1f} | {mean * 1000:+.1f} | "
            f"{np.round(1000 * err).astype(int).tolist()} |"
        )
    print(
        "\nStrain-based undisturbed zone (contiguous from the left wall, gamma < threshold; boundary at "
        "final x):"
    )
    print("| gamma threshold | RMS (mm) | mean (mm) | error per height (mm) |\n|---|---|---|---|")
    for thr, rms, mean, err in strain_table(x0, x, dx):
        print(
            f"| {thr:g} | {rms * 1000:.1f} | {mean * 1000:+.1f} | "
            f"{np.round(1000 * err).astype(int).tolist()} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
