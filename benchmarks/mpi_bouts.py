"""One build's side of the 2-rank MPI step timed side by side (reference_mpi.py), run by mpirun:

    mpirun -n 2 python benchmarks/mpi_bouts.py ROOT SOCKET TAG --cores 0,1 [--particles 10000]

ROOT is the tree whose `solver` and benchmark set-up this job imports (the current tree or an
exported baseline commit). Rank r pins itself to the r-th core of --cores, sets up the dam break
(as mpi_step.py), warms up, connects to the parent's Unix socket and says `ready`. Then for each
`go K` line it reads: a barrier, K steps, the controlled slowdown (slowdown.py) if set (that
fraction of the rank's CPU time outside communication, spun), a barrier, and it answers
`wall cpu comm core`: the bout's wall time between the barriers, its own CPU time, the part of
it spent in communication and the core it last ran on (/proc/self/stat), which the parent checks
against the pin. Between bouts every rank waits in a blocking socket read, which sleeps: MPICH's
own waits busy-poll, and a job spinning in a barrier would take the core from the other build's
bout. On `stop` it answers with its CPU time since `ready` outside the bouts (the parent checks
that the idle job used next to none) and exits.
"""

from __future__ import annotations

import argparse
import os
import socket
import sys
import time
from pathlib import Path


def last_core():
    """The core this process last ran on (field 39 of /proc/self/stat)."""
    stat = Path("/proc/self/stat").read_text()
    return int(stat.rsplit(")", 1)[1].split()[36])


def comm_cpu(comm):
    """CPU s this rank has spent in communication so far (halo, migration, reductions, including
    MPICH's busy-polling waits for the other rank); 0 on a serial communicator."""
    stats = getattr(comm, "stats", None)
    return getattr(stats, "cpu", 0.0)


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("root", type=Path)
    ap.add_argument("socket")
    ap.add_argument("tag")
    ap.add_argument("--cores", required=True, help="comma-separated core per rank")
    ap.add_argument("--particles", type=int, default=10_000)
    args = ap.parse_args(argv)
    # ROOT's modules only: this script's own directory (sys.path[0], the current tree's benchmarks/)
    # would otherwise supply whatever ROOT lacks
    sys.path[0:1] = [str(args.root), str(args.root / "benchmarks")]
    import numba

    numba.set_num_threads(1)
    from dam_break_setup import dam_break_scene, disordered
    from slowdown import spin_after

    from solver.parallel.launch import communicator
    from solver.simulation import Simulation

    comm = communicator()
    rank = getattr(comm, "rank", 0)
    core = int(args.cores.split(",")[rank])
    os.sched_setaffinity(0, {core})
    sim = disordered(Simulation(dam_break_scene(args.particles), comm=comm), seed=1 + rank)
    for _ in range(3):  # warm-up: JIT cache load, first rebuilds
        sim.step()
    n = comm.sum(sim.particles.n_owned)
    link = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    link.connect(args.socket)
    reader, writer = link.makefile("r"), link.makefile("w")
    writer.write(f"ready {args.tag} {rank} {os.getpid()} {sorted(os.sched_getaffinity(0))[0]} {n}\n")
    writer.flush()
    idle_from, in_bouts = time.process_time(), 0.0
    for line in reader:
        if line.startswith("stop"):
            idle = time.process_time() - idle_from - in_bouts
            writer.write(f"{idle}\n")
            writer.flush()
            break
        k = int(line.split()[1])
        comm.barrier()
        t0, c0, m0 = time.perf_counter(), time.process_time(), comm_cpu(comm)
        for _ in range(k):
            sim.step()
        # the controlled slowdown, if set: the rank's computing (its CPU time outside communication)
        # made that fraction longer, as a slower kernel would; the gate's figure is that time
        compute = time.process_time() - c0 - (comm_cpu(comm) - m0)
        spin_after(time.perf_counter() - compute, time.process_time() - compute)
        comm.barrier()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        in_bouts += cpu
        writer.write(f"{wall} {cpu} {comm_cpu(comm) - m0} {last_core()}\n")
        writer.flush()
    link.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
