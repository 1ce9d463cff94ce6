"""Speed of a saturated-bed step (issue 10, item 7), and what the seepage passes add to a soil step.

    make bench
    .venv/bin/python -m pytest benchmarks/bench_seepage_step.py --benchmark-only -o addopts="" -s

Three timings on the same soil particles (a sand bed, ~10k soil particles, disordered as the
other benchmarks: +-0.15 dx jitter, random velocities):
  * the dry bed's full step (soil only: the reference "soil step");
  * the saturated bed's full step (the same soil plus one pore-water particle per soil particle
    and 0.05 m of free water above: soil, water and coupling passes);
  * the seepage passes alone on the saturated state: pore pressure at soil (p~), seepage on water
    (with p^ at the water and the Biot storage), seepage on soil, i.e. the terms the coupling adds.
The issue's budget: the seepage passes add at most 40 % to a soil step with the same soil
particles, i.e. (seepage passes) / (dry soil step) <= 0.4, printed as `seepage share`. The
machine is shared: compare runs taken back to back, and note the load (`uptime`).
Public API only: Simulation(scene).step() and the plan's terms.
"""

import time

import numba
import numpy as np
import pytest
from dam_break_setup import disordered

from solver.simulation import Simulation
from verification import seepage_common as sc

N_SOIL = 10_000
WIDTH, DEPTH, WATER = 0.5, 0.2, 0.05
SEEPAGE_TERMS = ("pore pressure at soil", "seepage on water", "seepage on soil")
_results = {}


def bed(saturated, **sand):
    """The bench's sand bed (saturated: with pore water and a pond); `sand`: extra material keys."""
    dx = (WIDTH * DEPTH / N_SOIL) ** 0.5
    blocks = [{"name": "bed", "material": "sand", "shape": "rectangle", "min": [0.0, 0.0],
               "max": [WIDTH, DEPTH], "geostatic": True, "saturated": saturated}]  # fmt: skip
    mats = {"sand": sc.sand(0.4, permeability=1e-3, **sand)}
    if saturated:
        mats["water"] = sc.WATER
        blocks.append({"name": "pond", "material": "water", "shape": "rectangle", "min": [0.0, DEPTH],
                       "max": [WIDTH, DEPTH + WATER], "hydrostatic": True})  # fmt: skip
    else:  # a dry scene needs no n and k, but keeping them changes nothing
        mats["sand"] = {k: v for k, v in mats["sand"].items() if k not in ("porosity", "permeability")}
    return disordered(
        Simulation(sc.scene("seepage_bench", dx, 1.0, [WIDTH, DEPTH + WATER + 0.05], mats, blocks))
    )


def _threads(threads):
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))


def _report(benchmark, name, n_soil, threads):
    median = benchmark.stats.stats.median
    _results[(name, threads)] = median
    benchmark.extra_info.update(soil_particles=n_soil, threads=numba.get_num_threads(), median_s=median)
    dry = _results.get(("dry soil step", threads))
    share = f", {median / dry:.2f} x the dry soil step" if dry else ""
    print(
        f"\n{name}, {n_soil} soil particles, {numba.get_num_threads()} thread(s): "
        f"{1e3 * median:.2f} ms{share}"
    )


@pytest.mark.parametrize("threads", [1, 2])
def test_dry_soil_step(benchmark, threads):
    _threads(threads)
    sim = bed(False)
    benchmark.pedantic(sim.step, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "dry soil step", len(sc.soil_rows(sim)), threads)


@pytest.mark.parametrize("threads", [1, 2])
def test_saturated_bed_step(benchmark, threads):
    _threads(threads)
    sim = bed(True)
    benchmark.pedantic(sim.step, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "saturated bed step", len(sc.soil_rows(sim)), threads)


@pytest.mark.parametrize("threads", [1, 2])
def test_seepage_passes(benchmark, threads):
    """The coupling's terms on the saturated state (their refreshes are no-ops serially)."""
    _threads(threads)
    sim = bed(True)
    terms = [t for t in sim.plan.terms if t.name in SEEPAGE_TERMS]
    assert len(terms) == len(SEEPAGE_TERMS)

    def passes():
        for t in terms:
            t.run(sim.ctx)

    benchmark.pedantic(passes, rounds=30, iterations=1, warmup_rounds=2)
    _report(benchmark, "seepage passes", len(sc.soil_rows(sim)), threads)
    cpu = time.process_time()
    for _ in range(10):
        passes()
    benchmark.extra_info["cpu_s_per_call"] = (time.process_time() - cpu) / 10


def per_term_minimum(repeats=15):
    """Minimum time of the seepage terms (each, and together) and of the whole step, dry and
    saturated beds interleaved round by round so that both see the same load (docs/seepage.md,
    Speed). Other terms are not run alone: some change the state (return mapping, midpoint).
    CPU time at one thread (a loaded host's preemptions do not count), wall time with more (the
    OpenMP workers spin); minima are what a loaded machine distorts least."""
    clock = time.process_time if numba.get_num_threads() == 1 else time.perf_counter
    sims = {"dry": bed(False), "saturated": bed(True)}
    best = {}
    for _ in range(repeats):
        for kind, sim in sims.items():
            seepage = [t for t in sim.plan.terms if t.name in SEEPAGE_TERMS]
            calls = [(t.name, t.run, sim.ctx) for t in seepage] + [("whole step", sim.step, None)]
            if seepage:
                calls.append(("seepage terms together", _together(seepage), sim.ctx))
            for name, call, ctx in calls:
                start = clock()
                call() if ctx is None else call(ctx)
                elapsed = clock() - start
                best[kind, name] = min(best.get((kind, name), np.inf), elapsed)
    for kind, sim in sims.items():
        print(f"{kind} bed, {sim.particles.n_owned} particles, {len(sc.soil_rows(sim))} soil")
        for (k, name), t in best.items():
            if k == kind:
                print(f"  {name:40s} {1e3 * t:7.2f} ms")
    share = best["saturated", "seepage terms together"] / best["dry", "whole step"]
    print(f"saturated / dry step: {best['saturated', 'whole step'] / best['dry', 'whole step']:.2f}")
    print(f"seepage share: {share:.2f} x the dry soil step (issue 10 budget: 0.40)")


def _together(terms):
    def run(ctx):
        for t in terms:
            t.run(ctx)

    return run


if __name__ == "__main__":  # NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_seepage_step.py
    per_term_minimum()
