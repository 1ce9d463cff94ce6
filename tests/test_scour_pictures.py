"""The scour run's pictures (solver/output/scour.py): scour.png (surfaces and d(t)) and scour_hole.png
(the last snapshot zoomed on the hole, with the bed's first and last surfaces), drawn by the real
renderers (pyvista off-screen, matplotlib). A lattice bed with a pit cut in it checks that the hole
picture frames the pit and draws its surfaces to the picture's scale; a tiny run through the CLI that
both files are written and the depth it prints is scour.csv's last."""

import csv
import subprocess

import matplotlib.image as mpimg
import numpy as np
import pytest
from conftest import ENV, ROOT, SCOURSPH

from solver.output.scour import grid_for_scene, hole_window, render_hole, scour_series
from solver.scene import load_scene

SEED = ROOT / "scenes" / "scour_saturated.toml"  # a 0.25 x 0.095 m layer of 5 mm (water id 0, sand 1)
DX, TOP = 0.005, 0.095
PIT = (0.10, 0.15, 0.07)  # x from, x to, the height above which the lattice sites are removed
LINE_PX = 4  # the surfaces' line width in the picture (render._add_curve)


def bed(pit=None):
    """Sand at the lattice sites of the seed's layer (minus the pit's) and a water layer 4 rows deep."""
    i, k = np.meshgrid(np.arange(round(0.25 / DX)), np.arange(round(TOP / DX) + 4), indexing="ij")
    x = np.column_stack([(i.ravel() + 0.5) * DX, (k.ravel() + 0.5) * DX])
    sand = x[:, 1] < TOP
    if pit is not None:
        sand &= ~((x[:, 0] > pit[0]) & (x[:, 0] < pit[1]) & (x[:, 1] > pit[2]))
    # the rest is water: the 4 rows above the bed and the pit
    return {"position": x, "material": np.where(sand, 1, 0), "velocity": np.zeros((len(x), 2))}


@pytest.fixture(scope="module")
def pit_series():
    scene = load_scene(SEED)
    grid = grid_for_scene(scene)
    snaps = [bed(), bed(PIT)]
    fields = [{"x": f["position"], "material": f["material"]} for f in snaps]
    series = scour_series(list(zip((0.0, 1.0), fields)), [1], grid)
    return scene, grid, series, snaps[-1]


def test_the_hole_window_frames_the_pit_with_a_margin(pit_series):
    _, grid, series, _ = pit_series
    depth = series[-1][0].depth
    assert abs(depth - (TOP - PIT[2])) < DX / 2  # the measure (tests/test_scour_measure.py)
    (x_lo, z_lo), (x_hi, z_hi) = hole_window(series, grid)
    assert x_lo < PIT[0] - 5 * DX and x_hi > PIT[1] + 5 * DX  # the pit and ten bins either side
    assert x_hi - x_lo < 0.25  # a zoom: narrower than the layer
    assert z_lo < PIT[2] - 5 * DX and z_hi > TOP + 5 * DX
    assert 2 * (z_hi - z_lo) <= x_hi - x_lo + 1e-12 and z_hi - z_lo >= (x_hi - x_lo) / 4 - 1e-12


def _colours(img):
    """Masks of the red and black lines and of the sand (its shaded earth tone: red well above blue)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    red = (r > 0.8) & (g < 0.25) & (b < 0.25)
    return red, (r < 0.1) & (g < 0.1) & (b < 0.1), (r > b + 0.15) & (g > 0.3)


def test_the_hole_picture_draws_both_surfaces_to_its_scale(pit_series, tmp_path):
    """The red line (the last surface, drawn over the first) dips under the flat bed where the sand
    has a pit, by the measured depth, its ends where the measured surface has dropped; above the pit
    the black line (the surface at t = 0) shows. The scale is the red line's length over the window's
    bins, the place the drawn sand's pit (centred on x = 0.125 m). Within two widths of the line
    (LINE_PX): each check is the difference of two places read off the 4 px thick line (its centre,
    an edge or an end)."""
    scene, grid, series, last = pit_series
    png = render_hole(last, series, grid, scene, tmp_path / "scour_hole.png")
    img = mpimg.imread(png)[..., :3]
    red, black, sand = _colours(img)
    height, width = red.shape
    band = int(0.3 * height)  # the title and the legend (render.TITLE_BAND of the window above it)
    red[:band], black[:band], sand[:band] = False, False, False
    # the scale: the red line runs over the window's bins
    (x_lo, _), (x_hi, _) = hole_window(series, grid)
    shown = grid.x_bins[(grid.x_bins >= x_lo) & (grid.x_bins <= x_hi)]
    drawn = np.flatnonzero(red.any(axis=0))
    px_per_m = np.ptp(drawn) / (shown[-1] - shown[0])
    assert np.ptp(drawn) > 0.7 * width  # the window fills the picture: a zoom
    # the place: the sand's top in each column lies deeper in the pit, centred on x = 0.125 m
    cols = np.flatnonzero(sand.any(axis=0))
    top = sand[:, cols].argmax(axis=0)
    outside = np.median(top)
    pit_cols = cols[top > outside + 0.5 * (top.max() - outside)]
    gap_centre = 0.5 * (pit_cols.min() + pit_cols.max())

    def x_at(col):
        return 0.5 * (PIT[0] + PIT[1]) + (col - gap_centre) / px_per_m

    flat = np.flatnonzero(red.sum(axis=1) > 0.3 * width)  # the red line along the untouched bed
    assert len(flat), "no red line across the picture"
    bed_row = flat.mean()
    dip_rows, dip_cols = np.nonzero(red & (np.arange(height)[:, None] > bed_row + 4))  # below the bed
    assert len(dip_rows), "no red surface below the initial one"
    tol = 2 * LINE_PX / px_per_m
    m = series[-1][0]
    assert abs((dip_rows.max() - bed_row) / px_per_m - m.depth) < tol
    # where the measured surface has dropped by 2 px (the line's lower edge 4 px below the bed's
    # centre row), by linear interpolation between the bins as the line is drawn: the dip's ends
    drop = series[0][1] - series[-1][1]
    deep = np.flatnonzero(drop > 2 / px_per_m)
    k0, k1 = deep[0], deep[-1]
    x = grid.x_bins
    left = np.interp(2 / px_per_m, [drop[k0 - 1], drop[k0]], [x[k0 - 1], x[k0]])
    right = np.interp(2 / px_per_m, [drop[k1 + 1], drop[k1]], [x[k1 + 1], x[k1]])
    assert abs(x_at(dip_cols.min()) - left) < tol, (x_at(dip_cols.min()), left)
    assert abs(x_at(dip_cols.max()) - right) < tol, (x_at(dip_cols.max()), right)
    over_pit = black[int(bed_row) - 3 : int(bed_row) + 4, dip_cols.min() + 5 : dip_cols.max() - 5]
    assert over_pit.any(axis=0).mean() > 0.9  # the initial surface drawn across the hole


def test_a_scour_run_writes_its_plot_and_hole_picture_and_prints_the_depth(tmp_path):
    """The seed's scene for 5 ms (the nappe lands): the CLI writes scour.png and scour_hole.png (real
    renderers) and prints the last depth of scour.csv."""
    out = tmp_path / "out"
    sets = ["scene.end_time=0.005", "output.times=[0.0, 0.0025, 0.005]", "output.vtk=false"]
    proc = subprocess.run([*SCOURSPH, "run", str(SEED), "--out", str(out), "--quiet",
                           *[a for s in sets for a in ("--set", s)]],
                          capture_output=True, text=True, env=ENV, cwd=tmp_path)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    for name in ("scour.png", "scour_hole.png", "final.png"):
        img = mpimg.imread(out / name)
        assert img.shape[0] > 200 and np.ptp(img[..., :3]) > 0.5, name  # drawn, not blank
        assert str(out / name) in proc.stdout or name == "final.png", name
    with open(out / "scour.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [float(r["t_s"]) for r in rows] == [0.0, 0.0025, 0.005]
    depth_mm = 1000 * float(rows[-1]["depth_m"])
    assert f"scour depth at t = 0.005 s: {depth_mm:.1f} mm" in proc.stdout, proc.stdout


def test_no_hole_picture_when_pictures_are_off(tmp_path):
    """output.render = false (the tests' fast runs) draws no final.png and no scour_hole.png; the
    measure and its plot are still written."""
    out = tmp_path / "out"
    sets = ["scene.end_time=0.0025", "output.times=[0.0, 0.0025]", "output.vtk=false", "output.render=false"]
    proc = subprocess.run([*SCOURSPH, "run", str(SEED), "--out", str(out), "--quiet",
                           *[a for s in sets for a in ("--set", s)]],
                          capture_output=True, text=True, env=ENV, cwd=tmp_path)  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert (out / "scour.csv").is_file() and (out / "scour.png").is_file()
    assert not (out / "scour_hole.png").exists() and not (out / "final.png").exists()
