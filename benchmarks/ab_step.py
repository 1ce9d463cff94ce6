"""Back-to-back A/B timing of one step in two checkouts, for speed claims on a noisy host.

    python benchmarks/ab_step.py OLD_CHECKOUT NEW_CHECKOUT --kind soil --rounds 4
    python benchmarks/ab_step.py . . --kind water --old-scheme seed    # two numerics presets, one build

Each round runs the benchmark scene of each checkout in its own process (its own `solver`),
alternating, one Numba thread (--threads), and reports the CPU time per step of the fastest of 15
five-step blocks (after 3 warm-up steps; wall time with more threads, whose OpenMP workers spin
and so add CPU time that is not work). Kinds: water (dam break), soil (column collapse), and the
seepage bed of bench_seepage_step.py: dry (soil only), saturated (the whole step), coupling (the
seepage terms alone, run on the saturated state; time per call of all of them). CPU time rather
than wall time, and the two builds alternated, because this 2-core host's speed varies 2x within
an hour: the ratio new/old of one round is the figure to quote, with the load printed beside it.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

CHILD = """
import sys, time
root, kind, scheme, threads = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
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
clock = time.process_time if threads == 1 else time.perf_counter  # OpenMP threads spin: wall time
blocks = []
for _ in range(15):
    t0 = clock()
    for _ in range(5):
        step()
    blocks.append((clock() - t0) / 5)
print(min(blocks), sim.particles.n_owned)
"""


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
    args = ap.parse_args(argv)
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
