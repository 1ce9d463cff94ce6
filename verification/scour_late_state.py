"""The late state of a saturated scour run (docs/history/scour_study_history.md, "What the runs show"): the
mound
against the end wall, the trough upstream of it, the pore water's drift and the soil's and pore water's
speeds, from a study run's outputs in runs/scour_study/<case>/ (scour.csv, scour_profiles.csv, particles.h5).

    python -m verification.scour_late_state saturated_q0.11_dx5mm [--times 1 2] [--figure PNG]

--figure: the particles next to the end wall at those times (soil coloured by speed, pore and free water
pale blue), a close-up of what the late d measures.

Pore water: the water particles inside the layer (0 <= x <= length, z < the surface) at t = 0, followed
by id. The mound: z_s(x, t) - z_s(x, 0) at the last profile column before the end wall.
"""

from __future__ import annotations

import argparse
import csv
import sys

import numpy as np

from verification.scour_study import RUNS

SURFACE = 0.095  # m, the layer's initial top (scenes/scour_*.toml)
LATE = 0.5  # s: after the first impact (its soil speeds are cm/s); the late creep's maximum is from here on
WATER = 0  # material id of water: the scour scenes list [materials.water] first


def profiles(run):
    """(x, {t: z_s(x, t)}) from scour_profiles.csv."""
    with open(run / "scour_profiles.csv") as fh:
        rows = list(csv.reader(fh))
    head = rows[0][1:]
    times = [float(h.split("=")[1].rstrip(")")) for h in head]
    data = np.array([[float(v) for v in r] for r in rows[1:]])
    return data[:, 0], {t: data[:, k + 1] for k, t in enumerate(times)}


def nearest(series, t):
    k = int(np.argmin([abs(s[0] - t) for s in series]))
    return series[k]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("case")
    p.add_argument("--times", type=float, nargs="+", default=[1.0, 2.0])
    p.add_argument("--length", type=float, default=0.25)
    p.add_argument("--figure", help="write the end-wall close-up at --times to this PNG")
    a = p.parse_args(argv)
    run = RUNS / a.case
    if not (run / "particles.h5").exists():
        print(f"{run}: no particles.h5 (run the case first)", file=sys.stderr)
        return 2
    from solver.output.hdf5_writer import read_series

    x, zs = profiles(run)
    series = read_series(run / "particles.h5")
    t0, s0 = series[0]
    water = WATER
    m0, p0 = s0["material"], s0["position"]
    pore = (m0 == water) & (p0[:, 0] >= 0) & (p0[:, 0] <= a.length) & (p0[:, 1] < SURFACE)
    pore_ids = s0["id"][pore]
    start = dict(zip(s0["id"][pore], p0[pore]))
    depth = {float(r["t_s"]): r for r in csv.DictReader(open(run / "scour.csv"))}
    last = int(np.argmax(x[x < a.length]))
    print(f"{a.case}: {pore.sum()} pore-water particles at t = 0; mound column x = {x[last]:.4f} m")
    for t in a.times:
        tz = min(zs, key=lambda s: abs(s - t))
        ts, snap = nearest(series, t)
        r = depth[min(depth, key=lambda s: abs(s - t))]
        ids, pos, vel, mat = snap["id"], snap["position"], snap["velocity"], snap["material"]
        speed = np.linalg.norm(vel, axis=1)
        inpore = np.isin(ids, pore_ids)
        disp = np.array([np.linalg.norm(pos[k] - start[i]) for k, i in enumerate(ids) if inpore[k]])
        soil = mat != water
        upto = max([0.0] + [float(np.linalg.norm(v["velocity"][v["material"] != water], axis=1).max())
                   for tt, v in series if LATE <= tt <= ts + 1e-9])  # fmt: skip
        deep = inpore & (pos[:, 1] < 0.05)
        print(
            f"t = {ts:g} s: d = {1e3 * float(r['depth_m']):.2f} mm at x = {float(r['x_deepest_m']):.4f} m,"
            f" eroded {1e4 * float(r['eroded_area_m2']):.3f} cm2;"
            f" mound {1e3 * (zs[tz][last] - zs[0.0][last]):.2f}"
            f" mm (profile t = {tz:g}); pore water: {inpore.sum()} left, mean displacement"
            f" {1e3 * disp.mean():.2f} mm, {int((disp > 0.0025).sum())} moved > dx/2, max speed"
            f" {speed[inpore].max():.3f} m/s ({speed[deep].max() if deep.any() else float('nan'):.4f} below"
            f" z = 0.05 m); soil particles gone (outlet) {int((m0 != water).sum() - soil.sum())};"
            f" soil max speed {speed[soil].max():.4f} m/s (max over {LATE:g} s to t: {upto:.4f})"
        )
    if a.figure:
        end_wall_figure(series, a.times, a.length, a.case, a.figure)
    return 0


def end_wall_figure(series, times, length, case, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(
        len(times), 1, figsize=(8, 1.9 * len(times)), squeeze=False, sharex=True, layout="constrained"
    )
    for ax, t in zip(axes[:, 0], times):
        ts, snap = nearest(series, t)
        pos, mat = snap["position"], snap["material"]
        speed = np.linalg.norm(snap["velocity"], axis=1)
        w = mat == WATER
        ax.scatter(pos[w, 0], pos[w, 1], s=5, c="tab:blue", alpha=0.35, lw=0)
        sc = ax.scatter(pos[~w, 0], pos[~w, 1], s=9, c=speed[~w], cmap="inferno", vmin=0, vmax=0.1, lw=0)
        ax.axvline(length, color="k", lw=0.6)
        ax.axhline(SURFACE, color="k", lw=0.6, ls=":")
        ax.set_xlim(length - 0.1, length + 0.03)
        ax.set_ylim(SURFACE - 0.035, SURFACE + 0.03)
        ax.set_aspect("equal")
        ax.text(0.01, 0.9, f"{case}, t = {ts:g} s", transform=ax.transAxes, fontsize=8)
    fig.colorbar(sc, ax=axes[:, 0], shrink=0.5, label="soil speed (m/s)")
    axes[-1, 0].set_xlabel("x (m); end wall at the solid line, initial surface dotted")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"figure: {path}")


if __name__ == "__main__":
    sys.exit(main())
