"""Pack rows of several particle fields into one byte matrix and back (vectorised NumPy).

A message is a C-contiguous uint8 array of shape (rows, row_bytes): the fields side by side in
a fixed order, each as the raw bytes of its row. Consecutive rows for one destination are a
contiguous slice, so one buffer serves every neighbour with no per-particle Python loop.
"""

from __future__ import annotations

import numpy as np


def row_layout(arrays: dict, names) -> list[tuple[str, int, int]]:
    """[(name, first byte, last byte)] of each field within a packed row."""
    out, at = [], 0
    for name in names:
        a = arrays[name]
        nb = a.dtype.itemsize * (1 if a.ndim == 1 else a.shape[1])
        out.append((name, at, at + nb))
        at += nb
    return out


def row_bytes(layout) -> int:
    return layout[-1][2] if layout else 0


def pack(arrays: dict, layout, rows: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Bytes of arrays[name][rows] for every field of the layout, one row per particle."""
    n = len(rows)
    buf = out if out is not None else np.empty((n, row_bytes(layout)), dtype=np.uint8)
    if n == 0:
        return buf
    for name, b0, b1 in layout:
        vals = np.ascontiguousarray(arrays[name][rows])
        buf[:, b0:b1] = vals.reshape(n, -1).view(np.uint8)
    return buf


def unpack(buf: np.ndarray, arrays: dict, layout, first: int):
    """Write the rows of buf into arrays[name][first:first + len(buf)]."""
    n = len(buf)
    if n == 0:
        return
    for name, b0, b1 in layout:
        dst = arrays[name]
        vals = np.ascontiguousarray(buf[:, b0:b1]).view(dst.dtype)
        dst[first : first + n] = vals.reshape(dst[first : first + n].shape)


def unpack_dict(buf: np.ndarray, dtypes: dict, shapes: dict, layout) -> dict:
    """Rows of buf as new arrays {name: values} (migration: appended with append_owned)."""
    n = len(buf)
    out = {}
    if n == 0:
        return {name: np.zeros((0,) + shapes[name], dtype=dtypes[name]) for name, _, _ in layout}
    for name, b0, b1 in layout:
        vals = np.ascontiguousarray(buf[:, b0:b1]).view(dtypes[name])
        out[name] = vals.reshape((n,) + shapes[name])
    return out
