"""Step a scene a fixed number of times, serial or under mpirun, and dump the gathered state
and the communication statistics. Used by tests/test_mpi.py and benchmarks/bench_mpi.py:

    python -m solver.parallel.driver SCENE --steps 40 [--set scene.spacing=0.002 ...]
           [--threads 1] [--state out.npz] [--stats out.json]
    mpirun -n 2 python -m solver.parallel.driver SCENE ... (same, decomposed)

--set KEY=VALUE overrides a dotted scene key (VALUE is TOML: 0.002, true, [1, 2], "a").
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tomllib
from pathlib import Path

import numpy as np


def load_with_overrides(path, overrides):
    from ..scene import parse_scene

    raw = tomllib.loads(Path(path).read_text())
    for item in overrides:
        key, value = item.split("=", 1)
        parts = key.split(".")
        node = raw
        for p in parts[:-1]:
            node = node.setdefault(p, {})
        node[parts[-1]] = tomllib.loads(f"v = {value}")["v"]
    return parse_scene(raw, path)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m solver.parallel.driver")
    ap.add_argument("scene")
    ap.add_argument("--steps", type=int, required=True)
    ap.add_argument("--set", action="append", default=[], dest="overrides")
    ap.add_argument("--threads", type=int)
    ap.add_argument("--state", type=Path, help="npz of the gathered owned state (root)")
    ap.add_argument("--stats", type=Path, help="json of timings and halo statistics (root)")
    args = ap.parse_args(argv)
    import numba

    if args.threads:
        numba.set_num_threads(args.threads)
    from ..simulation import Simulation
    from .launch import communicator

    comm = communicator()
    scene = load_with_overrides(args.scene, args.overrides)
    t_setup = time.perf_counter()
    sim = Simulation(scene, comm=comm)
    t_setup = time.perf_counter() - t_setup
    sim.step()  # warm-up step (first call of every kernel: JIT/cache load)
    comm.barrier()
    if hasattr(comm, "stats"):
        comm.stats.reset_times()  # time only the timed steps
    t0, c0 = time.perf_counter(), time.process_time()
    for _ in range(args.steps - 1):
        sim.step()
    cpu = time.process_time() - c0  # this rank's CPU time (all its threads)
    comm.barrier()
    wall = time.perf_counter() - t0
    names = [
        n
        for n in (
            "x",
            "v",
            "rho",
            "mass",
            "material",
            "id",
            "v_half",
            "rho_half",
            "mean_stress",
            "stress_dev",
            "stress_dev_half",
            "eps_vp",
            "art_stress",
            "inlet_buffer",
            "outlet_buffer",
            "suspended",
            "eroded_share",
        )
        if n in sim.particles
    ]
    state = comm.gather_owned(sim.particles, names)
    report = comm.report()
    cpus = [cpu] if not report else [None] * len(report)
    if report:
        from mpi4py import MPI

        cpus = MPI.COMM_WORLD.allgather(cpu)
    n_total = comm.sum(sim.particles.n_owned)
    if comm.is_root():
        if args.state:
            np.savez(args.state, t=sim.t, steps=sim.step_count, **state)
        stats = {
            "ranks": comm.size,
            "threads_per_rank": numba.get_num_threads(),
            "particles": int(n_total),
            "steps_timed": args.steps - 1,
            "wall_s": wall,
            "setup_s": t_setup,
            "step_s": wall / max(args.steps - 1, 1),
            "particle_steps_per_s": n_total * (args.steps - 1) / wall if wall > 0 else 0.0,
            "rebuilds": sim.rebuilds,
            "t": sim.t,
            "per_rank": report,
            # load-independent view on a shared machine: CPU seconds per step outside communication
            # on the busiest rank (a rank waiting in MPI spins, so its comm CPU time is removed)
            "cpu_s": cpus,
            "compute_cpu_step_s": max(
                c - (r["comm_cpu_s"] if report else 0.0) for c, r in zip(cpus, report or [None] * len(cpus))
            )
            / max(args.steps - 1, 1),
        }
        if report:
            comm_kinds = ("halo_refresh", "halo_build", "migrate", "reduce", "rebalance")
            per = [sum(r["time_s"].get(k, 0.0) for k in comm_kinds) for r in report]
            for k in comm_kinds:
                stats[f"{k}_s_max"] = max(r["time_s"].get(k, 0.0) for r in report)
            stats["comm_s_max"] = max(per)
            stats["comm_s_mean"] = float(np.mean(per))
            stats["ghosts_mean"] = float(np.mean([r["ghosts_mean"] for r in report]))
            stats["ghosts_total_last"] = int(sum(r["ghosts_last"] for r in report))
        text = json.dumps(stats, indent=2)
        if args.stats:
            args.stats.write_text(text + "\n")
        else:
            print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
