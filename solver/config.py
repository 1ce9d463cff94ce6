"""Numba flags in one place, so every kernel is compiled the same way.

`fastmath` and `error_model="numpy"` let LLVM vectorise the branchless pair loops
(DESIGN.md: 2.2x on this machine); `cache=True` keeps compiled kernels on disk across
processes, which is what makes a second run start in well under a second.
SCOURSPH_NO_PARALLEL=1 compiles the serial variants (debugging, coverage).
"""

import os

import numba
from numba import njit

# Numba's TBB threading layer leaked ~50 MB per 500 steps of the dam break on 2 threads
# here (numba 0.68, tbb from PyPI); the OpenMP and workqueue layers stay flat. OpenMP unless
# the user chose a layer.
if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "omp"

PARALLEL = os.environ.get("SCOURSPH_NO_PARALLEL", "0") != "1"

FAST = dict(cache=True, fastmath=True, error_model="numpy")


def kernel(fn=None, *, parallel=False, exact=False):
    """Decorate a per-particle or per-pair kernel with the project's Numba flags.
    exact=True compiles without fastmath, for kernels that must see NaN and inf: fastmath
    lets LLVM assume there are none and fold np.isfinite to True."""

    def wrap(f):
        flags = dict(FAST, fastmath=False) if exact else FAST
        return njit(parallel=parallel and PARALLEL, **flags)(f)

    return wrap(fn) if fn is not None else wrap
