"""What the erosion law (issue 24; docs/erosion.md) adds to a saturated-bed step.

    .venv/bin/python -m pytest benchmarks/bench_erosion_step.py --benchmark-only -o addopts="" -s
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_erosion_step.py     # CPU-time minima, 1 thread

The saturated bed of bench_seepage_step.py (~10k soil particles, as many pore-water particles, a
0.05 m pond; disordered), its sand with and without a grain size (0.5 mm): the whole step of each,
and the five erosion terms alone (bed surface over soil neighbours; free water, the bed shear on
water over their soil neighbours; Shields pick-up over water neighbours; the bed shear on soil) on the
eroding state. Printed as a share of the saturated step without erosion. The
pond is at rest, so the pick-up samples every surface particle's water and finds theta = 0: the
cost of the pass, not of an active bed (the per-pair work is the same).
"""

import time

import numba
import numpy as np
import pytest
from bench_seepage_step import bed

from verification import seepage_common as sc

EROSION_TERMS = ("bed surface", "free water", "shields pick-up", "bed shear on water", "bed shear on soil")
D50 = 5e-4
_results = {}


def _threads(threads):
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))


def _report(benchmark, name, sim, threads):
    median = benchmark.stats.stats.median
    _results[(name, threads)] = median
    base = _results.get(("saturated step", threads))
    share = f", {median / base:.3f} x the saturated step" if base else ""
    benchmark.extra_info.update(soil_particles=len(sc.soil_rows(sim)), threads=numba.get_num_threads())
    print(f"\n{name}, {numba.get_num_threads()} thread(s): {1e3 * median:.2f} ms{share}")


@pytest.mark.parametrize("threads", [1, 2])
def test_saturated_step(benchmark, threads):
    _threads(threads)
    sim = bed(True)
    benchmark.pedantic(sim.step, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "saturated step", sim, threads)


@pytest.mark.parametrize("threads", [1, 2])
def test_eroding_step(benchmark, threads):
    _threads(threads)
    sim = bed(True, grain_size=D50)
    benchmark.pedantic(sim.step, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "eroding saturated step", sim, threads)


@pytest.mark.parametrize("threads", [1, 2])
def test_erosion_passes(benchmark, threads):
    _threads(threads)
    sim = bed(True, grain_size=D50)
    sim.step()
    terms = [t for t in sim.plan.terms if t.name in EROSION_TERMS]
    assert len(terms) == len(EROSION_TERMS)

    def passes():
        for t in terms:
            t.run(sim.ctx)

    benchmark.pedantic(passes, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "erosion passes", sim, threads)


def cpu_minima(repeats=15):
    """CPU-time minima at one thread (a loaded host's preemptions do not count), the two beds
    interleaved round by round."""
    sims = {"saturated": bed(True), "eroding": bed(True, grain_size=D50)}
    for sim in sims.values():
        sim.step()
    erosion = [t for t in sims["eroding"].plan.terms if t.name in EROSION_TERMS]
    best = {}
    for _ in range(repeats):
        for kind, sim in sims.items():
            start = time.process_time()
            sim.step()
            best[kind] = min(best.get(kind, np.inf), time.process_time() - start)
        start = time.process_time()
        for t in erosion:
            t.run(sims["eroding"].ctx)
        best["passes"] = min(best.get("passes", np.inf), time.process_time() - start)
    n, n_soil = sims["saturated"].particles.n_owned, len(sc.soil_rows(sims["saturated"]))
    print(f"{n} particles ({n_soil} soil), one thread, CPU-time minima of {repeats}:")
    for kind, t in best.items():
        print(f"  {kind:10s} {1e3 * t:7.2f} ms  {t / best['saturated']:.3f} x the saturated step")


if __name__ == "__main__":
    cpu_minima()
