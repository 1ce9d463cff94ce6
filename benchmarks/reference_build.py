"""The benchmark gate's second yardstick: the baseline commit's own build, timed call by call.

The calibration kernel (calibration.py) cancels most of this host's speed changes, but not all:
for minutes at a time the host enters a slow phase in which the solver's steps lose 15-25 %
against the kernel (the nightly of 2026-12-02 00:03 UTC measured water +13 %, soil +17 %,
two-phase +9 % in all three attempts of an unchanged build; docs/benchmarks.md). What is slow is
a vCPU: the two vCPUs of this guest run at different speeds that change from minute to minute.
Two processes of the same build taking turns call by call differ by up to 37 % when each is on its
own vCPU, and by about 1 % when both are pinned to one (docs/benchmarks.md). So the gate runs
each step benchmark in two processes, one per build, pinned to the same core, and has them take
turns: one timed call of the baseline build, one of the current build, and so on, a few
milliseconds apart, so that both see the same core in the same state. The ratio of a round is
current / baseline; a measurement is the median over PAIRS process pairs of each pair's median. The
baseline build is the commit recorded in baselines/gate.json, exported once with `git archive`
into runs/bench/reference/<commit>; each process imports its own `solver` and its own benchmark
set-up.

    python benchmarks/reference_build.py water_step [--pairs 3] [--slowdown 0.1]
    python benchmarks/reference_build.py mpi_two_rank_step | cold_compile    (their own schemes)
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import reference_compile
import reference_mpi

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TREES = ROOT / "runs" / "bench" / "reference"
PAIRS = 3  # process pairs per measurement (the MPI step and the cold compile: their own modules)
ROUNDS = 200  # alternating timed calls per pair; a call is 1-4 ms

# gate benchmark -> the child's build of it (the same scenes and sizes as bench_gate.py)
KINDS = {
    "water_step": "water",
    "soil_step": "soil",
    "two_phase_step": "two_phase",
    "neighbour_rebuild": "rebuild",
}
# every gate benchmark with a side-by-side verdict: the four above, and the two that cannot take
# turns call by call on one core, each with its own scheme (reference_mpi.py, reference_compile.py)
SIDE_BY_SIDE = (*KINDS, "mpi_two_rank_step", "cold_compile")

# One build's side, pinned to the given core: set up, warm up, then one timed call per line read
# from stdin, its CPU time written back. The wait for the next line is outside the timing.
CHILD = """
import os, sys, time
root, kind, cpu = sys.argv[1], sys.argv[2], int(sys.argv[3])
os.sched_setaffinity(0, {cpu})
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
for _ in range(3):
    if before is not None:
        before()
    target()
print("ready", flush=True)
for line in sys.stdin:
    if before is not None:
        before()
    t0, c0 = time.perf_counter(), time.process_time()
    target()
    spin_after(t0, c0)
    print(time.process_time() - c0, flush=True)
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


def _start(root, kind, cpu, slowdown=None):
    env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
    if slowdown:
        env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
    # stderr to a file, not a pipe nobody reads during the rounds (a full pipe would block the child)
    errors = tempfile.TemporaryFile(mode="w+")
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD, str(root), kind, str(cpu)],
        env=env,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=errors,
        text=True,
        bufsize=1,
    )
    proc.errors, proc.what = errors, f"{kind} benchmark in {root}"
    return proc


def _failed(proc, doing):
    proc.errors.seek(0)
    last = proc.errors.read().strip().splitlines()[-1:]
    return RuntimeError(f"{proc.what} {doing}: {last[0] if last else 'no message'}")


def _ready(proc):
    if proc.stdout.readline().strip() != "ready":
        raise _failed(proc, "did not start")


def _call(proc):
    proc.stdin.write("go\n")
    line = proc.stdout.readline()
    if not line:
        raise _failed(proc, "stopped")
    return float(line)


def alternating_times(name, reference, current=ROOT, slowdown=None, rounds=ROUNDS):
    """[(reference, current)] CPU time of one call per round, the two processes taking turns (the
    order alternating from round to round)."""
    kind = KINDS[name]
    cpu = max(os.sched_getaffinity(0))  # both on one core: this host's two vCPUs differ in speed
    ref, new = _start(reference, kind, cpu), _start(current, kind, cpu, slowdown)
    try:
        _ready(ref)
        _ready(new)
        out = []
        for k in range(rounds):
            if k % 2 == 0:
                r = _call(ref)
                n = _call(new)
            else:
                n = _call(new)
                r = _call(ref)
            out.append((r, n))
        return out
    finally:
        for p in (ref, new):
            p.stdin.close()
            p.wait()
            p.errors.close()


def default_pairs(name):
    """Process pairs (job pairs for the MPI step) of one measurement of a benchmark."""
    return {"mpi_two_rank_step": reference_mpi.PAIRS, "cold_compile": reference_compile.PAIRS}.get(
        name, PAIRS
    )


def measurement(name, reference, current=ROOT, slowdown=None, pairs=None):
    """One side-by-side measurement of a gate benchmark: per process pair the median over its
    rounds of current / reference, and `ratio`, the median over the pairs (a pair now and then
    reads 5-10 % off for its whole life, so pairs are the independent draws, not rounds). The MPI
    step and the cold compile have their own schemes with the same output."""
    pairs = pairs or default_pairs(name)
    if name == "mpi_two_rank_step":
        return reference_mpi.measurement(reference, current, slowdown, pairs)
    if name == "cold_compile":
        return reference_compile.measurement(reference, current, slowdown, pairs)
    rounds = [alternating_times(name, reference, current, slowdown) for _ in range(pairs)]
    per_pair = [statistics.median(n / r for r, n in pair) for pair in rounds]
    return {"ratio": statistics.median(per_pair), "pair_ratios": per_pair}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("name", choices=list(SIDE_BY_SIDE))
    ap.add_argument("--commit", help="baseline commit (default: the one in baselines/gate.json)")
    ap.add_argument("--pairs", type=int, help="process pairs (default: the benchmark's own)")
    ap.add_argument("--slowdown", type=float)
    args = ap.parse_args(argv)
    if args.commit is None:
        args.commit = json.loads((HERE / "baselines" / "gate.json").read_text())["commit"]
    m = measurement(args.name, reference_tree(args.commit), slowdown=args.slowdown, pairs=args.pairs)
    pairs = ", ".join(f"{r:.3f}" for r in m["pair_ratios"])
    print(f"{args.name}: current / {args.commit[:10]} = {m['ratio']:.4f} (pair ratios {pairs})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
