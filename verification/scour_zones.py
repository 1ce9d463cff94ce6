"""The nappe-zone scour depth of the scouring study (issue 11): d restricted to the part of the layer
the overflow nappe scours, leaving out the end-wall zone, where the outlet digs its own trough.

    python -m verification.scour_zones --from runs/scour_study --from MAIN_CHECKOUT/runs/scour_study
        # add the zone columns to every case in verification/results/scour/cases/ that lacks them,
        # from its run's scour_profiles.csv (copied to cases/<case>_profiles.csv)

Why. The whole-layer depth d(t) = max over x of (z_s0 - z_s) (solver/output/scour.py) is, from
about 0.9 s on, the depth of a trough against the end wall: the flow accelerates over the wall's
top into the outlet, the top soil row piles into a mound against the wall and a trough forms just
upstream of it (saturated runs; at q = 0.11 the mound leaves over the wall). In the 0.60 m layer
(docs/scour_long_layer.md) the trough sits at the same distance from the far wall, so it is the
wall's, not the nappe's.

The rule. d_nappe(t) = max(0, max over bins with centre FACE_ZONE <= x <= L - WALL_ZONE of
(z_s0 - z_s)), x measured from the caisson's face (the layer's upstream end, x = 0) and L the
layer's length (the end wall's face), and x_nappe where it is reached; d_face(t), the same over
x < FACE_ZONE, is kept beside it. WALL_ZONE = 0.10 m: in every 5 mm saturated run
of the study (0.25 m layer, q = 0.06-0.11, to 2-2.5 s) and in the 0.60 m layer, the surface change
after 0.5 s next to the end wall (trough and mound, |change| > 0.1 mm) reaches 0.065-0.080 m
upstream of the wall by 2 s at q <= 0.10 and in the 0.60 m layer, and 0.095 m at q = 0.11 in the
0.25 m layer (its hole widens upstream after the break-through); 0.10 m covers all of them. In the
0.25 m layer the nappe zone is then 0.03 <= x <= 0.15 m: it holds the nappe's landing (x = 0.06-0.10 m on
the rigid bed, docs/scour_setup.md sec. 6) and its first-impact dent (x = 0.03-0.13 m), and it is
docs/scour_long_layer.md's NAPPE_ZONE. The nappe's own influence (the first impact's ripple)
reaches 0.3 m in the 0.60 m layer, i.e. past the 0.25 m layer's wall zone, so the zone ends at the
wall zone, not before it. A deepest point on the zone's last bin (x_nappe >= L - WALL_ZONE - dx)
means the wall's trough may be reaching into the zone: `at_zone_edge` says so.

FACE_ZONE = 0.03 m: beside the caisson's face a bulge (x = 2.5 mm) and a dip (x = 12.5-22.5 mm)
form under a still pond with no inflow at all (verification/scour_face_dip.py; the pond's bed
changes nowhere else but at the end wall): the bodies' convex corners drive a spurious current
(up to 0.37 m/s within 15 mm of the caisson's corner, in water that should stay at rest), and the
pond's bed changes over x < 0.03 m only (0.16 mm bulge, 0.08 mm dip at 1 s, as large as the
flowing runs' at 1 s at five of six q). So the face zone is the body's, not the nappe's.
(corner9 fixed the corners: on its solver the pond's bed does not move and the saturated runs'
bulge is gone; the zone is kept as it was so that d_nappe compares across solvers, and d_face is
then mostly the first impact's ripple, docs/history/scour_study_history.md "The bodies' convex corners,
fixed".)

The zone columns are written into the study's copy of each run's scour.csv
(cases/<case>_scour.csv: depth_nappe_m, x_deepest_nappe_m, depth_face_m), computed from the run's surface
profiles (scour_profiles.csv, kept as cases/<case>_profiles.csv), after checking that those
profiles give the copy's whole-layer d at every time (so they are the same run's).
"""

from __future__ import annotations

import argparse
import csv
import shutil
import sys
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).with_name("results") / "scour"
CASES = RESULTS / "cases"
LONG_LAYER = RESULTS / "long_layer"  # where docs/scour_long_layer.md keeps the 0.60 m run's profiles
WALL_ZONE = 0.10  # m upstream of the end wall left out of d_nappe (module docstring: why 0.10)
FACE_ZONE = 0.03  # m beside the caisson's face left out of d_nappe (module docstring: why 0.03)
ZONE_COLUMNS = ("depth_nappe_m", "x_deepest_nappe_m", "depth_face_m")  # added to cases/<case>_scour.csv


def read_profiles(path):
    """(x bin centres, output times, z_s[bin, time]) from a scour_profiles.csv."""
    rows = list(csv.reader(open(path)))
    head = rows[0][1:]
    t = np.array([float(h.split("=", 1)[1].rstrip(")")) for h in head])
    a = np.array([[float(v) for v in r] for r in rows[1:]])
    return a[:, 0], t, a[:, 1:]


def layer_length(x):
    """The layer's length from its bin centres (bins dx wide from x = 0)."""
    return float(x[-1] + 0.5 * (x[1] - x[0]))


def zone_depth(x, z0, z, length, wall_zone=WALL_ZONE, face_zone=FACE_ZONE):
    """(d_nappe, x_nappe, d_face) of one profile z against the initial z0: the deepest drop over
    the bins with centre face_zone <= x <= length - wall_zone, where it is, and the deepest drop
    over the bins with x < face_zone (each 0 if the surface there has only risen)."""
    inside = (x >= face_zone - 1e-12) & (x <= length - wall_zone + 1e-12)
    drop = z0 - z
    k = int(np.argmax(drop[inside]))
    face = drop[x < face_zone - 1e-12]
    d_face = max(float(face.max()), 0.0) if len(face) else 0.0
    return max(float(drop[inside][k]), 0.0), float(x[inside][k]), d_face


def zone_series(x, t, z, length=None, wall_zone=WALL_ZONE, face_zone=FACE_ZONE):
    """d_nappe(t), x_nappe(t) and d_face(t) over every output time of a profiles table."""
    length = layer_length(x) if length is None else length
    d, xs, df = np.empty(len(t)), np.empty(len(t)), np.empty(len(t))
    for k in range(len(t)):
        d[k], xs[k], df[k] = zone_depth(x, z[:, 0], z[:, k], length, wall_zone, face_zone)
    return d, xs, df


def at_zone_edge(x_nappe, length, dx, wall_zone=WALL_ZONE):
    """True where the zone's deepest point is on its last bin (the wall's trough may reach in)."""
    return np.asarray(x_nappe) >= length - wall_zone - dx + 1e-12


def whole_layer_depth(z):
    """The solver's d(t) from a profiles table (solver/output/scour.py `measure`)."""
    return np.maximum((z[:, :1] - z).max(axis=0), 0.0)


def add_zone_columns(scour_csv, profiles_csv, wall_zone=WALL_ZONE, tol=2e-7):
    """Rewrite a study copy of scour.csv with the zone columns from the run's profiles; refuse
    (ValueError) profiles whose whole-layer d differs from the copy's depth_m at any time by more
    than `tol` m or than the profiles' own rounding, whichever is larger (they keep 6 significant
    digits of z: 0.1 um steps below z = 0.1 m, 1 um above, and a drop is the difference of two such
    values) or whose times differ."""
    rows = list(csv.DictReader(open(scour_csv)))
    x, t, z = read_profiles(profiles_csv)
    tol = max(tol, 2.0 * 10.0 ** (np.floor(np.log10(np.abs(z).max())) - 5))  # two rounded values
    ts = np.array([float(r["t_s"]) for r in rows])
    if len(ts) != len(t) or np.abs(ts - t).max() > 1e-6 * max(1.0, ts.max()):
        raise ValueError(f"{profiles_csv}: output times differ from {scour_csv}")
    d_copy = np.array([float(r["depth_m"]) for r in rows])
    gap = np.abs(whole_layer_depth(z) - d_copy).max()
    if gap > tol:
        raise ValueError(f"{profiles_csv}: its d differs from {scour_csv} by {gap:.3g} m (another run?)")
    d, xs, df = zone_series(x, t, z, wall_zone=wall_zone)
    fields = [k for k in rows[0] if k not in ZONE_COLUMNS] + list(ZONE_COLUMNS)
    for r, dn, xn, dfk in zip(rows, d, xs, df):
        r["depth_nappe_m"], r["x_deepest_nappe_m"], r["depth_face_m"] = f"{dn:.6g}", f"{xn:.6g}", f"{dfk:.6g}"
    with open(scour_csv, "w", newline="") as fh:
        w = csv.DictWriter(fh, fields)
        w.writeheader()
        w.writerows(rows)
    return d, xs, df


def keep_profiles(case, profiles_csv, cases=CASES):
    """The case's profiles as cases/<case>_profiles.csv (unless already kept there or in long_layer/);
    returns the kept path."""
    for kept in (cases / f"{case}_profiles.csv", LONG_LAYER / f"{case}_profiles.csv"):
        if kept.exists() and Path(profiles_csv).resolve() == kept.resolve():
            return kept
    dest = cases / f"{case}_profiles.csv"
    shutil.copyfile(profiles_csv, dest)
    return dest


def profile_candidates(case, sources, cases=CASES):
    """Where a case's profiles may be: kept beside it (cases/ or long_layer/) first, then
    <src>/<case>/scour_profiles.csv for each source (the first that matches the copy is used)."""
    paths = [cases / f"{case}_profiles.csv", LONG_LAYER / f"{case}_profiles.csv"]
    paths += [Path(s) / case / "scour_profiles.csv" for s in sources]
    return [p for p in paths if p.exists()]


def backfill(sources, cases=CASES, force=False):
    """Add the zone columns to every case copy in `cases` lacking them (or all, with force)."""
    done, missing = [], []
    for copy in sorted(cases.glob("*_scour.csv")):
        case = copy.name[: -len("_scour.csv")]
        have = next(csv.reader(open(copy)))
        if not force and all(k in have for k in ZONE_COLUMNS):
            continue
        for src in profile_candidates(case, sources, cases):
            try:
                add_zone_columns(copy, src)
            except ValueError:  # another run's profiles (an older run of the same case): try the next
                continue
            keep_profiles(case, src, cases)
            done.append(case)
            break
        else:
            missing.append(case)
    return done, missing


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.scour_zones", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    ap.add_argument("--from", dest="sources", action="append", default=[], metavar="DIR",
                    help="a directory with <case>/scour_profiles.csv (repeatable)")  # fmt: skip
    ap.add_argument("--force", action="store_true", help="recompute cases that have the columns")
    args = ap.parse_args(argv)
    runs = Path(__file__).resolve().parent.parent / "runs" / "scour_study"
    done, missing = backfill(args.sources or [runs], force=args.force)
    print(f"zone columns added: {', '.join(done) or 'none'}")
    if missing:
        print(f"no matching profiles for: {', '.join(missing)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
