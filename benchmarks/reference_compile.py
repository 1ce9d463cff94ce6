"""The cold compile timed against the baseline commit's build, side by side (the gate's verdict for
`cold_compile`; docs/benchmarks.md).

A cold compile gives one sample per process (about 15-20 s of CPU, almost all of it Numba
compiling the dam break's kernels), so it cannot take turns call by call like the step benchmarks
(reference_build.py). Processes taking turns, one build's cold start after the other's on the same
core, were measured first: pair ratios 0.77 and 1.25 in one measurement, because a process lasts
long enough for the core's speed to change under it (this host's two vCPUs change speed from
minute to minute). So a pair runs the two builds' cold starts **at the same time, pinned to the
same core**: the scheduler interleaves them every few milliseconds, both see the core in the same
states, and each process's CPU time counts its own work. Then both warm starts (the same Numba
caches, filled), the same way. A pair's figure is (cold - warm) current / (cold - warm) baseline by
CPU time; a measurement is the median over PAIRS pairs. Each process has its own empty Numba cache
directory. The pairs are spread over STREAMS cores, one pair per core at a time (each pair's two
builds on one core), which halves the gate's cost. `mode="turns"` keeps the one-after-the-other
scheme for comparison.

    python benchmarks/reference_build.py cold_compile [--pairs 6] [--slowdown 0.1]
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from cold_start import result, start

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PAIRS = 4  # chosen from the measured spread (docs/benchmarks.md)
STREAMS = 2  # cores used at once, one pair each
N_PARTICLES = 2_000  # as bench_gate.py's cold_compile


def _env(slowdown):
    env = dict(os.environ, OMP_NUM_THREADS="1")
    env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
    if slowdown:
        env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
    return env


def _cpu(procs):
    return [result(p)[0][1] for p in procs]


def pair(reference, current, cpu, baseline_first=True, slowdown=None, mode="together"):
    """(baseline s, current s): cold minus warm start CPU time of each build on core `cpu`, the
    two builds at the same time (`together`) or one after the other (`turns`, baseline first or
    not). Each build has its own Numba cache, empty for the cold start, filled for the warm one."""
    with (
        tempfile.TemporaryDirectory(prefix="numba-cold-") as ref_cache,
        tempfile.TemporaryDirectory(prefix="numba-cold-") as new_cache,
    ):
        sides = [(0, reference, ref_cache, None), (1, current, new_cache, slowdown)]
        if not baseline_first:
            sides.reverse()
        times = {}
        for phase in ("cold", "warm"):
            if mode == "together":
                procs = [start(N_PARTICLES, c, r, cpu, _env(s), cpu_spin=True) for _, r, c, s in sides]
                for (i, _, _, _), t in zip(sides, _cpu(procs)):
                    times[phase, i] = t
            else:
                for i, r, c, s in sides:
                    times[phase, i] = _cpu([start(N_PARTICLES, c, r, cpu, _env(s))])[0]
    return tuple(times["cold", i] - times["warm", i] for i in (0, 1))


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


def pairs_times(reference, current=ROOT, slowdown=None, pairs=PAIRS, streams=STREAMS, mode="together"):
    """[(baseline s, current s)] of `pairs` pairs, spread over the first `streams` cores."""
    byte_compile(reference, current)
    use = cores(streams)

    def stream(j):  # the pairs of core use[j], the order of the builds alternating (and per core)
        count = len(range(j, pairs, len(use)))
        return [pair(reference, current, use[j], (k + j) % 2 == 0, slowdown, mode) for k in range(count)]

    with ThreadPoolExecutor(len(use)) as pool:
        return [t for times in pool.map(stream, range(len(use))) for t in times]


def measurement(reference, current=ROOT, slowdown=None, pairs=PAIRS, streams=STREAMS, mode="together"):
    """`ratio`: the median over the pairs of current / baseline compile time (CPU s)."""
    times = pairs_times(reference, current, slowdown, pairs, streams, mode)
    per_pair = [n / r for r, n in times]
    return {"ratio": statistics.median(per_pair), "pair_ratios": per_pair, "times": times}
