"""Scour measurement from soil particles (issue 11 item 4): the surface z_s(x, t), the scour depth
d(t), the deepest point and the eroded area, written per run as CSV and plotted.

The rule. The soil volume fraction is interpolated with the solver's kernel (seed eq. 5,
h of the scene),
    phi(x, z) = sum_j V_j W(|(x, z) - x_j|, h),   V_j = dx^dim (the lattice volume a soil particle
                                                  stands for: skeleton and pores),
with the particles mirrored across the layer's rigid base and end walls (so phi ~ 1 inside the
bed right up to them, as the solver's image particles make it). In each x-bin (centres dx apart)
z_s is the lowest height above the base at which phi falls below 1/2, scanning upward from the
base (linear interpolation between samples dx/20 apart); if phi < 1/2 already at the base, the
hole has reached it and z_s is the base. An isolated grain contributes at most
V W(0) = dx^2 (10 / 7 pi h^2) = 0.27 (h = 1.3 dx) to phi, less than 1/2, and it lies above the
first crossing anyway: one grain thrown up beyond the top row's kernel support cannot move z_s.
Closer grains lift it by a fraction of dx (tests/test_scour_measure.py: 0.41 dx for a grain resting
on the bed, 0.26 dx for one a spacing above it).

Derived per output time, with z_s0 the surface of the first snapshot by the same rule:
  d(t) = max_x (z_s0(x) - z_s(x, t)) (the scour depth), x_deepest where it is reached,
  eroded area = integral of max(z_s0 - z_s, 0) dx, deposited area = integral of max(z_s - z_s0, 0) dx.

Written per run (write_scour_outputs): scour.csv, scour_profiles.csv, scour.png (the surfaces and
d(t)) and scour_hole.png (the last snapshot zoomed on the hole, with the surfaces it is read from).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..kernels import kernel_values

SAMPLES_PER_DX = 20


@dataclass(frozen=True)
class ScourGrid:
    """Where and how the surface is read: bin centres, the base, mirror planes, kernel."""

    x_bins: np.ndarray
    z_base: float
    z_top: float
    dx: float
    h: float
    mirror_x: tuple[float, ...] = ()  # vertical rigid walls bounding the layer (x = const)

    @classmethod
    def for_layer(cls, x_lo, x_hi, z_base, z_top, dx, h, mirror_ends=True):
        bins = x_lo + (np.arange(int(round((x_hi - x_lo) / dx))) + 0.5) * dx
        return cls(
            bins, float(z_base), float(z_top), float(dx), float(h), (x_lo, x_hi) if mirror_ends else ()
        )


def surface_profile(x_soil: np.ndarray, grid: ScourGrid, remaining=None) -> np.ndarray:
    """z_s at each bin centre from soil particle positions (n, 2). remaining (n,): the share of each
    particle's volume still bed (1 - its worn share, docs/erosion.md), so a surface particle the flow
    is wearing away lowers z_s continuously, by a whole row when it is gone; None: all of it."""
    pts = _with_mirrors(np.asarray(x_soil, float), grid, remaining)
    vol = grid.dx**2
    reach = 2.0 * grid.h
    dz = grid.dx / SAMPLES_PER_DX
    z = grid.z_base + dz * np.arange(int(np.ceil((grid.z_top - grid.z_base) / dz)) + 1)
    # above the highest particle's kernel support phi = 0: the scan stops at the first sample there
    # (the same samples and crossing as the whole column, at a fraction of the cost)
    if len(pts):
        z = z[: int(np.searchsorted(z, pts[:, 1].max() + reach, side="right")) + 1]
    out = np.empty(len(grid.x_bins))
    for k, xc in enumerate(grid.x_bins):
        near = pts[np.abs(pts[:, 0] - xc) < reach]
        if not len(near):
            out[k] = grid.z_base
            continue
        r = np.hypot(xc - near[None, :, 0], z[:, None] - near[None, :, 1])
        phi = vol * (kernel_values(r, grid.h, 2) * near[None, :, 2]).sum(axis=1)
        below = np.flatnonzero(phi < 0.5)
        if not len(below):
            out[k] = z[-1]
        elif below[0] == 0:
            out[k] = grid.z_base
        else:
            i = below[0]
            f = (phi[i - 1] - 0.5) / (phi[i - 1] - phi[i])
            out[k] = z[i - 1] + f * (z[i] - z[i - 1])
    return out


def _with_mirrors(pts, grid, remaining=None):
    """The particles plus their images across the base and the end walls (and the corners), as rows
    (x, z, remaining volume share)."""
    reach = 2.0 * grid.h
    share = np.ones(len(pts)) if remaining is None else np.asarray(remaining, float)
    pts = np.c_[pts[:, :2], share]
    sets = [pts]
    base = pts[pts[:, 1] - grid.z_base < reach].copy()
    base[:, 1] = 2.0 * grid.z_base - base[:, 1]
    sets.append(base)
    for xm in grid.mirror_x:
        for src in (pts, base):
            side = src[np.abs(src[:, 0] - xm) < reach].copy()
            side[:, 0] = 2.0 * xm - side[:, 0]
            sets.append(side)
    return np.concatenate(sets)


@dataclass(frozen=True)
class ScourMeasure:
    t: float
    depth: float  # d = max (z_s0 - z_s)
    x_deepest: float
    z_lowest: float
    eroded_area: float
    deposited_area: float


def measure(z0: np.ndarray, z: np.ndarray, grid: ScourGrid, t: float) -> ScourMeasure:
    drop = z0 - z
    k = int(np.argmax(drop))
    return ScourMeasure(
        t=float(t),
        depth=float(max(drop[k], 0.0)),
        x_deepest=float(grid.x_bins[k]),
        z_lowest=float(z.min()),
        eroded_area=float(np.sum(np.maximum(drop, 0.0)) * grid.dx),
        deposited_area=float(np.sum(np.maximum(-drop, 0.0)) * grid.dx),
    )


def scour_series(snapshots, soil_ids, grid: ScourGrid):
    """[(ScourMeasure, z_s)] for snapshots [(t, {"x": ..., "material": ..., "suspended": ...})]; soil_ids:
    soil material ids. With "suspended" (an eroding scene that writes it, docs/erosion.md) the surface
    is the bed's: soil the flow has picked up is not bed, wherever it still is; with "eroded_share"
    the worn part of a surface particle is not bed either (surface_profile's `remaining`)."""
    out, z0 = [], None
    for t, fields in snapshots:
        soil = np.isin(fields["material"], soil_ids)
        if fields.get("suspended") is not None:
            soil &= fields["suspended"] == 0
        worn = fields.get("eroded_share")
        remaining = None if worn is None else np.clip(1.0 - worn[soil], 0.0, 1.0)
        z = surface_profile(fields["x"][soil][:, :2], grid, remaining)
        if z0 is None:
            z0 = z
        out.append((measure(z0, z, grid, t), z))
    return out


def grid_for_scene(scene) -> ScourGrid | None:
    """The scour grid of a 2D scene with soil: bins over the soil blocks' x-range, base at their
    bottom, read up to the domain top; None unless the scene has water and soil (or in 3D)."""
    from ..geometry import block_span

    models = {m.model for m in scene.materials.values()}
    if scene.dim != 2 or models != {"water", "soil"}:
        return None  # scour needs water on soil
    soil = [b for b in scene.blocks if scene.materials[b.material].model == "soil" and not b.fixed]
    if not soil:
        return None
    lo = np.min([block_span(b)[0] for b in soil], axis=0)
    hi = np.max([block_span(b)[1] for b in soil], axis=0)
    return ScourGrid.for_layer(lo[0], hi[0], lo[1], scene.domain.max[1], scene.scene.spacing, scene.h)


def write_scour_outputs(out_dir, scene, hole_picture=True) -> Path | None:
    """scour.csv (t, d, x_deepest, ...), scour_profiles.csv (z_s per bin and time), scour.png (the
    profiles and d(t)) and, with hole_picture, scour_hole.png (the last snapshot zoomed on the hole,
    render_hole) from the run's particles.h5; returns the CSV path, or None for a scene without soil."""
    from .hdf5_writer import read_series

    grid = grid_for_scene(scene)
    out_dir = Path(out_dir)
    if grid is None or not (out_dir / "particles.h5").exists():
        return None
    soil_ids = [k for k, m in enumerate(scene.materials.values()) if m.model == "soil"]
    snapshots = read_series(out_dir / "particles.h5")
    series = scour_series(
        [
            (
                t,
                {
                    "x": f["position"],
                    "material": f["material"],
                    "suspended": f.get("suspended"),
                    "eroded_share": f.get("eroded_share"),
                },
            )  # fmt: skip
            for t, f in snapshots
        ],
        soil_ids,
        grid,
    )
    path = out_dir / "scour.csv"
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["t_s", "depth_m", "x_deepest_m", "z_lowest_m", "eroded_area_m2", "deposited_area_m2"])
        for m, _ in series:
            w.writerow([f"{m.t:.6g}", f"{m.depth:.6g}", f"{m.x_deepest:.6g}", f"{m.z_lowest:.6g}",
                        f"{m.eroded_area:.6g}", f"{m.deposited_area:.6g}"])  # fmt: skip
    with open(out_dir / "scour_profiles.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["x_m"] + [f"z_s(t={m.t:.4g})" for m, _ in series])
        for k, x in enumerate(grid.x_bins):
            w.writerow([f"{x:.6g}"] + [f"{z[k]:.6g}" for _, z in series])
    plot_scour(series, grid, out_dir / "scour.png", title=scene.scene.name)
    if hole_picture and series:
        render_hole(snapshots[-1][1], series, grid, scene, out_dir / "scour_hole.png")
    return path


def hole_window(series, grid: ScourGrid):
    """The part of the (x, z) plane the hole picture shows, ((x_lo, z_lo), (x_hi, z_hi)): the bins
    around the last time's deepest point where the bed dropped by more than a fifth of its depth,
    10 spacings either side (the bins' range if there is no hole yet: d = 0), from 8 spacings below
    the lowest surface there (not below the base) to 8 above the highest initial surface; widened to
    twice its height or raised to a quarter of its width, so that it is neither a slit nor a strip."""
    (m, z), z0 = series[-1], series[0][1]
    dx, drop = grid.dx, series[0][1] - series[-1][1]
    k = int(np.argmax(drop))
    if m.depth > 0:
        deep = drop > 0.2 * m.depth
        i0, i1 = k, k
        while i0 > 0 and deep[i0 - 1]:
            i0 -= 1
        while i1 < len(drop) - 1 and deep[i1 + 1]:
            i1 += 1
    else:
        i0, i1 = 0, len(drop) - 1
    x_lo, x_hi = grid.x_bins[i0] - 10 * dx, grid.x_bins[i1] + 10 * dx
    z_lo = max(grid.z_base, float(z[i0 : i1 + 1].min()) - 8 * dx)
    z_hi = float(z0[i0 : i1 + 1].max()) + 8 * dx
    if x_hi - x_lo < 2 * (z_hi - z_lo):
        grow = (2 * (z_hi - z_lo) - (x_hi - x_lo)) / 2
        x_lo, x_hi = x_lo - grow, x_hi + grow
    z_hi = max(z_hi, z_lo + (x_hi - x_lo) / 4)
    return (x_lo, z_lo), (x_hi, z_hi)


def render_hole(fields, series, grid: ScourGrid, scene, path):
    """scour_hole.png: the last snapshot's particles in the hole's window (hole_window), coloured by
    material (water drawn over the soil), with the bed's surface at the first and the last output time
    (the measure's z_s, so the picture shows what d is read from) and the depth in the title."""
    from .render import render_snapshot

    (m, z), z0 = series[-1], series[0][1]
    (x_lo, z_lo), (x_hi, z_hi) = window = hole_window(series, grid)
    shown = (grid.x_bins >= x_lo) & (grid.x_bins <= x_hi)
    names = list(scene.materials)
    water_ids = [k for k, mat in enumerate(scene.materials.values()) if mat.model == "water"]
    at = f"{1000 * m.depth:.1f} mm at x = {m.x_deepest:.3f} m" if m.depth > 0 else "0 (no hole yet)"
    curves = [
        (np.column_stack([grid.x_bins[shown], z0[shown]]), "black", f"bed at t = {series[0][0].t:.3g} s"),
        (np.column_stack([grid.x_bins[shown], z[shown]]), "red", f"bed at t = {m.t:.3g} s"),
    ]
    return render_snapshot(
        fields,
        path,
        scalar="material",
        title=f"{scene.scene.name}  t = {m.t:.3g} s: scour depth d = {at}",
        bodies=[b.vertices for b in scene.bodies],
        material_names=names,
        water_ids=water_ids,
        window=window,
        curves=curves,
    )


def plot_scour(series, grid, path, title=""):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4))
    cmap = plt.get_cmap("viridis")
    for k, (m, z) in enumerate(series):
        ax1.plot(grid.x_bins, z, color=cmap(k / max(len(series) - 1, 1)), label=f"t = {m.t:.3g} s")
    ax1.set_xlabel("x (m)")
    ax1.set_ylabel("soil surface z_s (m)")
    ax1.set_title("surface: kernel soil fraction = 1/2")
    if len(series) <= 8:
        ax1.legend(fontsize=7)
    elif len(series) > 1:  # too many times for a legend: a colour bar of t
        bar = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(series[0][0].t, series[-1][0].t))
        fig.colorbar(bar, ax=ax1, label="t (s)")
    ts = [m.t for m, _ in series]
    ax2.plot(ts, [1000 * m.depth for m, _ in series], "o-")
    last = series[-1][0] if series else None
    if last is not None:
        ax2.text(0.97, 0.05, f"d({last.t:.3g} s) = {1000 * last.depth:.1f} mm at x = {last.x_deepest:.3f} m",
                 transform=ax2.transAxes, ha="right", fontsize=9)  # fmt: skip
    ax2.set_xlabel("t (s)")
    ax2.set_ylabel("scour depth d (mm)")
    ax2.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
