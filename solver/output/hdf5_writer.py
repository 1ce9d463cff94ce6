"""HDF5 time series: one file per snapshot, tied together by a small series file.

    OUT/particles.h5            series file: run metadata, the merged scene, and
                                /snapshots/NNNNNN -> external link to the snapshot file
    OUT/snapshots/NNNNNN.h5     one snapshot: fields sorted by global particle id

Each snapshot and each new version of the series file is written to a temporary name and
renamed, so a crash leaves every earlier snapshot readable. Particle counts may change
between snapshots. h5py follows the external links, so readers see one file.
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from .atomic import atomic_path


class Hdf5Series:
    def __init__(self, out_dir, metadata: dict, scene_toml: str, snapshots=None):
        """`snapshots`: [(file, time, step, count)] of a series being continued (a restart)."""
        self.out = Path(out_dir)
        (self.out / "snapshots").mkdir(parents=True, exist_ok=True)
        self.metadata = dict(metadata)
        self.scene_toml = scene_toml
        self.snapshots: list[tuple[str, float, int, int]] = [tuple(s) for s in snapshots or ()]
        self._write_series()

    @property
    def path(self):
        return self.out / "particles.h5"

    def write(self, t, step, fields: dict[str, np.ndarray]):
        key = f"{len(self.snapshots):06d}"
        rel = f"snapshots/{key}.h5"
        n = len(fields["id"])
        with atomic_path(self.out / rel) as tmp:
            with h5py.File(tmp, "w") as f:
                f.attrs["time"] = t
                f.attrs["step"] = step
                f.attrs["n_particles"] = n
                for name, data in fields.items():
                    f.create_dataset(name, data=data)
        self.snapshots.append((rel, t, step, n))
        self._write_series()

    def finish(self, **extra):
        self.metadata.update(extra)
        self._write_series()

    def _write_series(self):
        with atomic_path(self.path) as tmp:
            with h5py.File(tmp, "w") as f:
                for k, v in self.metadata.items():
                    f.attrs[k] = v if isinstance(v, (int, float, str)) else json.dumps(v)
                f.attrs["scene_toml"] = self.scene_toml
                f.create_dataset("times", data=np.array([s[1] for s in self.snapshots], dtype=float))
                f.create_dataset("steps", data=np.array([s[2] for s in self.snapshots], dtype=np.int64))
                g = f.create_group("snapshots")
                for rel, *_ in self.snapshots:
                    g[Path(rel).stem] = h5py.ExternalLink(rel, "/")


def read_series(path):
    """[(time, {field: array})] of every snapshot in a series file (for post-processing)."""
    out = []
    with h5py.File(path, "r") as f:
        times = f["times"][:]
        for k, key in enumerate(sorted(f["snapshots"])):
            snap = f["snapshots"][key]
            out.append((float(times[k]), {name: snap[name][:] for name in snap}))
    return out


def read_metadata(path):
    with h5py.File(path, "r") as f:
        return dict(f.attrs)
