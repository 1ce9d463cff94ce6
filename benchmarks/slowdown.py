"""A controlled slowdown for showing that the benchmark gate catches one (benchmarks/gate.py).

SCOURSPH_BENCH_SLOWDOWN=0.10 makes every timed call of a gate benchmark 10 % longer: after the
call returns, a busy loop spins for 0.10 x the call's own wall time. It lives in the benchmark
harness only (this file, bench_gate.py, mpi_step.py and the cold-start script); no solver code
reads the variable, so a production run can never be slowed by it.
"""

from __future__ import annotations

import os
import time

ENV = "SCOURSPH_BENCH_SLOWDOWN"


def fraction():
    return float(os.environ.get(ENV, "0") or 0.0)


def spin_after(t0, fraction_=None):
    """Busy-wait until fraction x (now - t0) more has passed; return the total since t0."""
    f = fraction() if fraction_ is None else fraction_
    now = time.perf_counter()
    if f > 0.0:
        end = now + f * (now - t0)
        while time.perf_counter() < end:
            pass
    return time.perf_counter() - t0


def slowed(fn):
    """fn wrapped so that each call takes (1 + fraction) x its own time."""
    f = fraction()
    if f <= 0.0:
        return fn

    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        out = fn(*args, **kwargs)
        spin_after(t0, f)
        return out

    return wrapper
