"""The 2-rank MPI step of the benchmark gate, run under mpirun (benchmarks/bench_gate.py):

    mpirun -n 2 python benchmarks/mpi_step.py --particles 10000 --rounds 150 --steps 1 --out stats.json

Public calls only (Simulation(scene, comm).step()). Each round: both ranks time the calibration
kernel of their share of the particles at once (the step also occupies both cores), then both
take `steps` steps between barriers. Rank 0 writes its per-round step and calibration times.
The controlled slowdown of benchmarks/slowdown.py, if set, spins after each rank's steps.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE.parent), str(HERE)]


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--particles", type=int, default=50_000)
    ap.add_argument("--rounds", type=int, default=20)
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--out", type=Path, required=True)
    args = ap.parse_args(argv)
    import numba

    numba.set_num_threads(1)
    from calibration import calibration
    from dam_break_setup import dam_break_scene, disordered
    from slowdown import spin_after

    from solver.parallel.launch import communicator
    from solver.simulation import Simulation

    comm = communicator()
    cal = calibration(args.particles // max(comm.size, 1))  # each rank's share
    # disordered like the serial benchmarks, each rank its own jitter
    sim = disordered(
        Simulation(dam_break_scene(args.particles), comm=comm), seed=1 + getattr(comm, "rank", 0)
    )
    for _ in range(3):  # warm-up: JIT cache load, first rebuilds
        sim.step()
    steps, steps_cpu, cals, cals_cpu = [], [], [], []
    for _ in range(args.rounds):
        comm.barrier()
        w, c = cal.measure()
        cals.append(w)
        cals_cpu.append(c)
        comm.barrier()
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(args.steps):
            sim.step()
        spin_after(t0, c0)
        comm.barrier()
        steps.append((time.perf_counter() - t0) / args.steps)
        steps_cpu.append((time.process_time() - c0) / args.steps)
    n = comm.sum(sim.particles.n_owned)
    if comm.is_root():
        args.out.write_text(
            json.dumps(
                {
                    "ranks": comm.size,
                    "particles": int(n),
                    "step_s": steps,
                    "step_cpu_s": steps_cpu,
                    "calibration_s": cals,
                    "calibration_cpu_s": cals_cpu,
                    "load_1min": os.getloadavg()[0],
                }
            )
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
