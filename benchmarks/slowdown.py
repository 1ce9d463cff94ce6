"""A controlled slowdown for showing that the benchmark gate catches one (benchmarks/gate.py).

SCOURSPH_BENCH_SLOWDOWN=0.10 makes every timed call of a gate benchmark 10 % longer: after the
call returns, a busy loop spins for 0.10 x the call's own wall time and CPU time (whichever
ends later), so the call is at least 10 % slower by either clock. It lives in the benchmark
harness only (this file, bench_gate.py, mpi_step.py and the cold-start script); no solver code
reads the variable, so a production run can never be slowed by it.
"""

from __future__ import annotations

import os
import time

ENV = "SCOURSPH_BENCH_SLOWDOWN"


def fraction():
    return float(os.environ.get(ENV, "0") or 0.0)


def spin_after(t0, c0=None, fraction_=None):
    """Busy-wait until fraction x (now - t0) more wall time has passed and, if c0 (a
    time.process_time() reading) is given, fraction x the CPU time since c0 more CPU time:
    the call then looks at least that much slower by either clock. Returns the wall time since t0."""
    f = fraction() if fraction_ is None else fraction_
    now, cpu = time.perf_counter(), time.process_time()
    if f > 0.0:
        wall_end = now + f * (now - t0)
        cpu_end = cpu + f * (cpu - c0) if c0 is not None else cpu
        while time.perf_counter() < wall_end or time.process_time() < cpu_end:
            pass
    return time.perf_counter() - t0
