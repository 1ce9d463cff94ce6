"""Pick the communicator: MPI when started under mpirun with more than one rank, else serial.

MPI is detected from the launcher's environment (MPICH/Intel hydra, Open MPI, PMIx as set by
`srun --mpi=pmix` and Open MPI 5, PMI-1/2, MVAPICH), so a plain serial run never initialises
MPI. SCOURSPH_MPI=1 forces the MPI path (a launcher not listed here), SCOURSPH_MPI=0 forbids it.
"""

from __future__ import annotations

import os

from .communicator import SerialCommunicator

_MPI_ENV = (
    "PMI_RANK",
    "PMI_SIZE",
    "OMPI_COMM_WORLD_SIZE",
    "HYDRA_CONTROL_FD",
    "PMI_FD",
    "PMIX_RANK",
    "MV2_COMM_WORLD_SIZE",
    "MPI_LOCALNRANKS",
)


def communicator():
    forced = os.environ.get("SCOURSPH_MPI")
    if forced == "0" or (forced != "1" and not any(k in os.environ for k in _MPI_ENV)):
        return SerialCommunicator()
    from mpi4py import MPI

    if MPI.COMM_WORLD.size == 1:
        return SerialCommunicator()
    from .mpi_communicator import MpiCommunicator

    return MpiCommunicator(MPI.COMM_WORLD)
