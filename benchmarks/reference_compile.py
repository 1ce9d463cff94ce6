"""The cold compile timed against the baseline commit's build, side by side (the gate's verdict for
`cold_compile`; docs/benchmarks.md).

A cold compile gives one sample per process (about 20 s of CPU, almost all of it Numba compiling the
dam break's kernels), so it cannot take turns call by call like the step benchmarks
(reference_build.py). Instead a pair is four fresh processes on one core, one after the other:
the baseline build cold (empty Numba cache of its own) and warm (the same cache, filled), the
current build cold and warm, the order of the two builds alternating from pair to pair. A pair's
figure is (cold - warm) current / (cold - warm) baseline by CPU time, and a measurement is the
median over PAIRS pairs. Both builds of a pair run on the same core within about a minute: this
host's two vCPUs differ in speed, and which one is slow changes from minute to minute. When more
than one core is free the pairs are spread over STREAMS cores, one stream of pairs per core, each
pair still on one core; that halves the gate's cost and leaves each ratio a same-core one.

    python benchmarks/reference_compile.py [--pairs 6] [--slowdown 0.1]
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from cold_start import fresh_process

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PAIRS = 6  # chosen from the measured spread (docs/benchmarks.md)
STREAMS = 2  # cores used at once, one stream of pairs each
N_PARTICLES = 2_000  # as bench_gate.py's cold_compile


def _env(slowdown):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
    if slowdown:
        env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
    return env


def compile_cpu(root, cpu, slowdown=None):
    """CPU s of a cold start minus a warm start of `root`'s build on core `cpu` (a fresh empty Numba
    cache, filled by the cold start and read by the warm one)."""
    with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache:
        (_, cold), _, _ = fresh_process(N_PARTICLES, cache, root=root, cpu=cpu, env=_env(slowdown))
        (_, warm), _, _ = fresh_process(N_PARTICLES, cache, root=root, cpu=cpu, env=_env(slowdown))
    return cold - warm


def pair(reference, current, cpu, baseline_first, slowdown=None):
    """(baseline s, current s) of one pair on one core, in the given order."""
    if baseline_first:
        r = compile_cpu(reference, cpu)
        n = compile_cpu(current, cpu, slowdown)
    else:
        n = compile_cpu(current, cpu, slowdown)
        r = compile_cpu(reference, cpu)
    return r, n


def cores(streams=STREAMS):
    return sorted(os.sched_getaffinity(0))[:streams]


def byte_compile(*trees):
    """Write every tree's .pyc files first, so that no cold start pays for them."""
    for tree in trees:
        subprocess.run(
            [
                sys.executable,
                "-m",
                "compileall",
                "-q",
                str(Path(tree) / "solver"),
                str(Path(tree) / "benchmarks"),
            ],
            capture_output=True,
        )


def pairs_times(reference, current=ROOT, slowdown=None, pairs=PAIRS, streams=STREAMS):
    """[(baseline s, current s)] of `pairs` pairs, spread over the first `streams` cores."""
    byte_compile(reference, current)
    use = cores(streams)

    def stream(j):  # the pairs of core use[j], the order of the builds alternating (and per core)
        count = len(range(j, pairs, len(use)))
        return [pair(reference, current, use[j], (k + j) % 2 == 0, slowdown) for k in range(count)]

    with ThreadPoolExecutor(len(use)) as pool:
        return [t for times in pool.map(stream, range(len(use))) for t in times]


def measurement(reference, current=ROOT, slowdown=None, pairs=PAIRS, streams=STREAMS):
    """`ratio`: the median over the pairs of current / baseline compile time (CPU s)."""
    times = pairs_times(reference, current, slowdown, pairs, streams)
    per_pair = [n / r for r, n in times]
    return {"ratio": statistics.median(per_pair), "pair_ratios": per_pair, "times": times}
