"""SIGINT and SIGTERM end a run cleanly: a checkpoint at the end of the current step, then exit.

The handler only records the signal; the run loop looks at it after every step, through one
collective reduction under MPI (solver/output/checkpoint.py, `Checkpointer.after_step`), so
every rank stops after the same step, writes the same checkpoint and exits: none is left
waiting in a collective. mpirun (MPICH's hydra) forwards SIGINT and SIGTERM to every rank; a
signal sent to a single rank stops all of them just the same, through the reduction.

A second SIGINT or SIGTERM while the checkpoint is pending stops at once, without one
(the previous checkpoint stays).
"""

from __future__ import annotations

import os
import signal
import sys
import threading

SIGNALS = (signal.SIGINT, signal.SIGTERM)


def exit_status(signum: int) -> int:
    """128 + the signal number, as shells report a process ended by it: 130 SIGINT, 143 SIGTERM."""
    return 128 + int(signum)


class Interrupted(Exception):
    """A run stopped by SIGINT or SIGTERM after writing a checkpoint (or failing to)."""

    def __init__(self, signum, t, step, checkpoint, error=None):
        self.signum, self.t, self.step, self.checkpoint, self.error = int(signum), t, step, checkpoint, error
        self.signame = signal.Signals(self.signum).name
        super().__init__(f"interrupted by {self.signame} at t = {t:.6g} s (step {step})")

    @property
    def status(self):
        return exit_status(self.signum)


class StopSignals:
    """Records SIGINT/SIGTERM while installed (a context manager); `pending` is the signal
    number or 0. Only the main thread can install handlers: elsewhere this does nothing."""

    def __init__(self, announce=True, on_second=None):
        """`on_second(signum)`: what a second signal does instead of the default (under MPI: end
        every rank through MPI_Abort, as the other ranks may wait in a collective)."""
        self.pending = 0
        self.announce = announce
        self.on_second = on_second
        self._old = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                self._old[sig] = signal.signal(sig, self._handler)
        return self

    def __exit__(self, *exc):
        for sig, old in self._old.items():
            signal.signal(sig, old)
        self._old.clear()

    def _handler(self, signum, frame):
        if self.pending:  # the second one: stop now, as if no handler were installed
            self.__exit__()
            if self.on_second is not None:
                self.on_second(signum)
            if signum == signal.SIGINT:
                raise KeyboardInterrupt
            os.kill(os.getpid(), signum)
            return
        self.pending = signum
        if self.announce:
            sys.stderr.write(
                f"\nscoursph: {signal.Signals(signum).name} received: writing a checkpoint at the end of "
                "this step, then stopping (send it again to stop at once, without one)\n"
            )
            sys.stderr.flush()
