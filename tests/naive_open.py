"""Slow, obviously correct NumPy twins of the open-boundary and body kernels (solver/physics/bodies.py,
outlet.py)."""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as PolygonPath


def body_images(x, reach, edges, convex_vertices=()):
    """[(source row, image position, reflection matrix)] for edges [(a, b, outward normal)] and, for
    a particle within reach of a convex vertex and on no edge's strip, its point mirror through it
    (R = I - 2 m m^T, m the unit vector from the vertex). Rows ordered as the kernel: corners first."""
    out = []
    for i, xi in enumerate(x):
        for v in convex_vertices:
            r = xi - v
            dist = np.linalg.norm(r)
            on_strip = False
            for a, b, n in edges:
                t = (b - a) / np.linalg.norm(b - a)
                on_strip |= (xi - a) @ n >= 0 and 0 <= (xi - a) @ t <= np.linalg.norm(b - a)
            inside = inside_polygon(xi[None], np.array([e[0] for e in edges]))[0]
            if 0 < dist < reach and not on_strip and not inside:
                m = r / dist
                out.append((i, 2 * v - xi, np.eye(2) - 2.0 * np.outer(m, m)))
        for a, b, n in edges:
            t = (b - a) / np.linalg.norm(b - a)
            dist = (xi - a) @ n
            foot = (xi - a) @ t
            if 0.0 <= dist < reach and 0.0 <= foot <= np.linalg.norm(b - a):
                R = np.eye(2) - 2.0 * np.outer(n, n)
                out.append((i, xi - 2.0 * dist * n, R))
    return out


def rotate_tensor(R, T6):
    """T' = R T R^T with the 6-component storage (xx, yy, zz, xy, yz, xz)."""
    T = np.array([[T6[0], T6[3], T6[5]], [T6[3], T6[1], T6[4]], [T6[5], T6[4], T6[2]]])
    R3 = np.eye(3)
    R3[:2, :2] = R
    S = R3 @ T @ R3.T
    return np.array([S[0, 0], S[1, 1], S[2, 2], S[0, 1], S[1, 2], S[0, 2]])


def inside_polygon(x, vertices):
    return PolygonPath(np.asarray(vertices, float)).contains_points(x)


def in_boxes(x, lo, hi):
    inside = np.all((x[:, None, :] >= lo[None]) & (x[:, None, :] <= hi[None]), axis=2)
    return np.where(inside.any(axis=1), inside.argmax(axis=1), -1)


def _on_strip(p, a, b, n):
    """In front of edge (a, b) with the foot on it."""
    t = (b - a) / np.linalg.norm(b - a)
    return (p - a) @ n >= 0.0 and 0.0 <= (p - a) @ t <= np.linalg.norm(b - a)


def _nearest_is_vertex(p, v, edges):
    """The point of the (convex) polygon's boundary nearest to p is the vertex v: p is in the wedge
    outside v."""
    best = np.inf
    for a, b, _ in edges:
        t = b - a
        s = np.clip((p - a) @ t / (t @ t), 0.0, 1.0)
        best = min(best, np.linalg.norm(p - (a + s * t)))
    return np.isclose(np.linalg.norm(p - v), best, rtol=1e-12, atol=0.0) and not any(
        _on_strip(p, a, b, n) for a, b, n in edges
    )


def prune_to_own_region(targets, start, index, x, first, tag, edges, convex_vertices):
    """Twin of bodies.prune_to_own_region: the neighbour rows kept per target, as lists. A pair
    (target, image) is kept if the target is where the image's mirror applies: on the strip in front
    of the image's edge (tag >= 0), or nearest to the image's convex vertex (tag -1 - c)."""
    kept = []
    for t, i in enumerate(targets):
        row = []
        for j in index[start[t] : start[t + 1]]:
            k = j - first
            if 0 <= k < len(tag):
                g = tag[k]
                if g >= 0:
                    ok = _on_strip(x[i], *edges[g])
                else:
                    ok = _nearest_is_vertex(x[i], convex_vertices[-1 - g], edges)
                if not ok:
                    continue
            row.append(int(j))
        kept.append(row)
    return kept


def body_repulsion(x, r0, d_coef, edges, convex_vertices):
    """Twin of body_repulsion.body_repulsion: edges as (a, b, outward normal), convex vertices as
    (v, arriving edge direction, leaving edge direction)."""
    acc = np.zeros_like(x)
    for i, p in enumerate(x):
        for a, b, n in edges:
            t = (b - a) / np.linalg.norm(b - a)
            dist = np.dot(p - a, n)
            foot = np.dot(p - a, t)
            if abs(dist) < r0 and 0.0 <= foot <= np.linalg.norm(b - a):
                d = max(dist, 1e-6 * r0)
                acc[i] += d_coef * ((r0 / d) ** 12 - (r0 / d) ** 4) / d * n
        for v, t_in, t_out in convex_vertices:
            r = p - v
            if np.dot(r, t_in) > 0.0 and np.dot(r, t_out) < 0.0 and 0.0 < np.linalg.norm(r) < r0:
                d = np.linalg.norm(r)
                acc[i] += d_coef * ((r0 / d) ** 12 - (r0 / d) ** 4) / d * r / d
    return acc


def left_boxes(x, lo, hi, zone):
    """Twin of outlet.left_boxes: the box a buffer particle (zone >= 0) has left, else -1."""
    k = np.maximum(zone, 0)
    outside = np.any((x < lo[k]) | (x > hi[k]), axis=1)
    return np.where((zone >= 0) & outside, zone, -1)
