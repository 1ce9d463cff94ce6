"""Particle blocks: lattice points of a rectangle (any dimension) or a 2D polygon.

All blocks share one lattice, x = domain.min + (i + 1/2) dx, so that blocks tile without
gaps or overlaps and the first layer sits dx/2 from a wall, where its image particle
(seed sec. 2.5) lands exactly one spacing away on the mirrored lattice.

The functions read a scene (solver.scene.Scene) and its blocks (RectangleBlock, PolygonBlock) but do
not import solver/scene.py: a block is told by its shape tag, the discriminator of the scene's Block
union, so that the scene's checks can count and compare the blocks' lattice points (overlapping_blocks,
estimated_particles) without an import circle (tests/test_import_graph.py).
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as PolygonPath


def _lattice(lo, hi, origin, dx):
    """Lattice points with centres in [lo, hi) along each axis."""
    axes = []
    for a in range(len(lo)):
        i0 = int(np.ceil((lo[a] - origin[a]) / dx - 0.5 - 1e-9))
        i1 = int(np.floor((hi[a] - origin[a]) / dx - 0.5 - 1e-9))
        axes.append(origin[a] + (np.arange(i0, i1 + 1) + 0.5) * dx)
    grids = np.meshgrid(*axes, indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def _is_rectangle(block) -> bool:
    """A RectangleBlock (shape "rectangle") rather than a PolygonBlock (shape "polygon")."""
    if block.shape == "rectangle":
        return True
    assert block.shape == "polygon", block.shape
    return False


def block_points(block, scene) -> np.ndarray:
    """Positions (n, dim) of the particles of one block of the scene."""
    dx = scene.scene.spacing
    origin = np.asarray(scene.domain.min, dtype=float)
    if _is_rectangle(block):
        return _lattice(np.asarray(block.min, float), np.asarray(block.max, float), origin, dx)
    verts = np.asarray(block.vertices, float)
    candidates = _lattice(verts.min(axis=0), verts.max(axis=0) + dx, origin, dx)
    inside = PolygonPath(verts).contains_points(candidates, radius=1e-12 * dx)
    return candidates[inside]


def clear_of_bodies(points: np.ndarray, scene) -> np.ndarray:
    """Mask of the points a rigid body leaves free: outside every body and at least dx/2 from its
    edges. A block may overlap a body (a layer laid against an inclined face, a bed around a
    pile), and the body carves it. dx/2 is where the lattice puts the first layer at a box wall,
    so a particle's image across an edge is at least one spacing away and the body's repulsion
    backstop (zero beyond dx/2, body_repulsion.py) is not loaded at t = 0: a lattice point
    0.1 dx from an inclined edge was shot out of a resting layer at 80 m/s by it."""
    free = np.ones(len(points), dtype=bool)
    if len(points) == 0 or points.shape[1] != 2:
        return free  # bodies are 2D (scene_open.py refuses them elsewhere)
    half = 0.5 * scene.scene.spacing
    for body in scene.bodies:
        verts = np.asarray(body.vertices, float)
        free &= ~PolygonPath(verts).contains_points(points)
        for a, b in zip(verts, np.roll(verts, -1, axis=0)):
            e = b - a
            s = np.clip((points - a) @ e / (e @ e), 0.0, 1.0)  # foot of each point on the edge
            free &= np.hypot(*(points - a - s[:, None] * e).T) >= half * (1.0 - 1e-9)
    return free


def block_top(block) -> float:
    """Highest point of a block: the free surface of a hydrostatic start."""
    if _is_rectangle(block):
        return float(block.max[-1])
    return float(np.max(np.asarray(block.vertices)[:, -1]))


def block_span(block) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners of a block's bounding box."""
    if _is_rectangle(block):
        return np.asarray(block.min, float), np.asarray(block.max, float)
    verts = np.asarray(block.vertices, float)
    return verts.min(axis=0), verts.max(axis=0)


def estimated_particles(scene) -> float:
    """Particle count from the blocks' extents (an upper bound of the lattice count, cheap:
    computed before any lattice is built, so a far too small spacing is refused at once)."""
    dx = scene.scene.spacing
    total = 0.0
    for block in scene.blocks:
        lo, hi = block_span(block)
        with np.errstate(over="ignore"):  # inf for far too many: refused by the caller
            total += float(np.prod(np.floor((hi - lo) / dx) + 1.0))
    return total


def _lattice_index(points, origin, dx):
    """Integer lattice coordinates of lattice points (exact: points sit at (i + 1/2) dx)."""
    return np.rint((points - origin) / dx - 0.5).astype(np.int64)


def overlapping_blocks(scene):
    """((i, j), n): a pair of blocks i < j that put particles at n shared lattice sites, or
    None. Blocks that merely touch share no site: a lattice point belongs to the block whose
    [min, max) holds it."""
    if not scene.blocks:  # a scene filled by inlets only
        return None
    origin = np.asarray(scene.domain.min, dtype=float)
    dx = scene.scene.spacing
    idx = [_lattice_index(block_points(b, scene), origin, dx) for b in scene.blocks]
    labels = np.concatenate([np.full(len(a), j) for j, a in enumerate(idx)])
    if len(labels) == 0:
        return None
    sites = np.concatenate(idx) + 1  # blocks lie in the domain: indices from -1 up
    shape = sites.max(axis=0) + 1
    keys = np.ravel_multi_index(tuple(sites.T), tuple(shape))
    order = np.argsort(keys, kind="stable")  # stable: equal keys keep block order
    keys, labels = keys[order], labels[order]
    dup = np.flatnonzero(keys[1:] == keys[:-1])
    if not len(dup):
        return None
    pairs = np.stack([labels[dup], labels[dup + 1]], axis=1)
    first = pairs[np.lexsort((pairs[:, 0], pairs[:, 1]))[0]]  # the lowest j, then the lowest i
    n = int(np.sum(np.all(pairs == first, axis=1)))
    return (int(first[0]), int(first[1])), n
