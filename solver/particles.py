"""Particle storage: one structure of arrays, only the fields the plan asks for.

Rows are laid out as [owned | ghosts | images]:
  [0, n_owned)            particles this process integrates,
  [n_owned, n_local)      copies of other ranks' particles near a cut (MPI halo),
  [n_local, n_total)      wall image particles (seed sec. 2.5), rebuilt with the neighbour lists.
Arrays keep spare capacity so particles can be added (inflow) or removed (outflow) during
a run; every particle keeps a global id for life.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np


class Mirror(Enum):
    """How a wall image particle takes a field from its source (seed sec. 2.5, eq. 23)."""

    NONE = "not needed on images"
    POSITION = "x' = s x + o"
    VELOCITY = "v' = s v (free slip: normal part reversed; no slip: all reversed)"
    SCALAR = "copied"
    TENSOR = "T'_ab = s_a s_b T_ab (eq. 23; kept across no-slip walls)"
    DIRECTION = "d' = s d (a geometric vector, as a position without the offset, at every wall kind)"


@dataclass(frozen=True)
class FieldSpec:
    components: int  # 0 for a scalar, else the size of the trailing axis
    dtype: type
    reason: str  # which term needs it (printed by --explain)
    mirror: Mirror = Mirror.NONE  # how images get it, if a term reads it from neighbours
    constant: bool = False  # never changes for a particle: ghosts and images get it at rebuilds only
    default: float = 0.0  # the value of a new particle that is not given one (append_owned)

    def nbytes_per_particle(self):
        return np.dtype(self.dtype).itemsize * max(self.components, 1)


class ParticleSet:
    GROWTH = 1.5

    def __init__(self, dim: int, specs: dict[str, FieldSpec], capacity: int):
        self.dim = dim
        self.specs = dict(specs)
        self.capacity = 0
        self.arrays: dict[str, np.ndarray] = {}
        self.n_owned = self.n_ghost = self.n_image = 0
        self.next_id = 0
        self._allocate(max(int(capacity), 16))

    # -- sizes -----------------------------------------------------------------
    @property
    def n_local(self):
        return self.n_owned + self.n_ghost

    @property
    def n_total(self):
        return self.n_local + self.n_image

    def __getitem__(self, name) -> np.ndarray:
        return self.arrays[name]

    def __contains__(self, name):
        return name in self.arrays

    def owned(self, name) -> np.ndarray:
        return self.arrays[name][: self.n_owned]

    def nbytes(self):
        return sum(a.nbytes for a in self.arrays.values())

    # -- memory ----------------------------------------------------------------
    def _shape(self, spec, n):
        return (n,) if spec.components == 0 else (n, spec.components)

    def _allocate(self, capacity):
        for name, spec in self.specs.items():
            new = np.zeros(self._shape(spec, capacity), dtype=spec.dtype)
            if name in self.arrays:
                new[: self.n_total] = self.arrays[name][: self.n_total]
            self.arrays[name] = new
        self.capacity = capacity

    def ensure_capacity(self, n):
        """Room for n rows; grows geometrically so repeated growth stays O(N)."""
        if n > self.capacity:
            self._allocate(max(n, int(self.capacity * self.GROWTH) + 1))

    # -- changing the particle count -------------------------------------------
    def drop_halo(self):
        """Forget ghosts and images (they are rebuilt with the neighbour lists)."""
        self.n_ghost = self.n_image = 0

    def append_owned(self, **fields):
        """Add owned particles (set-up, inflow, migration); new ids unless `id` is given."""
        n_new = len(next(iter(fields.values())))
        unknown = set(fields) - set(self.arrays)
        if unknown:
            raise KeyError(f"no such particle field(s): {', '.join(sorted(unknown))}")
        self.drop_halo()
        self.ensure_capacity(self.n_owned + n_new)
        rows = slice(self.n_owned, self.n_owned + n_new)
        for name, array in self.arrays.items():  # fields not given start at their default
            array[rows] = fields.get(name, self.specs[name].default)
        if "id" not in fields:
            self.arrays["id"][rows] = np.arange(self.next_id, self.next_id + n_new)
        self.next_id = max(self.next_id, int(self.arrays["id"][rows].max()) + 1) if n_new else self.next_id
        self.n_owned += n_new

    def remove_owned(self, keep: np.ndarray):
        """Keep only owned rows where `keep` is true (outflow, migration)."""
        self.drop_halo()
        self.permute_owned(np.flatnonzero(keep))

    def permute_owned(self, order: np.ndarray):
        """Reorder (or subset) the owned rows, e.g. into cell order for memory locality."""
        n = len(order)
        for arr in self.arrays.values():
            arr[:n] = arr[order]
        self.n_owned = n

    def take_owned(self, rows: np.ndarray) -> dict[str, np.ndarray]:
        """Copies of the given owned rows of every field (for migration and checkpoints)."""
        return {name: arr[rows].copy() for name, arr in self.arrays.items()}
