"""Does a new build step the 25k water benchmark scene to the same bits as an old build?

    python benchmarks/studies/water_identical.py OLD_CHECKOUT NEW_CHECKOUT [--steps 200] [--scheme seed]

For a change meant to leave every floating-point operation as it was (an index type, a loop's
layout): each build runs the disordered dam break of benchmarks/dam_break_setup.py for --steps
steps in its own process, one Numba thread, and the positions, velocities, densities and pressures
are compared by particle id. The verdict is "bit-identical" or the largest differences; for a
change that rounds differently, benchmarks/studies/soil_roundoff.py's one-ulp bound is the scale to use.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = """
import sys
root, steps, scheme, out = sys.argv[1:5]
sys.path[:0] = [root, root + "/benchmarks"]
import numpy as np
from dam_break_setup import dam_break
sim = dam_break(25_000, **({} if scheme == "-" else {"numerics.scheme": scheme}))
for _ in range(int(steps)):
    sim.step()
ps = sim.particles
n = ps.n_owned
order = np.argsort(ps["id"][:n])
np.savez(out, **{k: ps[k][:n][order] for k in ("x", "v", "rho", "p")}, steps=sim.step_count, t=sim.t)
"""


def run(root, steps, scheme, out):
    # a fixed hash seed: the saturated bed's results vary at round-off with it (main against itself:
    # 5e-17 m in 100 steps; docs/benchmarks.md), the dam break's do not
    env = dict(os.environ, NUMBA_NUM_THREADS="1", PYTHONHASHSEED="0")
    args = [sys.executable, "-c", CHILD, os.path.abspath(root), str(steps), scheme or "-", out]
    done = subprocess.run(args, env=env, capture_output=True, text=True)
    if done.returncode:
        raise SystemExit(f"{root}: {done.stderr.strip().splitlines()[-1]}")
    return dict(np.load(out))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument(
        "--scheme", help='numerics.scheme of both runs ("seed", "default"); default: the scene\'s'
    )
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        old = run(args.old, args.steps, args.scheme, os.path.join(folder, "old.npz"))
        new = run(args.new, args.steps, args.scheme, os.path.join(folder, "new.npz"))
    steps = f"{int(old['steps'])} / {int(new['steps'])} steps"
    print(f"{len(old['x'])} particles, old / new: {steps}, t {old['t']} / {new['t']} s")
    same = int(old["steps"]) == int(new["steps"]) and old["t"] == new["t"]
    for k in ("x", "v", "rho", "p"):
        equal = np.array_equal(old[k], new[k])
        same &= equal
        print(f"  {k:4s} {'identical' if equal else f'max |new - old| {np.abs(new[k] - old[k]).max():.3e}'}")
    print("verdict:", "bit-identical" if same else "NOT bit-identical")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
