"""What the mu(I) rheology (issue 24 item 1; docs/rheology.md) adds to a soil step.

    .venv/bin/python -m pytest benchmarks/bench_rheology_step.py --benchmark-only -o addopts="" -s
    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_rheology_step.py     # CPU-time minima, 1 thread

The soil collapse of bench_soil_step.py (~25k particles, disordered, random velocities, so the soil
shears everywhere), perfectly plastic (the verification scene) and with mu(I) for the bars (d = 1 mm):
the whole step of each. mu(I) costs the shear rate in the soil pass (a square root per particle) and a
branch and a square root per particle in each of the two return mappings.
"""

import time

import numba
import numpy as np
import pytest
from dam_break_setup import disordered

from solver.simulation import Simulation
from verification.column_collapse import H0, L0, scene_at

MU_I = {"numerics": {"rheology": "material"}, "materials": {"bars": {"rheology": "mu_I", "grain_size": 1e-3}}}
N_PARTICLES = 25_000


def collapse(rheology):
    dx = float(np.sqrt(L0 * H0 / N_PARTICLES))
    return disordered(Simulation(scene_at(dx, overrides=MU_I if rheology else None)))


@pytest.mark.parametrize("rheology", [False, True], ids=["perfectly_plastic", "mu_I"])
@pytest.mark.parametrize("threads", [1, 2])
def test_soil_step_with_and_without_mu_of_i(benchmark, threads, rheology):
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    sim = collapse(rheology)
    benchmark.pedantic(sim.step, rounds=30, iterations=1, warmup_rounds=2)
    benchmark.extra_info.update(particles=sim.particles.n_owned, threads=numba.get_num_threads())
    print(
        f"\nsoil step, mu(I) {rheology}, {numba.get_num_threads()} thread(s): "
        f"{1e3 * benchmark.stats.stats.median:.2f} ms"
    )


def cpu_minima(repeats=15):
    """CPU-time minima at one thread, the two collapses interleaved round by round."""
    sims = {"perfectly plastic": collapse(False), "mu(I)": collapse(True)}
    for sim in sims.values():
        sim.step()
    best = {}
    for _ in range(repeats):
        for kind, sim in sims.items():
            start = time.process_time()
            sim.step()
            best[kind] = min(best.get(kind, np.inf), time.process_time() - start)
    base = best["perfectly plastic"]
    print(f"{sims['mu(I)'].particles.n_owned} soil particles, one thread, CPU-time minima of {repeats}:")
    for kind, t in best.items():
        print(f"  {kind:18s} {1e3 * t:7.2f} ms  {t / base:.3f} x the perfectly plastic step")


if __name__ == "__main__":
    cpu_minima()
