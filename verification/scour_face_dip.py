"""The dip beside the caisson's face (docs/history/scour_study_history.md): the flow's, or a residue of the
body
images at the caisson's corner?

In the saturated study runs a dip forms at x = 0.0175 m beside a bulge against the caisson's face
(x = 0.0025 m); at q = 0.09 it is the deepest point at 2 s (0.64 mm). The first study's defect was
there: the images of the overflow above the crown, mirrored across the crown's line or through its
corner (0, 0.105), reached the pore water below the crown and compressed it
(docs/history/scour_study_history.md,
"What was wrong"); prune_behind_mirrors (solver/physics/bodies.py) removed the pairs that see an
image from behind its mirror line. That rule drove a current at the convex corners in still water;
corner9 replaced it by prune_to_own_region (each particle sees only the images of its own edge
strip or corner wedge). `images` replays the old rule (the runs it was written for); `pond --label`
keeps a run of another solver beside the old one. Three looks:

  images   from a study run's HDF5 series: at every output time, the caisson's corner and crown
           images of the water (the solver's own rules: BodyGeometry, the corner's wedge, the
           edges' feet, reach 2h) and which of them reach a pore-water or soil particle after the
           pruning. The caisson's face images (x = 0) are left out: a plain free-slip mirror, as a
           box wall's.
  near     the same series: the top soil rows within 0.035 m of the face (displacement since t = 0),
           the water just above the bed (z < crown) by x (mean horizontal velocity, time-averaged)
           and the top pore water's pressure by x.
  pond     a run: the same saturated layer, caisson and end wall under a still pond up to z = 0.2 m
           (no inlet, no outlet, the water table at the pond's surface, x_max closed), to --end; the
           surface profile and the top rows' displacement beside the face, against the flowing run
           at the same time. A dip without the flow would be the face's or its images'; none means
           it needs the flow.

    python -m verification.scour_face_dip images saturated_q0.09_dx5mm
    python -m verification.scour_face_dip near saturated_q0.09_dx5mm --from 0.5 --to 2.0
    nice -n 10 python -m verification.scour_face_dip pond --end 1.0      # runs/scour_face_dip/pond_dx5mm
    nice -n 10 python -m verification.scour_face_dip pond --end 0.5 --label corner9   # ..._corner9
    nice -n 10 python -m verification.scour_face_dip pond --end 0.1 --without no_corner_images   # experiment
    python -m verification.scour_face_dip compare saturated_q0.09_dx5mm --at 1.0

Each command prints its table and writes it as JSON to verification/results/scour/face_dip/.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

from verification.scour_study import ROOT, RUNS, SCENES

OUT = Path(__file__).with_name("results") / "scour" / "face_dip"
POND_RUNS = ROOT / "runs" / "scour_face_dip"
SURFACE = 0.095  # m, the layer's top (scenes/scour_*.toml)
CROWN = 0.105  # m, the caisson's crown
POND_TOP = 0.20  # m: about the flowing runs' water level near the caisson (crown + y_c = 0.21 at q = 0.11)
NEAR = 0.035  # m from the face: the bulge (0.0025 m) and the dip (0.0125-0.0225 m) with a spacing to spare
WATER, SAND = 0, 1  # material ids: the scour scenes list [materials.water] first


def _series(case, root=RUNS):
    from solver.output.hdf5_writer import read_series

    return read_series(Path(root) / case / "particles.h5")


def _pore_ids(first):
    """The pore water: water particles inside the layer at t = 0, followed by id."""
    return np.sort(first["id"][(first["material"] == WATER) & (first["position"][:, 1] < SURFACE)])


def images(case, t_from=0.02):
    """Pairs (pore-water target, caisson corner/crown image of water) within 2h, before and after
    the pruning, summed over the output times from t_from on; the last time any is kept and the
    lowest target kept. Soil sees only soil images: the soil particles that could have corner or
    crown images (above the crown's level, within reach of the face) are counted."""
    from solver.physics.bodies import BodyGeometry
    from solver.scene import load_scene

    scene = load_scene(RUNS / case / "scene.toml")
    g = BodyGeometry(scene)
    reach = 2.0 * scene.h
    caisson = g.names.index("breakwater")
    series = _series(case)
    pore_ids = _pore_ids(series[0][1])
    tally = {}
    last_kept = {}
    for t, f in series:
        if t < t_from - 1e-12:
            continue
        x, mat, ids = f["position"], f["material"], f["id"]
        water = mat == WATER
        pore = water & np.isin(ids, pore_ids)
        imgs = []  # (kind, source, image) of the caisson's corner and crown edge (water sources)
        for c, ti, to in zip(g.corner, g.t_in, g.t_out):
            if not (abs(c[0]) < 1e-12 and abs(c[1] - CROWN) < 1e-12):
                continue  # the crown's landward corner only (the seaward one is far from the layer)
            r = x - c
            d = np.hypot(r[:, 0], r[:, 1])
            for s in np.flatnonzero(water & (d < reach) & (d > 0) & (r @ ti > 0) & (r @ to < 0)):
                imgs.append(("corner", x[s], 2.0 * c - x[s]))
        for a, tt, n, ln, b in zip(g.a, g.t, g.n, g.length, g.body):
            if b != caisson or abs(n[1]) < 0.5:
                continue  # the crown edge only (the vertical faces are plain free-slip mirrors)
            r = x - a
            dist, foot = r @ n, r @ tt
            for s in np.flatnonzero(water & (dist >= 0) & (dist < reach) & (foot >= 0) & (foot <= ln)):
                imgs.append(("crown", x[s], x[s] - 2.0 * dist[s] * n))
        for name, target in (("pore water", pore),):
            for kind, xs, xk in imgs:
                near = target & (np.hypot(*(x - xk).T) < reach)
                if not near.any():
                    continue
                kept = int((((x[near] - 0.5 * (xs + xk)) @ (xs - xk)) > 0).sum())
                key = f"{name} <- {kind} images"
                a_, b_ = tally.get(key, (0, 0))
                tally[key] = (a_ + kept, b_ + int(near.sum()))
                if kept:
                    zk = x[near][((x[near] - 0.5 * (xs + xk)) @ (xs - xk)) > 0][:, 1]
                    lowest = min(last_kept.get(key, (0.0, np.inf))[1], float(zk.min()))
                    last_kept[key] = (float(t), lowest)
    soil_sources = 0
    for t, f in series:  # soil that would have corner or crown images: above the crown's level
        if t >= t_from - 1e-12:
            xs = f["position"][f["material"] == SAND]
            soil_sources += int(np.sum((xs[:, 1] > CROWN) & (xs[:, 0] < reach)))
    result = {
        "case": case,
        "reach_m": reach,
        "from_s": t_from,
        "pairs": {k: {"kept": v[0], "within_reach": v[1]} for k, v in tally.items()},
        "last_kept": {k: {"t_s": v[0], "lowest_target_z_m": v[1]} for k, v in last_kept.items()},
        "soil_above_the_crown_within_reach": soil_sources,
    }
    return result


def near(case, t_from=0.5, t_to=2.0, times=(0.25, 0.5, 1.0, 1.5, 2.0)):
    """The top soil rows beside the face (displacement since t = 0 at `times`), and, time-averaged
    over [t_from, t_to], the water above the bed (z < crown) by x: mean u; the top pore water's
    pressure by x (z > SURFACE - 2 dx)."""
    series = _series(case)
    t0, f0 = series[0]
    pore_ids = _pore_ids(f0)
    x0 = dict(zip(f0["id"].tolist(), f0["position"]))
    top = [i for i, p, m in zip(f0["id"].tolist(), f0["position"], f0["material"])
           if m == SAND and p[0] < NEAR and p[1] > SURFACE - 0.011]  # fmt: skip
    rows = {}
    for t, f in series:
        if not any(abs(t - s) < 1e-9 for s in times):
            continue
        pos = dict(zip(f["id"].tolist(), f["position"]))
        rows[f"{t:g}"] = {
            f"({1000 * x0[i][0]:.1f}, {1000 * x0[i][1]:.1f}) mm": [
                round(1000 * float(pos[i][0] - x0[i][0]), 3), round(1000 * float(pos[i][1] - x0[i][1]), 3)
            ]
            for i in sorted(top, key=lambda i: (-x0[i][1], x0[i][0]))
        }  # fmt: skip
    edges = np.arange(0.0, 0.25 + 1e-9, 0.005)
    u_sum, u_n, p_sum, p_n = (np.zeros(len(edges) - 1) for _ in range(4))
    for t, f in series:
        if not (t_from - 1e-9 <= t <= t_to + 1e-9):
            continue
        x, m, v, p = f["position"], f["material"], f["velocity"], f["pressure"]
        pore = (m == WATER) & np.isin(f["id"], pore_ids)
        free = (m == WATER) & ~pore & (x[:, 1] > SURFACE) & (x[:, 1] < CROWN)
        top_pore = pore & (x[:, 1] > SURFACE - 0.01) & (x[:, 1] < SURFACE)
        for sel, s_sum, s_n, val in ((free, u_sum, u_n, v[:, 0]), (top_pore, p_sum, p_n, p)):
            k = np.digitize(x[sel, 0], edges) - 1
            ok = (k >= 0) & (k < len(s_n))
            np.add.at(s_sum, k[ok], val[sel][ok])
            np.add.at(s_n, k[ok], 1)
    centres = 0.5 * (edges[1:] + edges[:-1])
    with np.errstate(invalid="ignore"):
        u, pp = u_sum / u_n, p_sum / p_n
    return {
        "case": case,
        "top_rows_displacement_mm": rows,
        "window_s": [t_from, t_to],
        "x_m": centres.round(4).tolist(),
        "water_above_bed_u_m_s": np.round(u, 4).tolist(),
        "water_above_bed_samples": u_n.astype(int).tolist(),
        "top_pore_pressure_pa": np.round(pp, 0).tolist(),
    }


def pond_raw(dx=0.005, end_time=1.0):
    """scenes/scour_saturated.toml under a still pond: inlet and outlet removed, a hydrostatic water
    block over the caisson, the layer and the end wall up to POND_TOP (the layer's water table
    follows it, solver/initial_state.water_table), the x_max side closed by a free-slip wall."""
    raw = tomllib.loads((SCENES / "scour_saturated.toml").read_text())
    raw["scene"].update(name=f"pond_dx{dx * 1000:g}mm", spacing=float(dx), end_time=float(end_time))
    raw.pop("inlets", None)
    raw.pop("outlets", None)
    raw["walls"]["x_max"] = "free_slip"
    x0, x1 = raw["domain"]["min"][0], raw["domain"]["max"][0]
    raw["blocks"].append(
        {
            "name": "still pond",
            "material": "water",
            "shape": "polygon",
            "vertices": [[x0, CROWN], [0.0, CROWN], [0.0, SURFACE], [x1, SURFACE], [x1, POND_TOP],
                         [x0, POND_TOP]],
            "hydrostatic": True,
        }
    )  # fmt: skip
    k = 1
    times = [0.0]
    while k * 0.025 <= end_time + 1e-9:
        times.append(round(k * 0.025, 6))
        k += 1
    raw["output"].update(times=times, vtk=False, render=False)
    return raw


VARIANTS = ("no_corner_images", "no_pruning")  # experiment-only switches of the body images (below)


def _switch_off(variant):
    """Experiment only (not a solver option): the pond with one part of the body images removed, to
    see which part drives the current at the corners. no_corner_images: no image through a convex
    vertex (BodyGeometry's corner table emptied); no_pruning: every image pair kept
    (BodyImages.prune a no-op)."""
    from solver.physics import bodies

    if variant == "no_corner_images":
        init = bodies.BodyGeometry.__init__

        def without_corners(self, scene):
            init(self, scene)
            self.corner, self.t_in, self.t_out = (np.zeros((0, 2)) for _ in range(3))

        bodies.BodyGeometry.__init__ = without_corners
    elif variant == "no_pruning":
        bodies.BodyImages.prune = lambda self, particles, lists, first: lists


def pond(dx=0.005, end_time=1.0, variant=None, resume=False, label=""):
    import os
    import resource

    from solver.run import run_scene
    from solver.scene import parse_scene

    if variant:
        _switch_off(variant)
    name = f"pond_dx{dx * 1000:g}mm" + (f"_{variant}" if variant else "") + (f"_{label}" if label else "")
    out = POND_RUNS / name
    load0 = os.getloadavg()[0]
    c0, w0 = time.process_time(), time.perf_counter()
    scene = parse_scene(pond_raw(dx, end_time), SCENES / "scour_saturated.toml")
    run_scene(scene, out, quiet=True, overwrite=True, restart=out if resume else None)
    report = json.loads((out / "run.json").read_text())
    return {
        "run": str(out.relative_to(ROOT)),
        "variant": variant,
        "water_speed_near_corners": corner_currents(out),
        "t_reached": report["simulated_time_s"],
        "status": report["status"],
        "cpu_s": time.process_time() - c0,
        "wall_s": time.perf_counter() - w0,
        "load_start": load0,
        "load_end": os.getloadavg()[0],
        "max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
        "body_leaks": report.get("body_leaks"),
        "particles": report["particles"],
        "steps": report["steps"],
    }


CORNERS = {"caisson's landward corner": (0.0, CROWN), "end wall's upstream corner": (0.25, SURFACE),
           "mid-pond (control)": (0.12, 0.15)}  # fmt: skip


def corner_currents(run, radius=0.015):
    """Max and mean water speed within `radius` of each of CORNERS at every output time of a run
    (in a still pond every water particle should stay at rest)."""
    from solver.output.hdf5_writer import read_series

    out = {}
    for t, f in read_series(Path(run) / "particles.h5"):
        w = f["material"] == WATER
        x, sp = f["position"][w], np.hypot(*f["velocity"][w].T)
        row = {}
        for name, c in CORNERS.items():
            k = np.hypot(x[:, 0] - c[0], x[:, 1] - c[1]) < radius
            row[name] = [round(float(sp[k].max()), 4), round(float(sp[k].mean()), 4)] if k.any() else None
        out[f"{t:g}"] = row
    return out


def _profile_at(run, t):
    from verification.scour_zones import read_profiles

    x, ts, z = read_profiles(Path(run) / "scour_profiles.csv")
    k = int(np.argmin(np.abs(ts - t)))
    return x, z[:, k] - z[:, 0], float(ts[k])


def compare(case, at=1.0, dx=0.005, pond_label=""):
    """The surface change beside the face (x < NEAR) and the top rows' horizontal displacement, the
    flowing run against the still pond (the run `pond --label pond_label` made), at time `at`."""
    pond_run = POND_RUNS / (f"pond_dx{dx * 1000:g}mm" + (f"_{pond_label}" if pond_label else ""))
    out = {"case": case, "at_s": at}
    for label, run, root in (("flow", RUNS / case, RUNS), ("pond", pond_run, POND_RUNS)):
        x, dz, t = _profile_at(run, at)
        k = x < NEAR
        series = _series(run.name, root)
        t0, f0 = series[0]
        tk, fk = min(series, key=lambda s: abs(s[0] - at))
        x0 = dict(zip(f0["id"].tolist(), f0["position"]))
        pos = dict(zip(fk["id"].tolist(), fk["position"]))
        top = [i for i, p, m in zip(f0["id"].tolist(), f0["position"], f0["material"])
               if m == SAND and p[0] < NEAR and p[1] > SURFACE - 0.005]  # fmt: skip
        top.sort(key=lambda i: x0[i][0])
        out[label] = {
            "t_s": t,
            "x_m": x[k].round(4).tolist(),
            "surface_change_mm": (1000 * dz[k]).round(3).tolist(),
            "deepest_drop_mm": round(float(-1000 * dz[k].min()), 3),
            "highest_rise_mm": round(float(1000 * dz[k].max()), 3),
            "top_row_x0_mm": [round(1000 * float(x0[i][0]), 1) for i in top],
            "top_row_dx_mm": [round(1000 * float(pos[i][0] - x0[i][0]), 3) for i in top],
            "top_row_dz_mm": [round(1000 * float(pos[i][1] - x0[i][1]), 3) for i in top],
        }
    return out


def _write(name, result):
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"{name}.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.scour_face_dip", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    sub = ap.add_subparsers(dest="cmd", required=True)
    a = sub.add_parser("images")
    a.add_argument("case")
    a.add_argument("--from", dest="t_from", type=float, default=0.02)
    b = sub.add_parser("near")
    b.add_argument("case")
    b.add_argument("--from", dest="t_from", type=float, default=0.5)
    b.add_argument("--to", dest="t_to", type=float, default=2.0)
    c = sub.add_parser("pond")
    c.add_argument("--end", type=float, default=1.0)
    c.add_argument("--dx", type=float, default=0.005)
    c.add_argument("--without", choices=VARIANTS, help="experiment: switch this part of the body images off")
    c.add_argument("--continue", dest="resume", action="store_true", help="extend the pond run to --end")
    c.add_argument("--label", default="", help="a suffix of the run's name (keeps earlier runs)")
    d = sub.add_parser("compare")
    d.add_argument("case")
    d.add_argument("--at", type=float, default=1.0)
    d.add_argument("--pond-label", default="", help="compare with the pond run of this --label")
    args = ap.parse_args(argv)
    if args.cmd == "images":
        _write(f"images_{args.case}", images(args.case, args.t_from))
    elif args.cmd == "near":
        _write(f"near_{args.case}", near(args.case, args.t_from, args.t_to))
    elif args.cmd == "pond":
        tag = f"pond_dx{args.dx * 1000:g}mm" + (f"_{args.without}" if args.without else "")
        tag += f"_{args.label}" if args.label else ""
        result = pond(args.dx, args.end, args.without, args.resume, args.label)
        _write(tag + (f"_to{args.end:g}s" if args.resume else ""), result)
    elif args.cmd == "compare":
        other = "pond" + (f"_{args.pond_label}" if args.pond_label else "")
        tag = f"compare_{args.case}_{other}_{args.at:g}s"
        _write(tag, compare(args.case, args.at, pond_label=args.pond_label))
    return 0


if __name__ == "__main__":
    sys.exit(main())
