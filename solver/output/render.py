"""Off-screen picture of a snapshot with pyvista (no display needed)."""

from __future__ import annotations

import os

if not os.environ.get("DISPLAY"):
    # no X server: ask VTK (>= 9.4) for its EGL off-screen window instead of trying X first (and warning)
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np
import pyvista as pv

from .atomic import atomic_path
from .vtk_writer import particles_polydata


def render_snapshot(fields, png_path, scalar="speed", title="", point_size=None, domain=None):
    pv.OFF_SCREEN = True
    cloud = particles_polydata(fields)
    if scalar not in cloud.point_data:  # the scene schema refuses this (output.render_field)
        raise ValueError(f"no field '{scalar}' to render (fields: {', '.join(cloud.point_data)})")
    lo, hi = (
        (np.asarray(domain[0], float), np.asarray(domain[1], float))
        if domain is not None
        else (cloud.points.min(axis=0)[:2], cloud.points.max(axis=0)[:2])
    )
    aspect = float((hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12))
    # 20 % wider than the domain: tight() centres the domain, the colour bar sits in the margin
    plotter = pv.Plotter(off_screen=True, window_size=(1600, int(np.clip(1600 / 1.2 * aspect, 300, 1400))))
    plotter.set_background("white")
    span = (
        np.ptp(np.asarray(domain), axis=0).max() if domain is not None else np.ptp(cloud.points, axis=0).max()
    )
    size = point_size or max(2.0, 1200.0 / max(span / max(_spacing(cloud.points), 1e-12), 1.0))
    plotter.add_mesh(
        cloud,
        scalars=scalar,
        point_size=size,
        render_points_as_spheres=True,
        cmap="viridis",
        scalar_bar_args={
            "title": scalar,
            "color": "black",
            "vertical": True,
            "position_x": 0.925,
            "position_y": 0.1,
            "width": 0.05,
            "height": 0.8,
        },
    )
    if domain is not None:
        box = pv.Box(bounds=(lo[0], hi[0], lo[1], hi[1], 0, 0))
        plotter.add_mesh(box, style="wireframe", color="black")
    if title:
        plotter.add_text(title, color="black", font_size=12)
    plotter.view_xy()
    plotter.enable_parallel_projection()
    plotter.camera.tight(padding=0.06, view="xy")
    with atomic_path(png_path) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()
    return png_path


def _spacing(points):
    """Rough particle spacing from the bounding box and count (for the marker size)."""
    n = len(points)
    area = np.prod(np.maximum(np.ptp(points[:, :2], axis=0), 1e-12))
    return float(np.sqrt(area / max(n, 1)))
