"""Back-to-back A/B timing of one step in two checkouts, for speed claims on a noisy host.

    python benchmarks/studies/ab_step.py OLD_CHECKOUT NEW_CHECKOUT --kind soil --rounds 4
    python benchmarks/studies/ab_step.py . . --kind water --old-scheme seed  # two presets, one build

Each round runs the benchmark scene of each checkout in its own process (its own `solver`),
alternating, one Numba thread (--threads), and reports the CPU time per step of the fastest of 15
five-step blocks (after 3 warm-up steps; wall time with more threads, whose OpenMP workers spin
and so add CPU time that is not work). Kinds: water (dam break), soil (column collapse), and the
seepage bed of bench_seepage_step.py: dry (soil only), saturated (the whole step), coupling (the
seepage terms alone, run on the saturated state; time per call of all of them). CPU time rather
than wall time, and the two builds alternated, because this 2-core host's speed varies 2x within
an hour: the ratio new/old of one round is the figure to quote, with the load printed beside it.

    python benchmarks/studies/ab_step.py OLD NEW --kind coupling --call-by-call --pairs 3 --calls 200

--call-by-call: the two builds in two long-lived processes pinned to one core (--cpu), taking
turns call by call (one timed call of the old build, one of the new, a few milliseconds apart, as
benchmarks/reference_build.py does for the gate): both see the same core in the same state, which
process-by-process rounds do not (a vCPU's speed changes from minute to minute). Per process pair
the median of the calls' new/old ratios; one Numba thread, CPU time.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import numpy as np

SETUP = """
import os, sys, time
root, kind, scheme, threads = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
if len(sys.argv) > 5:
    os.sched_setaffinity(0, {int(sys.argv[5])})
sys.path[:0] = [root, root + "/benchmarks"]
import numba
numba.set_num_threads(threads)
if kind == "water":
    from dam_break_setup import dam_break
    sim = dam_break(25_000, **({} if scheme == "-" else {"numerics.scheme": scheme}))
elif kind == "soil":
    from bench_soil_step import soil_collapse
    sim = soil_collapse(25_000)
else:
    from bench_seepage_step import bed
    sim = bed(kind != "dry")
step = sim.step
if kind == "coupling":  # the names of the seepage terms in every version of the coupling
    names = ("pore pressure at soil", "pore pressure at water", "seepage on soil", "seepage on water")
    terms = [t for t in sim.plan.terms if t.name in names]
    def step():
        for t in terms:
            t.run(sim.ctx)
for _ in range(3):
    step()
"""

CHILD = (
    SETUP
    + """
clock = time.process_time if threads == 1 else time.perf_counter  # OpenMP threads spin: wall time
blocks = []
for _ in range(15):
    t0 = clock()
    for _ in range(5):
        step()
    blocks.append((clock() - t0) / 5)
print(min(blocks), sim.particles.n_owned)
"""
)


CALLS = (
    SETUP
    + """
print("ready", flush=True)
for line in sys.stdin:
    c0 = time.process_time()
    step()
    print(time.process_time() - c0, flush=True)
"""
)


def call_by_call(old, new, kind, scheme_old, scheme_new, cpu, calls):
    """Median new/old of `calls` alternating calls, both builds' processes pinned to `cpu`."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", CALLS, os.path.abspath(root), kind, scheme or "-", "1", str(cpu)],
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )  # fmt: skip
        for root, scheme in ((old, scheme_old), (new, scheme_new))
    ]
    try:
        for p in procs:
            if p.stdout.readline().strip() != "ready":
                raise SystemExit(f"a {kind} child did not start")
        times = []
        for _ in range(calls):
            pair = []
            for p in procs:
                p.stdin.write("go\n")
                pair.append(float(p.stdout.readline()))
            times.append(pair)
    finally:
        for p in procs:
            p.stdin.close()
            p.wait()
    t = np.array(times)
    return float(np.median(t[:, 1] / t[:, 0])), float(np.median(t[:, 0])), float(np.median(t[:, 1]))


def step_time(root, kind, scheme=None, threads=1):
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
    out = subprocess.run(
        [sys.executable, "-c", CHILD, os.path.abspath(root), kind, scheme or "-", str(threads)],
        env=env,
        capture_output=True,
        text=True,
    )
    if out.returncode:
        raise SystemExit(f"{root}: {out.stderr.strip().splitlines()[-1]}")
    seconds, n = out.stdout.split()
    return float(seconds), int(n)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--kind", choices=("water", "soil", "dry", "saturated", "coupling"), default="soil")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--threads", type=int, default=1, help="Numba threads (> 1: wall time, not CPU time)")
    for side in ("old", "new"):
        ap.add_argument(
            f"--{side}-scheme",
            help=f'water only: numerics.scheme of the {side} run ("seed", "default"); default: the scene\'s',
        )
    ap.add_argument("--call-by-call", action="store_true", help="alternate call by call on one core (--cpu)")
    ap.add_argument("--cpu", type=int, default=1, help="--call-by-call: the core both processes run on")
    ap.add_argument("--pairs", type=int, default=3, help="--call-by-call: process pairs")
    ap.add_argument("--calls", type=int, default=200, help="--call-by-call: alternating calls per pair")
    args = ap.parse_args(argv)
    if args.call_by_call:
        for k in range(args.pairs):
            ratio, t_old, t_new = call_by_call(
                args.old, args.new, args.kind, args.old_scheme, args.new_scheme, args.cpu, args.calls
            )
            print(
                f"pair {k + 1}: {args.kind}, {args.calls} calls each on cpu {args.cpu}, median old "
                f"{t_old * 1e3:.2f} ms, new {t_new * 1e3:.2f} ms, median new/old {ratio:.3f}, "
                f"load {os.getloadavg()[0]:.1f}"
            )
        return
    for k in range(args.rounds):
        (t_old, n) = step_time(args.old, args.kind, args.old_scheme, args.threads)
        (t_new, _) = step_time(args.new, args.kind, args.new_scheme, args.threads)
        load = os.getloadavg()[0]
        rates = f"old {n / t_old / 1e6:.2f}, new {n / t_new / 1e6:.2f} M particle-steps/s"
        print(
            f"round {k + 1}: {args.kind}, {n} particles, old {t_old * 1e3:.2f} ms, new {t_new * 1e3:.2f} ms "
            f"({rates}), new/old {t_new / t_old:.3f}, load {load:.1f}"
        )


if __name__ == "__main__":
    main()
