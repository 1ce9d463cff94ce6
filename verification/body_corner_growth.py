"""Where the still pond's residual current beside a convex body corner comes from (corner10).

The pond is verification/body_corner_rules.py's (a 0.08 m hydrostatic pond over and beside a 0.04 m
step, c = 25 m/s). Per output time it prints the largest and mean water speed within 15 mm of the
corner (0, 0.04), where the fastest particle is and in which image region (C: the crown's strip,
x <= 0 above the crown; W: the corner's wedge, x > 0, y > 0.04; F: the face's strip, x >= 0 below
the crown), and how many particles within reach of the corner are in another region than at t = 0
(region crossings, which switch the image set a particle sees). Variants:

  --flat            no step (the control)
  --frozen          experiment only: every particle keeps the image region of its t = 0 position
                    (monkeypatched in this process), so no crossing switches an image set
  --spacing, --h-over-dx, --sound-speed-scale   the lattice, the kernel width, c (typical_velocity)

    python -m verification.body_corner_growth --end 1.0
    python -m verification.body_corner_growth --end 3.0 --every 0.25 --flat
    python -m verification.body_corner_growth --end 1.0 --frozen
    python -m verification.body_corner_growth --end 3.0 --every 0.5 --h-over-dx 1.2

Findings (docs/history/scour_study_history.md, "The bodies' convex corners"): the current is a
lattice-scale zig-zag
that grows exponentially from the first 0.1-0.2 s, before any crossing, equally with frozen regions;
the flat pond grows the same mode later (1.5 s at 5 mm), and neither grows at h = 1.2 dx.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from verification.body_corner_rules import CORNER, RADIUS, _raw


def region(x):
    """C (crown strip), W (corner wedge), F (face strip) or O (elsewhere) of each position."""
    label = np.full(len(x), "O")
    label[(x[:, 0] <= CORNER[0]) & (x[:, 1] >= CORNER[1])] = "C"
    label[(x[:, 0] > CORNER[0]) & (x[:, 1] > CORNER[1])] = "W"
    label[(x[:, 0] >= CORNER[0]) & (x[:, 1] <= CORNER[1])] = "F"
    return label


def freeze_regions():
    """Experiment only: body images and the pair rule decide a particle's region by its t = 0
    position (by id), the images' geometry by its current one."""
    from solver.physics import bodies

    start = {}

    def as_at_start(particles, n):
        ids, x = particles["id"][:n], particles["x"][:n].copy()
        known = np.array([int(i) in start for i in ids], dtype=bool)
        if known.any():
            x[known] = np.array([start[int(i)] for i in ids[known]])
        return x

    rebuild, prune = bodies.BodyImages.rebuild, bodies.BodyImages.prune

    def frozen_rebuild(self, particles, first, box=None):
        n_local, x = particles.n_local, particles["x"]
        if not start:
            start.update({int(i): xi.copy() for i, xi in zip(particles["id"][:n_local], x[:n_local])})
        now = x[:n_local].copy()
        x[:n_local] = as_at_start(particles, n_local)
        n = rebuild(self, particles, first, box)  # regions (tags) from the t = 0 positions
        x[:n_local] = now
        g = self.geo
        for k in np.flatnonzero(self.tag[:n] < 0):  # a wedge image's point mirror from the current position
            i, v = self.src[k], g.corner[-1 - self.tag[k]]
            m = (x[i] - v) / np.hypot(*(x[i] - v))
            self.rot[k] = np.eye(2) - 2.0 * np.outer(m, m)
            self.off[k] = 2.0 * v - x[i] - self.rot[k] @ x[i]
        return n

    def frozen_prune(self, particles, lists, first):
        n, x = particles.n_owned, particles["x"]
        now = x[:n].copy()
        x[:n] = as_at_start(particles, n)
        try:
            return prune(self, particles, lists, first)
        finally:
            x[:n] = now

    bodies.BodyImages.rebuild, bodies.BodyImages.prune = frozen_rebuild, frozen_prune


def run(args):
    from solver.scene import parse_scene
    from solver.simulation import Simulation

    raw = _raw("flat" if args.flat else "region")
    raw["scene"]["spacing"] = args.spacing
    raw.setdefault("numerics", {})["h_over_dx"] = args.h_over_dx
    raw["materials"]["water"]["typical_velocity"] *= args.sound_speed_scale
    if args.frozen:
        freeze_regions()
    sim = Simulation(parse_scene(raw, "<corner pond>"))
    ps = sim.particles
    n = ps.n_owned
    x0 = ps["x"][:n][np.argsort(ps["id"][:n])].copy()
    label0 = region(x0)
    print(f"{n} particles, h = {sim.h:.4g} m, reach {sim.radius:.4g} m")
    print("t (s)  max / mean speed (m/s)  fastest (region, x, y)  crossings within reach")
    c0 = time.process_time()
    first = None
    for t in np.arange(args.every, args.end + 1e-9, args.every):
        sim.advance_to(float(t))
        ps = sim.particles
        n = ps.n_owned
        order = np.argsort(ps["id"][:n])
        x, v = ps["x"][:n][order], ps["v"][:n][order]
        r = np.hypot(x[:, 0] - CORNER[0], x[:, 1] - CORNER[1])
        label = region(x)
        crossed = np.flatnonzero((r < sim.radius) & (label != label0))
        if len(crossed) and first is None:
            first = (float(t), [f"{label0[k]}->{label[k]}" for k in crossed])
        speed = np.hypot(*v.T)
        near = np.flatnonzero(r < RADIUS)
        k = near[np.argmax(speed[near])]
        kinds = " ".join(sorted({f"{label0[c]}->{label[c]}" for c in crossed}))
        print(f"{t:5.2f}  {speed[near].max():.4f} / {speed[near].mean():.4f}  "
              f"{label[k]} ({x[k, 0]:+.4f}, {x[k, 1]:.4f})  {len(crossed)} {kinds}", flush=True)  # fmt: skip
    print(f"first crossing: {first}")
    print(f"{time.process_time() - c0:.1f} s CPU")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.body_corner_growth", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    ap.add_argument("--end", type=float, default=1.0)
    ap.add_argument("--every", type=float, default=0.05)
    ap.add_argument("--spacing", type=float, default=0.005)
    ap.add_argument("--h-over-dx", type=float, default=1.3)
    ap.add_argument("--sound-speed-scale", type=float, default=1.0)
    ap.add_argument("--flat", action="store_true")
    ap.add_argument("--frozen", action="store_true")
    args = ap.parse_args(argv)
    if args.end <= 0 or args.every <= 0:
        ap.error("--end and --every must be positive")
    run(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
