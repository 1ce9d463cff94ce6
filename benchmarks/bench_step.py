"""Speed of one full step of the 2D dam break (issue 2), in particle-steps per second.

    make bench       (or: .venv/bin/python -m pytest benchmarks --benchmark-only -o addopts="")

Reported in extra_info: particles, threads, particle_steps_per_s (from the median step, a
step without neighbour rebuild) and particle_steps_per_s_incl_rebuilds (from the mean step,
which carries the rebuilds in their real proportion).
"""

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numba
import pytest
from dam_break_setup import dam_break
from hand_fused import hand_fused_2d

from solver.materials import Phase

ROOT = Path(__file__).resolve().parent.parent


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("n_particles", [25_000, 100_000])
def test_full_step(benchmark, n_particles, threads):
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    sim = dam_break(n_particles)
    n = sim.particles.n_owned
    rounds = 40 if n_particles < 50_000 else 12
    benchmark.pedantic(sim.step, rounds=rounds, iterations=1, warmup_rounds=2)
    benchmark.extra_info.update(
        particles=n,
        threads=numba.get_num_threads(),
        particle_steps_per_s=n / benchmark.stats.stats.median,
        particle_steps_per_s_incl_rebuilds=n / benchmark.stats.stats.mean,
        rebuild_fraction=sim.rebuilds / max(sim.step_count, 1),
    )


@pytest.mark.parametrize("variant", ["composed", "hand_fused"])
def test_composed_vs_hand_fused(benchmark, variant):
    """The plan's composed kernel (optional terms as None-able arguments) against a loop
    with the same terms written inline: viscous stress divergence, pressure, AV, XSPH."""
    numba.set_num_threads(1)
    sim = dam_break(25_000)
    ps, m = sim.particles, sim.plan.materials
    nl = sim.lists[(Phase.WATER, Phase.WATER)]
    from solver.physics import fluid_rates as fluid

    args = (nl.targets, nl.start, nl.index, ps["x"], ps["v"], ps["rho"], ps["p"], ps["mass"])
    if variant == "composed":
        call = lambda: fluid.fluid_rates(
            *args,
            ps["material"],
            m.sound_speed,
            sim.h,
            sim.norm,
            ps["drho"],
            ps["acc"],
            ps["tau"],
            m.av_alpha,
            m.av_beta,
            ps["xsph"],
            0.001,
        )
    else:
        call = lambda: hand_fused_2d(
            *args,
            ps["tau"],
            m.sound_speed[0],
            m.av_alpha[0],
            m.av_beta[0],
            0.001,
            sim.h,
            sim.norm,
            ps["drho"],
            ps["acc"],
            ps["xsph"],
        )
    benchmark.pedantic(call, rounds=60, iterations=1, warmup_rounds=3)
    benchmark.extra_info.update(pairs_per_s=nl.pairs() / benchmark.stats.stats.median)


COLD = """
import os, time, sys
def resident():
    return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
t0 = time.perf_counter()
sys.path.insert(0, {root!r}); sys.path.insert(0, {bench!r})
import solver.simulation
before = resident()
from dam_break_setup import dam_break
sim = dam_break({n})
for _ in range(20):
    sim.step()
t1 = time.perf_counter()
print(t1 - t0, resident() - before, sim.particles.n_owned)
"""


def _fresh_process(n, cache_dir):
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir, "NUMBA_NUM_THREADS": "1"}
    out = subprocess.run(
        [sys.executable, "-c", COLD.format(root=str(ROOT), bench=str(ROOT / "benchmarks"), n=n)],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    seconds, rss, particles = out.stdout.split()
    return float(seconds), int(rss), int(particles)


def test_cold_compile_and_memory(benchmark):
    """Cold start (empty Numba cache: import, set-up, compile, first steps) and the memory per
    particle: growth of the resident set over set-up and 20 steps (arrays, neighbour lists,
    cells, images), differenced between 100k and 25k particles to cancel fixed costs."""
    with tempfile.TemporaryDirectory() as cache:
        cold, _, _ = benchmark.pedantic(_fresh_process, args=(2_000, cache), rounds=1, iterations=1)
        warm, _, _ = _fresh_process(2_000, cache)
        _, rss_small, n_small = _fresh_process(25_000, cache)
        _, rss_big, n_big = _fresh_process(100_000, cache)
    benchmark.extra_info.update(
        cold_start_s=cold,
        warm_start_s=warm,
        compile_s=cold - warm,
        bytes_per_particle=(rss_big - rss_small) / (n_big - n_small),
    )
