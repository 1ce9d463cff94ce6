"""The cost of a checkpoint (README "Restart", docs/restart.md): bytes per particle and the time
to write one and to read it back, against the time of a step, for a water and a soil scene.

    nice -n 10 .venv/bin/python benchmarks/studies/checkpoint_cost.py [--particles 200000] [--steps 20]

Serial, one process, the machine's load printed with the figures (a timing on a shared machine
means nothing without it). The checkpoint goes to a temporary directory on the same disk as the
repository (fsync included: that is what a real checkpoint pays).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numba

from solver.output.checkpoint import load_resume, read_header, write_checkpoint
from solver.parallel.communicator import SerialCommunicator
from solver.plan import build_plan
from solver.scene import load_scene
from solver.simulation import Simulation

ROOT = Path(__file__).resolve().parents[2]
SCENES = {
    # (file, area of the material in m^2 (2D), overrides)
    "water (dam break)": (ROOT / "scenes" / "dam_break_2d.toml", 0.05715 * 0.1143, []),
    "soil (column collapse)": (ROOT / "scenes" / "column_collapse_2d.toml", 0.2 * 0.1, []),
}


def measure(name, path, area, particles, steps, folder):
    spacing = math.sqrt(area / particles)
    scene = load_scene(path, [f"scene.spacing={spacing!r}", "output.render=false"])
    comm = SerialCommunicator()
    sim = Simulation(scene, comm=comm)
    n = sim.particles.n_owned
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.step()
    step_s = (time.perf_counter() - t0) / steps
    run_dir = Path(folder) / name.split()[0]
    run_dir.mkdir()
    writes = []
    for _ in range(3):
        t0 = time.perf_counter()
        path_ = write_checkpoint(run_dir, sim, comm, "{}", {"outputs": {}, "segments": [], "metadata": {}})
        writes.append(time.perf_counter() - t0)
        sim.step()
    size = path_.stat().st_size
    t0 = time.perf_counter()
    header = read_header(path_)
    load_resume(path_, header, build_plan(scene), comm)
    read_s = time.perf_counter() - t0
    write_s = min(writes)
    print(
        f"{name}: {n} particles, {sim.plan.bytes_per_particle()} B/particle in memory, "
        f"checkpoint {size / 1e6:.1f} MB = {size / n:.0f} B/particle; write {write_s:.3f} s "
        f"(best of 3; {', '.join(f'{w:.3f}' for w in writes)}) = {write_s / n * 1e6:.2f} s per million "
        f"particles; read {read_s:.3f} s; step {step_s * 1e3:.1f} ms: a checkpoint costs "
        f"{write_s / step_s:.1f} steps"
    )


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--particles", type=int, default=200_000)
    p.add_argument("--steps", type=int, default=20)
    args = p.parse_args()
    print(f"load before: {os.getloadavg()}; Numba threads {numba.get_num_threads()}")
    with tempfile.TemporaryDirectory(dir=ROOT) as folder:
        for name, (path, area, _) in SCENES.items():
            measure(name, path, area, args.particles, args.steps, folder)
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
