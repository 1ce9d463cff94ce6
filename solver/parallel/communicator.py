"""One interface for serial and MPI runs: the physics only ever sees this.

The serial communicator is the identity; the MPI one (issue 4) implements the same
methods with mpi4py reductions, halo exchange and migration.
"""

from __future__ import annotations

import numpy as np


class SerialCommunicator:
    rank = 0
    size = 1

    def min(self, value):
        return value

    def max(self, value):
        return value

    def sum(self, value):
        return value

    def any(self, flag):
        return bool(flag)

    def barrier(self):
        pass

    def is_root(self):
        return True

    def setup(self, scene):
        """MPI: the domain box and the scene's [parallel] settings; serial: nothing."""

    def rebalance_due(self, step, n_owned):
        """MPI: collective check of the load imbalance (True forces a rebuild with new cuts)."""
        return False

    def owns(self, x):
        """Which rows of x this process owns (a new particle is appended by its owner only)."""
        return np.ones(len(x), dtype=bool)

    # Halo: a serial run has no ghosts.
    def migrate(self, particles):
        pass

    def build_halo(self, particles, reach, fields):
        particles.n_ghost = 0

    def refresh_halo(self, particles, fields):
        pass

    # Output: fields of all owned particles, sorted by global id, on the root rank.
    def gather_owned(self, particles, names):
        order = np.argsort(particles.owned("id"), kind="stable")
        out = {name: particles.owned(name)[order].copy() for name in names}
        out["rank"] = np.zeros(len(order), dtype=np.int32)
        return out

    def bcast(self, value):
        return value

    # Checkpoints (solver/output/checkpoint.py): any picklable value, one per rank.
    def gather(self, value):
        """[value of each rank] on the root (None elsewhere)."""
        return [value]

    def allgather(self, value):
        """[value of each rank] on every rank."""
        return [value]

    def decomposition_state(self):
        """MPI: the current domain cuts (arrays) for a checkpoint; serial: None."""
        return None

    def restore_decomposition(self, state):
        """MPI: use these cuts (a restart on the same rank count); None: cut afresh."""

    def abort(self, message, status):
        raise SystemExit(status)

    # Faults: the MPI version makes one rank's failure end (or explain) the whole job.
    def agree(self, what, where, here=True):
        """The failure message every rank reports (MPI: that of the rank that saw it)."""
        return what, where

    def fail(self, exc):
        """An unexpected exception (MPI: print it and abort every rank); serial: re-raised by the caller."""

    def report(self):
        """Per-rank communication statistics (none in a serial run)."""
        return []
