"""Speed of one full step of the soil column collapse (issue 3), in particle-steps per second.

    make bench
    .venv/bin/python -m pytest benchmarks/bench_soil_step.py --benchmark-only -o addopts="" -s

The Bui et al. (2008) collapse scene (Drucker-Prager, artificial viscosity, artificial stress,
no-slip floor, geostatic start) refined to ~25k particles, disordered like the water benchmark
(+-0.15 dx jitter, random velocities; a perfect lattice hides branch and cache costs,
DESIGN.md). A soil step carries the stress pass, the return mapping, the Hooke-Jaumann rate,
and 6 stress components more per particle through images than a water step.
extra_info as in bench_step.py.
"""

import numba
import numpy as np
import pytest
from dam_break_setup import disordered

from solver.simulation import Simulation
from verification.column_collapse import H0, L0, scene_at


def soil_collapse(n_particles):
    dx = float(np.sqrt(L0 * H0 / n_particles))
    return disordered(Simulation(scene_at(dx)))


@pytest.mark.parametrize("threads", [1, 2])
def test_soil_step(benchmark, threads):
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    sim = soil_collapse(25_000)
    n = sim.particles.n_owned
    benchmark.pedantic(sim.step, rounds=40, iterations=1, warmup_rounds=2)
    benchmark.extra_info.update(
        particles=n,
        threads=numba.get_num_threads(),
        particle_steps_per_s=n / benchmark.stats.stats.median,
        particle_steps_per_s_incl_rebuilds=n / benchmark.stats.stats.mean,
        rebuild_fraction=sim.rebuilds / max(sim.step_count, 1),
    )
    print(
        f"\nsoil step, {n} particles, {numba.get_num_threads()} thread(s): "
        f"{n / benchmark.stats.stats.median / 1e6:.2f} M particle-steps/s (median), "
        f"{n / benchmark.stats.stats.mean / 1e6:.2f} M incl. rebuilds"
    )
