"""A fresh Python process that imports the solver, sets up the dam break and steps it 20 times: the
cold-compile and memory benchmarks of the gate (bench_gate.py) and the cold compile timed side by
side against the baseline commit's build (reference_compile.py).

`root` is the tree whose `solver` and `benchmarks/` the process imports (the current tree or an
exported baseline commit); `cpu`, if given, pins the process to that core before anything is timed.
The controlled slowdown (slowdown.py) spins at the end, over the whole process's time, if
SCOURSPH_BENCH_SLOWDOWN is set in its environment.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

COLD = """
import os, sys, time
if {cpu!r} is not None:
    os.sched_setaffinity(0, {{{cpu!r}}})
t0, c0 = time.perf_counter(), time.process_time()
sys.path[:0] = [{root!r}, {bench!r}]
from slowdown import spin_after
import solver.simulation
def resident():
    return int(open("/proc/self/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
before = resident()
from dam_break_setup import dam_break
sim = dam_break({n})
for _ in range(20):
    sim.step()
grown = resident() - before
if {cpu_spin!r}:  # the slowdown by CPU time alone: wall time runs on while a process shares its core
    spin_after(time.perf_counter() - (time.process_time() - c0), c0)
wall = spin_after(t0, c0, 0.0) if {cpu_spin!r} else spin_after(t0, c0)
print(wall, time.process_time() - c0, grown, sim.particles.n_owned)
"""


def start(n, cache_dir, root=ROOT, cpu=None, env=None, cpu_spin=False):
    """Start the fresh process (see fresh_process); `cpu_spin`: the controlled slowdown adds its
    fraction of CPU time only, for a process that shares its core with another (its wall time is
    then not its own)."""
    env = {
        **(os.environ if env is None else env),
        "NUMBA_CACHE_DIR": str(cache_dir),
        "NUMBA_NUM_THREADS": "1",
    }
    script = COLD.format(
        root=str(root), bench=str(Path(root) / "benchmarks"), n=n, cpu=cpu, cpu_spin=cpu_spin
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )
    proc.root = root
    return proc


def result(proc):
    """((wall s, CPU s), resident-set growth, particle count) of a started process, when it ends."""
    out, err = proc.communicate()
    if proc.returncode:
        last = err.strip().splitlines()[-1:]
        raise RuntimeError(f"cold start in {proc.root} failed: {last[0] if last else 'no message'}")
    wall, cpu_s, rss, particles = out.split()
    return (float(wall), float(cpu_s)), int(rss), int(particles)


def fresh_process(n, cache_dir, root=ROOT, cpu=None, env=None):
    """(wall s, CPU s) for import, set-up, compile or cache load and 20 steps of n particles in a
    fresh process; its resident-set growth; the particle count. `env` replaces the inherited
    environment (NUMBA_CACHE_DIR and NUMBA_NUM_THREADS are set here)."""
    return result(start(n, cache_dir, root, cpu, env))
