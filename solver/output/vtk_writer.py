"""ParaView-readable VTK time series: a .pvd collection over per-snapshot .vtp files.

Written with pyvista (the real VTK writer); each file goes through write-then-rename.
Points are 3D for VTK; a 2D scene gets z = 0 and 3-component vectors.
"""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pyvista as pv

from .atomic import atomic_path, atomic_write_text


def _pad3(a):
    if a.ndim == 2 and a.shape[1] < 3:
        return np.hstack([a, np.zeros((len(a), 3 - a.shape[1]))])
    return a


def particles_polydata(fields: dict[str, np.ndarray]) -> pv.PolyData:
    cloud = pv.PolyData(_pad3(np.asarray(fields["position"], dtype=float)))
    for name, data in fields.items():
        if name != "position":
            cloud.point_data[name] = _pad3(np.asarray(data))
    if "velocity" in fields:
        cloud.point_data["speed"] = np.linalg.norm(fields["velocity"], axis=1)
    return cloud


class VtkSeries:
    def __init__(self, out_dir, entries=None):
        """`entries`: [(time, file)] of a series being continued (a restart)."""
        self.out = Path(out_dir)
        (self.out / "vtk").mkdir(parents=True, exist_ok=True)
        self.entries: list[tuple[float, str]] = [tuple(e) for e in entries or ()]
        if entries is not None:
            self._write_collection()

    @property
    def path(self):
        return self.out / "particles.pvd"

    def write(self, t, step, fields):
        rel = f"vtk/{len(self.entries):06d}.vtp"
        with atomic_path(self.out / rel) as tmp:
            particles_polydata(fields).save(tmp)
        self.entries.append((float(t), rel))  # a NumPy scalar's repr is "np.float64(...)": not for ParaView
        self._write_collection()

    def _write_collection(self):
        rows = "\n".join(
            f'    <DataSet timestep="{t!r}" part="0" file={quoteattr(f)}/>' for t, f in self.entries
        )
        atomic_write_text(
            self.path,
            '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n",
        )
