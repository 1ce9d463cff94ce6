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
