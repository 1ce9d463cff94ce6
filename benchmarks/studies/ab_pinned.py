"""Two builds' 25k water step timed call by call on one core: the side-by-side A/B for speed claims.

    python benchmarks/studies/ab_pinned.py OLD_CHECKOUT NEW_CHECKOUT [--pairs 3] [--rounds 100]
    python benchmarks/studies/ab_pinned.py . . --old-scheme seed --new-scheme default # two presets, one build

ab_step.py alternates whole processes, which on this host can land on different vCPUs, and the two
vCPUs run at different speeds that change from minute to minute (docs/benchmarks.md: up to 37 %
between two processes of one build, about 1 % when both are pinned to one core). Here, as in the
gate's reference_build.py, one process per build, both pinned to the same core, take turns one
timed step at a time (the order alternating from round to round), so both see the core in the
same state. A pair's figure is the median over its rounds of new / old (CPU time per step); the
measurement is the median over pairs. OLD may be any commit's export (git archive REV | tar -x -C
DIR): the child needs only its benchmarks/dam_break_setup.py, whose dam_break() every version has.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys

CHILD = """
import os, sys, time
root, scheme, cpu, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
os.sched_setaffinity(0, {cpu})
sys.path[:0] = [root, root + "/benchmarks"]
import numba
numba.set_num_threads(1)
from dam_break_setup import dam_break
sim = dam_break(n, **({} if scheme == "-" else {"numerics.scheme": scheme}))
for _ in range(3):
    sim.step()
print("ready", sim.particles.n_owned, flush=True)
for line in sys.stdin:
    c0 = time.process_time()
    sim.step()
    print(time.process_time() - c0, flush=True)
print("rebuilds", sim.rebuilds, sim.step_count, flush=True)
"""


def start(root, scheme, cpu, n):
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    args = [sys.executable, "-c", CHILD, os.path.abspath(root), scheme or "-", str(cpu), str(n)]
    pipe = subprocess.PIPE
    proc = subprocess.Popen(args, env=env, stdin=pipe, stdout=pipe, text=True, bufsize=1)
    ready = proc.stdout.readline().split()
    if not ready or ready[0] != "ready":
        raise SystemExit(f"{root}: the benchmark did not start")
    return proc, int(ready[1])


def call(proc):
    proc.stdin.write("go\n")
    return float(proc.stdout.readline())


def finish(proc):
    proc.stdin.close()
    _, rebuilds, steps = proc.stdout.readline().split()
    proc.wait()
    return int(rebuilds) / int(steps)


def pair(args, cpu):
    """One process pair: [(old, new)] CPU seconds per step, and each side's rebuild fraction."""
    old, n = start(args.old, args.old_scheme, cpu, args.particles)
    new, _ = start(args.new, args.new_scheme, cpu, args.particles)
    times = []
    for k in range(args.rounds):
        if k % 2 == 0:
            t_old = call(old)
            t_new = call(new)
        else:
            t_new = call(new)
            t_old = call(old)
        times.append((t_old, t_new))
    return times, n, finish(old), finish(new)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument(
        "--old-scheme", help='numerics.scheme of the old run ("seed", "default"); default: the scene\'s'
    )
    ap.add_argument("--new-scheme", help="numerics.scheme of the new run")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--rounds", type=int, default=100, help="alternating timed steps per pair")
    ap.add_argument("--particles", type=int, default=25_000)
    args = ap.parse_args(argv)
    cpu = max(os.sched_getaffinity(0))
    ratios = []
    for p in range(args.pairs):
        load0 = os.getloadavg()[0]
        times, n, reb_old, reb_new = pair(args, cpu)
        ratio = statistics.median(b / a for a, b in times)
        t_old = statistics.median(a for a, _ in times)
        t_new = statistics.median(b for _, b in times)
        ratios.append(ratio)
        print(
            f"pair {p + 1}: {n} particles, core {cpu}, median step old {t_old * 1e3:.2f} ms,"
            f" new {t_new * 1e3:.2f} ms ({n / t_old / 1e6:.2f} / {n / t_new / 1e6:.2f} M particle-steps/s),"
            f" new/old {ratio:.3f}; rebuilds per step old {reb_old:.3f}, new {reb_new:.3f};"
            f" load {load0:.1f}-{os.getloadavg()[0]:.1f}",
            flush=True,
        )
    print(f"new/old, median over {args.pairs} pairs: {statistics.median(ratios):.3f}")


if __name__ == "__main__":
    main()
