"""Particle blocks: lattice points of a rectangle (any dimension) or a 2D polygon.

All blocks share one lattice, x = domain.min + (i + 1/2) dx, so that blocks tile without
gaps or overlaps and the first layer sits dx/2 from a wall, where its image particle
(seed sec. 2.5) lands exactly one spacing away on the mirrored lattice.
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as PolygonPath

from .scene import PolygonBlock, RectangleBlock, Scene


def _lattice(lo, hi, origin, dx):
    """Lattice points with centres in [lo, hi) along each axis."""
    axes = []
    for a in range(len(lo)):
        i0 = int(np.ceil((lo[a] - origin[a]) / dx - 0.5 - 1e-9))
        i1 = int(np.floor((hi[a] - origin[a]) / dx - 0.5 - 1e-9))
        axes.append(origin[a] + (np.arange(i0, i1 + 1) + 0.5) * dx)
    grids = np.meshgrid(*axes, indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def block_points(block, scene: Scene) -> np.ndarray:
    """Positions (n, dim) of the particles of one block."""
    dx = scene.scene.spacing
    origin = np.asarray(scene.domain.min, dtype=float)
    if isinstance(block, RectangleBlock):
        return _lattice(np.asarray(block.min, float), np.asarray(block.max, float), origin, dx)
    assert isinstance(block, PolygonBlock)
    verts = np.asarray(block.vertices, float)
    candidates = _lattice(verts.min(axis=0), verts.max(axis=0) + dx, origin, dx)
    inside = PolygonPath(verts).contains_points(candidates, radius=1e-12 * dx)
    return candidates[inside]


def block_top(block) -> float:
    """Highest point of a block: the free surface of a hydrostatic start."""
    if isinstance(block, RectangleBlock):
        return float(block.max[-1])
    return float(np.max(np.asarray(block.vertices)[:, -1]))


def block_span(block) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of a block's bounding box."""
    if isinstance(block, RectangleBlock):
        return np.asarray(block.min, float), np.asarray(block.max, float)
    verts = np.asarray(block.vertices, float)
    return verts.min(axis=0), verts.max(axis=0)
