"""The 2-rank MPI step timed against the baseline commit's build, side by side (the gate's verdict
for `mpi_two_rank_step`; docs/benchmarks.md).

The step benchmarks take turns call by call on one core (reference_build.py); the MPI step needs
both cores. So each build runs as its own persistent 2-rank job (benchmarks/mpi_bouts.py under
mpirun), both jobs with rank 0 pinned to core 0 and rank 1 to core 1, and this process has them
take turns in bouts: BOUT steps of the baseline build on both cores, then BOUT steps of the
current build, and so on (the order alternating from round to round), ROUNDS rounds. A job waits
for its turn in a blocking socket read, so it leaves both cores to the other. A round's figure is
current / baseline of the bout's wall time on rank 0 between two barriers (the step's cost is
that of its slower rank); a job pair's figure is the median over its rounds, and a measurement is
the median over PAIRS job pairs. Every bout reports the core each rank last ran on, and the
measurement fails if one is off its pin.

    python benchmarks/reference_mpi.py [--pairs 3] [--bout 4] [--slowdown 0.1]
"""

from __future__ import annotations

import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import NamedTuple

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
BIN = Path(sys.executable).parent
PAIRS = 3  # job pairs per measurement
ROUNDS = 100  # bouts of each build per job pair
BOUT = 4  # steps per bout, ~10 ms (docs/benchmarks.md: why 4)
PARTICLES = 10_000  # as bench_gate.py's MPI step: ~5k particles and ~2 ms per rank and step
# what a bout's figure is (Bout.estimate): rank 0's wall time, the CPU time of both ranks, or the
# busiest rank's CPU time outside communication; chosen from the measured spread (docs/benchmarks.md)
ESTIMATORS = ("wall", "cpu", "compute")
ESTIMATOR = "compute"
TIMEOUT = 300  # s for a job to set up, or for a bout


class Bout(NamedTuple):
    """One bout of one job: rank 0's wall s between the barriers, each rank's CPU s, and the part
    of it each rank spent in communication (halo, migration, reductions, MPICH's busy waits)."""

    wall: float
    cpu: list
    comm_cpu: list

    def estimate(self, estimator):
        if estimator == "wall":
            return self.wall
        if estimator == "cpu":
            return sum(self.cpu)
        return max(c - m for c, m in zip(self.cpu, self.comm_cpu))  # "compute": the busiest rank


class Job:
    """One build's 2-rank job: the mpirun process and a socket per rank (rank order)."""

    def __init__(self, root, tag, server, cores, slowdown=None):
        env = dict(os.environ, NUMBA_NUM_THREADS="1", OMP_NUM_THREADS="1")
        env.pop("SCOURSPH_BENCH_SLOWDOWN", None)
        if slowdown:
            env["SCOURSPH_BENCH_SLOWDOWN"] = str(slowdown)
        self.root, self.tag, self.cores = root, tag, cores
        self.errors = tempfile.TemporaryFile(mode="w+")  # a file: a pipe nobody reads could block it
        self.proc = subprocess.Popen(
            [
                str(BIN / "mpirun"),
                "-n",
                "2",
                sys.executable,
                str(HERE / "mpi_bouts.py"),
                str(root),
                server,
                tag,
                "--cores",
                ",".join(map(str, cores)),
                "--particles",
                str(PARTICLES),
            ],
            env=env,
            stdout=self.errors,
            stderr=self.errors,
        )
        self.ranks = [None, None]

    def failed(self, doing):
        self.errors.seek(0)
        last = self.errors.read().strip().splitlines()[-1:]
        return RuntimeError(f"MPI benchmark in {self.root} {doing}: {last[0] if last else 'no message'}")

    def bout(self, k):
        """The Bout of k steps on both ranks."""
        for r in self.ranks:
            r.write(f"go {k}\n")
            r.flush()
        answers = [r.readline().split() for r in self.ranks]
        if any(len(a) != 4 for a in answers):
            raise self.failed("stopped")
        cores = [int(a[3]) for a in answers]
        if cores != list(self.cores):
            raise RuntimeError(
                f"MPI benchmark in {self.root}: ranks ran on cores {cores}, pinned to {self.cores}"
            )
        return Bout(float(answers[0][0]), [float(a[1]) for a in answers], [float(a[2]) for a in answers])

    def stop(self):
        """CPU s each rank used outside its bouts (it should have slept)."""
        idle = []
        for r in self.ranks:
            if r is None:
                continue
            try:
                r.write("stop\n")
                r.flush()
                idle.append(float(r.readline() or "nan"))
            except (OSError, ValueError):
                idle.append(float("nan"))
        try:
            self.proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        self.errors.close()
        return idle


def cores():
    use = sorted(os.sched_getaffinity(0))
    if len(use) < 2:
        raise RuntimeError(f"the 2-rank MPI step side by side needs 2 cores, this process has {use}")
    return use[:2]


def connect(server, jobs):
    """Accept each rank's connection and file it under its job and rank; a job whose mpirun ends
    before both its ranks said `ready` fails with its last error line."""
    by_tag = {j.tag: j for j in jobs}
    server.settimeout(1.0)
    deadline = time.monotonic() + TIMEOUT
    while any(None in j.ranks for j in jobs):
        for j in jobs:
            if None in j.ranks and j.proc.poll() is not None:
                raise j.failed("did not start")
        if time.monotonic() > deadline:
            raise next(j for j in jobs if None in j.ranks).failed(f"did not start within {TIMEOUT} s")
        try:
            conn, _ = server.accept()
        except TimeoutError:
            continue
        conn.settimeout(TIMEOUT)
        f = conn.makefile("rw")
        _, tag, rank, _pid, _core, _n = f.readline().split()
        by_tag[tag].ranks[int(rank)] = f


def alternating_bouts(reference, current=ROOT, slowdown=None, rounds=ROUNDS, bout=BOUT):
    """[(baseline Bout, current Bout)] one per round, the two jobs taking turns (the order
    alternating from round to round); and {job: CPU s each rank spent outside its bouts}."""
    use = cores()
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "bouts.sock")
        server = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        server.bind(path)
        server.listen(4)
        jobs = [Job(reference, "baseline", path, use), Job(current, "current", path, use, slowdown)]
        try:
            connect(server, jobs)
            ref, new = jobs
            out = []
            for k in range(rounds):
                if k % 2 == 0:
                    r, n = ref.bout(bout), new.bout(bout)
                else:
                    n, r = new.bout(bout), ref.bout(bout)
                out.append((r, n))
            return out, {j.tag: j.stop() for j in jobs}
        except (TimeoutError, OSError) as err:
            raise jobs[0].failed(f"stopped ({err})") from None
        finally:
            for j in jobs:
                if j.proc.poll() is None:
                    j.proc.kill()
                    j.proc.wait()
            server.close()


def measurement(reference, current=ROOT, slowdown=None, pairs=PAIRS, bout=BOUT, estimator=None):
    """`ratio`: the median over job pairs of each pair's median over rounds of current / baseline,
    by ESTIMATOR; `by_estimator`, the same figure by every estimator (for the record)."""
    runs = [alternating_bouts(reference, current, slowdown, bout=bout) for _ in range(pairs)]
    by = {
        e: [statistics.median(n.estimate(e) / r.estimate(e) for r, n in times) for times, _ in runs]
        for e in ESTIMATORS
    }
    per_pair = by[estimator or ESTIMATOR]
    return {
        "ratio": statistics.median(per_pair),
        "pair_ratios": per_pair,
        "by_estimator": {e: statistics.median(v) for e, v in by.items()},
        "idle_cpu_s": [idle for _, idle in runs],
    }
