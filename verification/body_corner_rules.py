"""Which body images may a particle see near a convex corner? A still pond beside a caisson-like step,
run under several rules (experiment only: the rules other than the solver's are switched in by
monkeypatching solver/physics/bodies.py in this process), and the water's speed near the corner.

The scene is tests/test_bodies.py's CORNER_POND: a 0.08 m deep hydrostatic pond over and beside a
0.04 x 0.04 m step, 5 mm spacing, c = 25 m/s (the scour scenes'), 256 particles. Rules:

  region       the solver's (prune_to_own_region): a particle sees an image only if it lies in the
               region whose mirror made it, the edge's strip (in front, foot on the edge) or the
               convex vertex's wedge
  mirror_line  main before corner9 (prune_behind_mirrors): a pair is dropped when its target lies
               behind the image's mirror line (the bisector of image and source)
  half_plane   an edge's images seen by every particle in front of the edge's line (no foot
               condition), a vertex's by its wedge
  all_pairs    no pruning: every image seen by every neighbour
  flat         no step at all: the same pond over a flat floor (the control)

    python -m verification.body_corner_rules --end 0.5            # every rule, a table every 0.05 s
    python -m verification.body_corner_rules --rules region flat --end 1.0

Prints, per rule and time, the largest and the mean water speed within 15 mm of the corner (0, 0.04)
and the CPU time; writes the table as JSON to verification/results/scour/face_dip/corner_rules.json.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np

OUT = Path(__file__).with_name("results") / "scour" / "face_dip" / "corner_rules.json"
CORNER = (0.0, 0.04)
RADIUS = 0.015
RULES = ("region", "mirror_line", "half_plane", "all_pairs", "flat")

POND = """
[scene]
name = "corner_pond"
dimension = 2
spacing = 0.005
end_time = 0.1
gravity = [0.0, -9.81]

[domain]
min = [-0.04, 0.0]
max = [0.06, 0.12]

[walls]
x_min = "free_slip"
x_max = "free_slip"
y_min = "free_slip"

[materials.water]
model = "water"
density = 1000.0
typical_velocity = 2.5         # the scour scenes' (c = 25 m/s)

[[bodies]]
name = "caisson"               # its landward corner (0, 0.04) is convex, under 0.04 m of water
vertices = [[-0.04, 0.0], [0.0, 0.0], [0.0, 0.04], [-0.04, 0.04]]

[[blocks]]
name = "pond"
material = "water"
shape = "polygon"
vertices = [[-0.04, 0.04], [0.0, 0.04], [0.0, 0.0], [0.06, 0.0], [0.06, 0.08], [-0.04, 0.08]]
hydrostatic = true

[output]
interval = 1.0
fields = ["velocity"]
vtk = false
render = false
"""


def _raw(rule):
    raw = tomllib.loads(POND)
    if rule == "flat":
        raw.pop("bodies")
        raw["blocks"][0]["vertices"] = [[-0.04, 0.0], [0.06, 0.0], [0.06, 0.08], [-0.04, 0.08]]
    return raw


def _switch(rule):
    """Experiment only: replace the solver's pair rule in this process."""
    from numba import njit

    from solver.physics import bodies

    if rule == "all_pairs":
        bodies.BodyImages.prune = lambda self, particles, lists, first: lists
    elif rule == "half_plane":

        @njit
        def half_plane(
            targets, start, index, x, first, tag, ea, et, en, elen, cv, cin, cout, new_start, new_index
        ):
            fill = new_index.shape[0] > 0
            m = 0
            new_start[0] = 0
            for t in range(targets.shape[0]):
                i = targets[t]
                for s in range(start[t], start[t + 1]):
                    j = index[s]
                    k = j - first
                    if 0 <= k < tag.shape[0]:
                        g = tag[k]
                        if g >= 0:
                            ok = (x[i, 0] - ea[g, 0]) * en[g, 0] + (x[i, 1] - ea[g, 1]) * en[g, 1] >= 0.0
                        else:
                            ok = bodies.in_image_region(x[i, 0], x[i, 1], g, ea, et, en, elen, cv, cin, cout)
                        if not ok:
                            continue
                    if fill:
                        new_index[m] = j
                    m += 1
                new_start[t + 1] = m
            return m

        bodies.prune_to_own_region = half_plane
    elif rule == "mirror_line":

        def behind_mirror_line(self, particles, lists, first):
            if self.n == 0:
                return lists
            x, src = particles["x"], self.src[: self.n]
            out = {}
            for key, nl in lists.items():
                keep = []
                for t, i in enumerate(nl.targets):
                    row = nl.index[nl.start[t] : nl.start[t + 1]]
                    k = row - first
                    img = (k >= 0) & (k < len(src))
                    side = np.ones(len(row))
                    s = x[src[k[img]]]
                    side[img] = np.einsum("kd,kd->k", x[i] - 0.5 * (s + x[row[img]]), s - x[row[img]])
                    keep.append(row[side > 0.0])
                new_start = np.concatenate([[0], np.cumsum([len(r) for r in keep])]).astype(np.int64)
                new_index = np.concatenate(keep).astype(nl.index.dtype) if keep else nl.index[:0]
                out[key] = type(nl)(nl.targets, new_start, new_index)
            return out

        bodies.BodyImages.prune = behind_mirror_line


def run(rule, end, every=0.05):
    from solver.scene import parse_scene
    from solver.simulation import Simulation

    sim = Simulation(parse_scene(_raw(rule), "<corner pond>"))
    c0 = time.process_time()
    rows = []
    for t in np.arange(every, end + 1e-9, every):
        sim.advance_to(float(t))
        ps = sim.particles
        x, v = ps["x"][: ps.n_owned], ps["v"][: ps.n_owned]
        speed = np.hypot(*v[np.hypot(x[:, 0] - CORNER[0], x[:, 1] - CORNER[1]) < RADIUS].T)
        rows.append({"t_s": round(float(t), 4), "max_m_s": round(float(speed.max()), 4),
                     "mean_m_s": round(float(speed.mean()), 4)})  # fmt: skip
    cpu = round(time.process_time() - c0, 1)
    return {"rule": rule, "particles": int(sim.particles.n_owned), "cpu_s": cpu, "rows": rows}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.body_corner_rules", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    ap.add_argument("--rules", nargs="+", choices=RULES, default=list(RULES))
    ap.add_argument("--end", type=float, default=0.5)
    args = ap.parse_args(argv)
    if args.end <= 0:
        ap.error("--end must be positive")
    results = []
    for rule in args.rules:  # one process per rule: the switches are monkeypatches
        code = f"from verification.body_corner_rules import _one; _one({rule!r}, {args.end!r})"
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
        results.append(json.loads(out.strip().splitlines()[-1]))
        r = results[-1]
        print(f"{rule:12s} ({r['particles']} particles, {r['cpu_s']} s CPU):  " + "  ".join(
            f"{row['t_s']:g}: {row['max_m_s']:.4f}/{row['mean_m_s']:.4f}" for row in r["rows"]))  # fmt: skip
    OUT.parent.mkdir(parents=True, exist_ok=True)
    table = {"corner": CORNER, "radius_m": RADIUS, "speed": "max/mean m/s", "runs": results}
    OUT.write_text(json.dumps(table, indent=1) + "\n")
    return 0


def _one(rule, end):
    if rule not in ("region", "flat"):
        _switch(rule)
    print(json.dumps(run(rule, end)))


if __name__ == "__main__":
    sys.exit(main())
