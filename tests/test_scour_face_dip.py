"""verification/scour_face_dip.py: the still-pond control scene (no run: the scene and its start only)."""

import numpy as np

from solver.geometry import block_points, clear_of_bodies
from solver.initial_state import water_table
from solver.scene import parse_scene
from verification import scour_face_dip as fd
from verification.scour_study import SCENES


def test_the_pond_scene_is_the_saturated_layer_under_still_water_and_nothing_else():
    scene = parse_scene(fd.pond_raw(0.005, 0.1), SCENES / "scour_saturated.toml")
    assert not scene.inlets and not scene.outlets
    assert scene.walls.x_max == "free_slip"  # the pond cannot run out of the domain
    layer, pond = scene.blocks
    assert water_table(scene, layer) == fd.POND_TOP  # the pore water starts under the pond's head
    pts = block_points(pond, scene)
    pts = pts[clear_of_bodies(pts, scene)]
    below = pts[:, 1] < fd.SURFACE
    assert not below.any()  # no pond water inside the layer
    over_caisson = pts[:, 0] < 0.0
    assert pts[over_caisson, 1].min() > fd.CROWN  # above the crown, not inside the caisson
    assert np.isclose(pts[:, 1].max(), fd.POND_TOP - 0.0025)
    assert [b.name for b in scene.bodies] == ["breakwater", "end wall"]  # the same caisson and end wall
