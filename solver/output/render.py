"""Off-screen pictures of a snapshot with pyvista (no display needed): the whole domain, or a window
of it (the scour hole, solver/output/scour.py) with curves drawn over the particles."""

from __future__ import annotations

import os

if not os.environ.get("DISPLAY"):
    # no X server: ask VTK (>= 9.4) for its EGL off-screen window instead of trying X first (and warning)
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np
import pyvista as pv

from .atomic import atomic_path
from .vtk_writer import particles_polydata

# Categorical colours for `render_field = "material"`: water blue, soils in earth tones (in scene order)
WATER_COLOUR = "#2b7bba"
SOIL_COLOURS = ("#c8a165", "#8c6d46", "#d9c59a", "#6b4f2a")
BODY_COLOUR = "#9a9a9a"
# A saturated bed puts a soil and a pore-water particle at every site: drawn as equal spheres they
# z-fight into half-coloured balls. Soil is drawn first and water on top, smaller, so both show.
WATER_ON_SOIL_SIZE = 0.55
# A window's picture (render_snapshot's window) shows this share of its height again above it, empty,
# for the title and the curves' legend
TITLE_BAND = 0.35


def render_snapshot(fields, png_path, scalar="speed", title="", point_size=None, domain=None, bodies=(),
                    material_names=None, water_ids=(), window=None, curves=()):  # fmt: skip
    """A PNG of one snapshot. bodies: polygons (vertex arrays) drawn in grey; material_names and
    water_ids (the materials' names in id order and the water materials' ids) let a scene with
    water and soil draw its water on top of its soil, and `scalar = "material"` draw named colours.
    window: (lo, hi) corners of the part of the plane to show (a zoom; the particles outside it are
    left out, a band above it is left for the title), instead of the domain; curves: (points (n, 2),
    colour, label) polylines drawn over the particles, each over the ones before it, named in a legend."""
    pv.OFF_SCREEN = True
    if window is not None:
        lo, hi = (np.asarray(c, float)[:2] for c in window)
        if not np.all(hi > lo):
            raise ValueError(
                f"window: its upper corner {hi.tolist()} is not above and right of {lo.tolist()}"
            )
        xy = np.asarray(fields["position"], float)[:, :2]
        inside = np.all((xy >= lo) & (xy <= hi), axis=1)
        fields = {k: np.asarray(v)[inside] for k, v in fields.items()}
        domain = None
        hi = hi + np.array([0.0, TITLE_BAND * (hi[1] - lo[1])])  # an empty band on top: title, legend
    cloud = particles_polydata(fields)
    if scalar not in cloud.point_data:  # the scene schema refuses this (output.render_field)
        raise ValueError(f"no field '{scalar}' to render (fields: {', '.join(cloud.point_data)})")
    if window is None:
        lo, hi = (
            (np.asarray(domain[0], float), np.asarray(domain[1], float))
            if domain is not None
            else (cloud.points.min(axis=0)[:2], cloud.points.max(axis=0)[:2])
        )
    aspect = float((hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-12))
    # 20 % wider than the domain: tight() centres the domain, the colour bar sits in the margin
    plotter = pv.Plotter(off_screen=True, window_size=(1600, int(np.clip(1600 / 1.2 * aspect, 300, 1400))))
    plotter.set_background("white")
    span = float(np.max(hi - lo))
    water = (
        np.isin(np.asarray(fields["material"]).ravel(), np.asarray(water_ids, dtype=int))
        if "material" in fields
        else np.zeros(cloud.n_points, dtype=bool)
    )
    layered = bool(water.any() and (~water).any())  # water and soil in one picture
    spacing = _spacing(cloud.points[~water] if layered else cloud.points)
    size = point_size or max(2.0, 1200.0 / max(span / max(spacing, 1e-12), 1.0))
    for polygon in bodies:
        _add_body(plotter, polygon, z=-2.0 * spacing)
    # a sphere's depth bulges by its radius towards the camera: water sits two spacings above the soil
    layers = [(~water, size, 0.0), (water, WATER_ON_SOIL_SIZE * size, 2.0 * spacing)] if layered else [
        (np.ones(cloud.n_points, bool), size, 0.0)]  # fmt: skip
    legend = []  # [label, colour, face] of each material drawn and each curve
    if scalar == "material" and material_names is not None and "material" in fields:
        legend = _add_materials(plotter, cloud, layers, material_names, water_ids)
    else:
        values = np.asarray(cloud.point_data[scalar])
        values = values if values.ndim == 1 else np.linalg.norm(values, axis=1)
        clim = (float(values.min()), float(values.max())) if values.size else None
        for k, (mask, layer_size, z) in enumerate(layers):
            if not mask.any():
                continue
            part = _subset(cloud, mask, z)
            plotter.add_mesh(
                part, scalars=scalar, clim=clim, point_size=layer_size, render_points_as_spheres=True,
                cmap="viridis", show_scalar_bar=k == 0, scalar_bar_args=_bar(scalar),
            )  # fmt: skip
    if domain is not None:
        box = pv.Box(bounds=(lo[0], hi[0], lo[1], hi[1], 0, 0))
        plotter.add_mesh(box, style="wireframe", color="black")
    for k, (points, colour, label) in enumerate(curves):  # each in front of those before it
        _add_curve(plotter, points, colour, z=(4.0 + 0.5 * k) * spacing)
        legend.append([label, colour, "line"])
    if legend:
        size = (0.26, 0.03 * len(legend) + 0.02) if curves else (0.14, 0.04 * len(legend) + 0.02)
        plotter.add_legend(legend, bcolor="white", border=True, size=size, loc="upper right")
    if title:
        plotter.add_text(title, color="black", font_size=12)
    plotter.view_xy()
    plotter.enable_parallel_projection()
    if window is None:
        plotter.camera.tight(padding=0.06, view="xy")
    else:  # the window and its band, centred: its full height, its width 1/1.2 of the picture's
        centre = 0.5 * (lo + hi)
        plotter.camera.focal_point = (centre[0], centre[1], 0.0)
        plotter.camera.position = (centre[0], centre[1], 10.0 * span)
        plotter.camera.up = (0.0, 1.0, 0.0)
        width_px, height_px = plotter.window_size
        seen = max(float(hi[1] - lo[1]), 1.2 * float(hi[0] - lo[0]) * height_px / width_px)
        plotter.camera.parallel_scale = 0.5 * seen
        plotter.renderer.ResetCameraClippingRange()
    with atomic_path(png_path) as tmp:
        plotter.screenshot(str(tmp))
    plotter.close()
    return png_path


def _bar(title):
    return {"title": title, "color": "black", "vertical": True, "position_x": 0.925, "position_y": 0.1,
            "width": 0.05, "height": 0.8}  # fmt: skip


def _subset(cloud, mask, z):
    """The points of `cloud` where mask holds, with their point data, lifted by z towards the camera
    of view_xy (so they are drawn over what lies at z = 0)."""
    points = np.array(cloud.points[mask], dtype=float)
    points[:, 2] += z
    part = pv.PolyData(points)
    for name in cloud.point_data:
        part.point_data[name] = np.asarray(cloud.point_data[name])[mask]
    return part


def _add_materials(plotter, cloud, layers, names, water_ids):
    """One colour per material; returns the legend's entries [name, colour, face]."""
    material = np.asarray(cloud.point_data["material"]).ravel().astype(int)
    waters = {int(w) for w in water_ids}
    soils = [k for k in range(len(names)) if k not in waters]
    colours = {k: WATER_COLOUR for k in waters}
    colours.update({k: SOIL_COLOURS[i % len(SOIL_COLOURS)] for i, k in enumerate(soils)})
    legend = []
    for mask, layer_size, z in layers:
        for k, name in enumerate(names):
            sel = mask & (material == k)
            if not sel.any():
                continue
            plotter.add_mesh(_subset(cloud, sel, z), color=colours[k], point_size=layer_size,
                             render_points_as_spheres=True)  # fmt: skip
            if name not in [entry[0] for entry in legend]:
                legend.append([name, colours[k], "circle"])
    return legend


def _add_curve(plotter, points, colour, z):
    """A polyline in the plane, lifted by z towards the camera (drawn over the particles)."""
    p = np.asarray(points, float)
    line = pv.lines_from_points(np.column_stack([p[:, 0], p[:, 1], np.full(len(p), z)]))
    plotter.add_mesh(line, color=colour, line_width=4)


def _add_body(plotter, vertices, z):
    """A rigid body's polygon, filled grey with a black outline."""
    v = np.asarray(vertices, float)
    points = np.column_stack([v[:, :2], np.full(len(v), z)])
    face = np.concatenate([[len(v)], np.arange(len(v))])
    polygon = pv.PolyData(points, faces=face)
    plotter.add_mesh(polygon, color=BODY_COLOUR, show_edges=True, edge_color="black", line_width=2)


def _spacing(points):
    """Rough particle spacing from the bounding box and count (for the marker size)."""
    n = len(points)
    area = np.prod(np.maximum(np.ptp(points[:, :2], axis=0), 1e-12))
    return float(np.sqrt(area / max(n, 1)))
