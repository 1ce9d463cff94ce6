"""The benchmark gate's second yardstick: the baseline commit's own build, timed side by side.

The calibration kernel (calibration.py) cancels most of this host's speed changes, but not all:
for minutes at a time the host enters a slow phase in which the solver's steps lose 15-25 %
against the kernel (the nightly of 2026-12-02 00:03 UTC measured water +13 %, soil +17 %,
two-phase +9 % in all three attempts of an unchanged build; docs/benchmarks.md). Whatever slows
the solver's step slows the same step of the baseline commit as much, so the gate times each step
benchmark in both builds, alternating processes every few seconds, and compares the ratio
current / baseline build. The baseline build is the commit recorded in baselines/gate.json,
exported once with `git archive` into runs/bench/reference/<commit> (no solver code of the current
tree is imported there: each side runs its own `solver` and its own benchmark set-up).

    python benchmarks/reference_build.py water [--pairs 4]      one A/B measurement, printed
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TREES = ROOT / "runs" / "bench" / "reference"
PAIRS = 6  # A/B pairs per measurement, each side in its own process, order alternated (ABBA)
ROUNDS = 150  # timed calls per process; a call is 1-4 ms, so a process lives ~3 s

# gate benchmark -> the child's build of it (the same scenes and sizes as bench_gate.py)
KINDS = {
    "water_step": "water",
    "soil_step": "soil",
    "two_phase_step": "two_phase",
    "neighbour_rebuild": "rebuild",
}

CHILD = """
import os, sys, time
root, kind, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
sys.path[:0] = [root, root + "/benchmarks"]
import numba
numba.set_num_threads(1)
from slowdown import spin_after
if kind in ("water", "rebuild"):
    from dam_break_setup import dam_break
    sim = dam_break(5_000)
elif kind == "soil":
    from bench_soil_step import soil_collapse
    sim = soil_collapse(2_500)
else:
    from saturated_bed_setup import saturated_bed
    sim = saturated_bed(3_750)
target, before = (sim.rebuild, sim.step) if kind == "rebuild" else (sim.step, None)
best = float("inf")
for k in range(rounds + 3):
    if before is not None:
        before()
    t0, c0 = time.perf_counter(), time.process_time()
    target()
    spin_after(t0, c0)
    if k >= 3:
        best = min(best, time.process_time() - c0)
print(best, sim.particles.n_owned)
"""


def reference_tree(commit):
    """The baseline commit's files, exported once (git archive) into runs/bench/reference/."""
    tree = TREES / commit[:12]
    if (tree / "solver").is_dir():
        return tree
    TREES.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=TREES) as tmp:
        archive = Path(tmp) / "tree.tar"
        r = subprocess.run(
            ["git", "archive", "--format=tar", "-o", str(archive), commit],
            cwd=ROOT,
            capture_output=True,
            text=True,
        )
        if r.returncode:
            raise RuntimeError(f"cannot export the baseline commit {commit[:12]}: {r.stderr.strip()}")
        staging = Path(tmp) / "tree"
        with tarfile.open(archive) as tar:
            tar.extractall(staging, filter="data")
        staging.rename(tree)
    return tree


def time_in(root, kind, slowdown=None, rounds=ROUNDS):
    """CPU time of the fastest of `rounds` calls of the benchmark in a fresh process of `root`."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
    if slowdown:
        env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
    out = subprocess.run(
        [sys.executable, "-c", CHILD, str(root), kind, str(rounds)], env=env, capture_output=True, text=True
    )
    if out.returncode:
        raise RuntimeError(f"{kind} in {root}: {out.stderr.strip().splitlines()[-1:]}")
    return float(out.stdout.split()[0])


def ab_times(name, reference, current=ROOT, slowdown=None, pairs=PAIRS):
    """CPU times (reference, current) of gate benchmark `name`, one process each, `pairs` times;
    the order of the two processes alternates from pair to pair so that a drift of the host's
    speed cancels."""
    kind = KINDS[name]
    for root in (reference, current):  # compile or load each build's Numba cache outside the timing
        time_in(root, kind, rounds=1)
    out = []
    for k in range(pairs):
        if k % 2 == 0:
            ref = time_in(reference, kind)
            new = time_in(current, kind, slowdown)
        else:
            new = time_in(current, kind, slowdown)
            ref = time_in(reference, kind)
        out.append((ref, new))
    return out


def measurement(name, reference, current=ROOT, slowdown=None, pairs=PAIRS):
    """One A/B measurement of a gate benchmark: `ratio`, the current build's fastest process over
    the reference build's fastest; the per-pair ratios beside it. The host's noise only ever slows
    a process down (a whole process of 1-2 s can run 20 % slow: the A/A pairs of the soil step
    ranged 0.78-1.02), so each build's fastest process is its undisturbed cost."""
    times = ab_times(name, reference, current, slowdown, pairs)
    return {
        "ratio": min(n for _, n in times) / min(r for r, _ in times),
        "pair_ratios": [n / r for r, n in times],
        "times": times,
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", choices=list(KINDS))
    ap.add_argument("--commit", help="baseline commit (default: the one in baselines/gate.json)")
    ap.add_argument("--pairs", type=int, default=PAIRS)
    ap.add_argument("--slowdown", type=float)
    args = ap.parse_args(argv)
    if args.commit is None:
        import json

        args.commit = json.loads((HERE / "baselines" / "gate.json").read_text())["commit"]
    m = measurement(args.name, reference_tree(args.commit), slowdown=args.slowdown, pairs=args.pairs)
    pairs = ", ".join(f"{r:.3f}" for r in m["pair_ratios"])
    print(f"{args.name}: current / {args.commit[:10]} = {m['ratio']:.4f} (pair ratios {pairs})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
