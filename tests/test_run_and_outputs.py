"""A run end to end through the CLI: HDF5 series, VTK series, PNG, merged scene, blow-up report."""

import json
import re
import subprocess
import tomllib
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest
from conftest import ENV, ROOT, SCOURSPH

from solver.output.hdf5_writer import Hdf5Series, read_metadata, read_series
from solver.scene import parse_scene

DAM = (ROOT / "scenes" / "dam_break_2d.toml").read_text()


def set_key(text, key, value):
    """The scene text with `key = ...` set to value; fails if the key is not there exactly once
    (a silent no-op edit would leave the test checking the wrong scene)."""
    pattern = re.compile(rf"^{key} = [^\n#]*", re.M)
    text, n = pattern.subn(f"{key} = {value}", text)
    assert n == 1, f"{key} appears {n} times"
    return text


def tiny_dam_break(tmp_path, extra=""):
    text = set_key(set_key(DAM, "spacing", "0.005715"), "end_time", "0.03")
    # the snapshot times the tests below expect (0, 0.01, 0.02, 0.03), whatever the shipped scene says
    text = set_key(text, "interval", "0.01") + extra
    path = tmp_path / "tiny.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def finished_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("run")
    scene = tiny_dam_break(tmp)
    out = tmp / "out"
    proc = subprocess.run(
        [*SCOURSPH, "run", str(scene), "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp,
    )
    return proc, out


def test_run_succeeds_and_says_where_outputs_are(finished_run):
    proc, out = finished_run
    assert proc.returncode == 0, proc.stderr
    assert str(out) in proc.stdout
    for name in ("particles.h5", "particles.pvd", "final.png", "scene.toml", "run.json"):
        assert (out / name).is_file(), name


def test_hdf5_series_has_metadata_and_every_snapshot(finished_run):
    _, out = finished_run
    meta = read_metadata(out / "particles.h5")
    assert meta["solver"] == "ScourSPH" and meta["status"] == "completed"
    assert "scene_toml" in meta and meta["mpi_ranks"] == 1
    series = read_series(out / "particles.h5")
    np.testing.assert_allclose([t for t, _ in series], [0.0, 0.01, 0.02, 0.03], atol=1e-12)
    for _, fields in series:
        assert np.all(np.diff(fields["id"]) > 0)  # sorted by global id
        assert fields["position"].shape == (200, 2)
        assert {"velocity", "density", "pressure", "material", "rank"} <= set(fields)
    assert np.abs(series[-1][1]["velocity"]).max() > 0.1  # the column is falling


def test_saved_scene_reproduces_the_run_setup(finished_run):
    _, out = finished_run
    saved = parse_scene(tomllib.loads((out / "scene.toml").read_text()))
    assert saved.scene.spacing == 0.005715 and saved.numerics.h_over_dx == 1.3


def test_vtk_collection_points_at_readable_files(finished_run):
    import pyvista as pv

    _, out = finished_run
    datasets = ET.parse(out / "particles.pvd").getroot().findall(".//DataSet")
    assert len(datasets) == 4
    cloud = pv.read(out / datasets[-1].get("file"))
    assert cloud.n_points == 200 and "pressure" in cloud.point_data


def test_picture_is_not_blank(finished_run):
    import matplotlib.image as mpimg

    _, out = finished_run
    img = mpimg.imread(out / "final.png")
    assert img.shape[0] > 100 and img[..., :3].std() > 0.05


def test_crash_during_a_snapshot_keeps_the_earlier_ones(tmp_path, monkeypatch):
    series = Hdf5Series(tmp_path, {"solver": "ScourSPH"}, "scene")
    fields = {"id": np.arange(5), "position": np.zeros((5, 2))}
    series.write(0.0, 0, fields)

    def boom(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(h5py.Group, "create_dataset", boom)
    with pytest.raises(OSError):
        series.write(0.1, 10, fields)
    monkeypatch.undo()
    assert [t for t, _ in read_series(tmp_path / "particles.h5")] == [0.0]
    assert not list(tmp_path.rglob("*partial*"))


def test_blow_up_stops_with_what_where_when_and_keeps_outputs(tmp_path):
    extra = "\n[numerics.cfl]\nsound = 3.0\nforce = 3.0\n"
    scene = tiny_dam_break(tmp_path, extra)
    text = set_key(scene.read_text(), "interval", "0.01").replace("interval = 0.01", "times = [0.0, 0.03]")
    scene.write_text(text)
    out = tmp_path / "out"
    proc = subprocess.run(
        [*SCOURSPH, "run", str(scene), "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp_path,
    )
    assert proc.returncode == 1
    assert "simulation stopped at t =" in proc.stderr and "step" in proc.stderr  # when
    assert "particle id" in proc.stderr  # where
    assert (
        "crossed a wall" in proc.stderr or "non-finite" in proc.stderr or "collapsed" in proc.stderr
    )  # what
    assert [t for t, _ in read_series(out / "particles.h5")] == [0.0]  # what was written is kept
    assert "blew up" in json.loads((out / "run.json").read_text())["status"]


def _colour_fractions(img):
    """Fractions of the picture that are blue (water), sandy (soil: red over blue) and mid grey (a body);
    sphere shading varies the shades, so hues are counted, not exact colours."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    grey = (np.abs(r - g) < 0.04) & (np.abs(g - b) < 0.04) & (r > 0.3) & (r < 0.7)
    return (b > r + 0.15).mean(), (r > b + 0.15).mean(), grey.mean()


def test_saturated_bed_picture_shows_pore_water_over_soil_and_the_body(tmp_path):
    """A soil and a pore-water particle at every site used to z-fight into half-coloured balls, and
    rigid bodies were not drawn: the water is now drawn on top of the soil, smaller, and bodies grey."""
    import matplotlib.image as mpimg

    from solver.output.render import render_snapshot

    sites = np.stack(np.meshgrid(np.arange(0.0025, 0.2, 0.005), np.arange(0.0025, 0.1, 0.005)), -1).reshape(
        -1, 2
    )
    fields = {
        "position": np.vstack([sites, sites]),
        "material": np.repeat([1, 0], len(sites)),  # sand (id 1) first, pore water (id 0) at the same sites
        "velocity": np.zeros((2 * len(sites), 2)),
    }
    png = tmp_path / "bed.png"
    body = [[0.2, 0.0], [0.25, 0.0], [0.25, 0.12], [0.2, 0.12]]
    render_snapshot(fields, png, scalar="material", domain=([0.0, 0.0], [0.25, 0.15]), bodies=[body],
                    material_names=("water", "sand"), water_ids=[0])  # fmt: skip
    water, soil, grey = _colour_fractions(mpimg.imread(png))
    # the bed covers ~45 % of the picture, the body ~10 %: each must show (the water was hidden before)
    assert water > 0.05 and soil > 0.05 and grey > 0.03, (water, soil, grey)
