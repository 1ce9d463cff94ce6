"""Pick the communicator: MPI when started under mpirun with more than one rank, else serial."""

from __future__ import annotations

import os

from .communicator import SerialCommunicator

_MPI_ENV = ("PMI_RANK", "PMI_SIZE", "OMPI_COMM_WORLD_SIZE", "HYDRA_CONTROL_FD", "PMI_FD")


def communicator():
    if not any(k in os.environ for k in _MPI_ENV):
        return SerialCommunicator()
    from mpi4py import MPI
    if MPI.COMM_WORLD.size == 1:
        return SerialCommunicator()
    from .mpi_communicator import MpiCommunicator  # issue 4
    return MpiCommunicator(MPI.COMM_WORLD)
