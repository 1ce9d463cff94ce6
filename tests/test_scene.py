"""Bad scene input is refused before anything runs: file, key and reason; exit 2; no output."""

import subprocess

import pytest
from conftest import ENV, ROOT, SCOURSPH

from solver.errors import SceneError
from solver.scene import load_scene, parse_scene, scene_to_toml

GOOD = (ROOT / "scenes" / "dam_break_2d.toml").read_text()


def edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


BAD = {
    "unknown key": (
        lambda t: edit(t, "dimension = 2", "dimension = 2\nviscosty = 1.0"),
        "scene.viscosty",
        "unknown key",
    ),
    "missing value": (lambda t: edit(t, "density = 1000.0\n", ""), "materials.water.density", "missing"),
    "negative density": (
        lambda t: edit(t, "density = 1000.0", "density = -1000.0"),
        "materials.water.density",
        "greater than 0",
    ),
    "negative spacing": (
        lambda t: edit(t, "spacing = 0.00142875", "spacing = -0.001"),
        "scene.spacing",
        "greater than 0",
    ),
    "zero end time": (
        lambda t: edit(t, "end_time = 0.33", "end_time = 0.0"),
        "scene.end_time",
        "greater than 0",
    ),
    "block outside": (
        lambda t: edit(t, "max = [0.05715, 0.1143]", "max = [0.05715, 0.5]"),
        "blocks[0]",
        "outside the domain",
    ),
    "spacing larger than block": (
        lambda t: edit(t, "max = [0.05715, 0.1143]", "max = [0.001, 0.1143]"),
        "scene.spacing",
        "larger than block",
    ),
    "unknown material": (
        lambda t: edit(t, 'material = "water"', 'material = "sand"'),
        "blocks[0].material",
        "unknown material 'sand'",
    ),
    "bad wall kind": (
        lambda t: edit(t, 'x_min = "free_slip"', 'x_min = "sticky"'),
        "walls.x_min",
        "Input should be",
    ),
    "gravity size": (
        lambda t: edit(t, "gravity = [0.0, -9.81]", "gravity = [0.0, 0.0, -9.81]"),
        "scene.gravity",
        "needs 2",
    ),
    "toml syntax": (lambda t: t + "\n[[oops\n", "(syntax)", ""),
    "frictional wall without an angle": (
        lambda t: edit(t, 'x_min = "free_slip"', 'x_min = "frictional"'),
        "walls.friction_angle",
        "required for a 'frictional' wall",
    ),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_input_names_file_key_reason(tmp_path, case):
    make, key, reason = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(make(GOOD))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.key == key
    assert reason in err.value.reason
    assert str(path) in str(err.value)


@pytest.mark.parametrize("case", ["unknown key", "block outside", "negative density"])
def test_cli_exits_2_and_writes_nothing(tmp_path, case):
    make, key, _ = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(make(GOOD))
    out = tmp_path / "out"
    proc = subprocess.run(
        [*SCOURSPH, "run", str(path), "--out", str(out), "--quiet"],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert str(path) in proc.stderr and key in proc.stderr
    assert not out.exists()


def test_missing_file_is_bad_input(tmp_path):
    proc = subprocess.run(
        [*SCOURSPH, "run", str(tmp_path / "nope.toml")], capture_output=True, text=True, env=ENV, cwd=tmp_path
    )
    assert proc.returncode == 2 and "no such scene file" in proc.stderr


def test_merged_scene_round_trips():
    """The merged scene saved with every output reloads to the same scene."""
    scene = load_scene(ROOT / "scenes" / "dam_break_2d.toml")
    import tomllib

    again = parse_scene(tomllib.loads(scene_to_toml(scene)))
    assert again == scene
    assert again.numerics.xsph_epsilon == 0.001  # default filled in from defaults.toml
    assert again.numerics.artificial_viscosity["water"].alpha == 0.01


def test_command_line_overrides_are_validated_like_the_file(tmp_path):
    scene = load_scene(
        ROOT / "scenes" / "dam_break_2d.toml",
        ["parallel.rebalance_every=25", "numerics.xsph_epsilon=0.0", "scene.name=renamed"],
    )
    assert (
        scene.parallel.rebalance_every == 25
        and scene.numerics.xsph_epsilon == 0.0
        and scene.scene.name == "renamed"
    )
    with pytest.raises(SceneError) as err:
        load_scene(ROOT / "scenes" / "dam_break_2d.toml", ["scene.spacing=-1.0"])
    assert err.value.key == "scene.spacing"
    bad = subprocess.run(
        [
            *SCOURSPH,
            "run",
            str(ROOT / "scenes" / "dam_break_2d.toml"),
            "--imbalance-threshold",
            "0.5",
            "--explain",
        ],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp_path,
    )
    assert bad.returncode == 2 and "parallel.imbalance_threshold" in bad.stderr
    good = subprocess.run(
        [
            *SCOURSPH,
            "run",
            str(ROOT / "scenes" / "dam_break_2d.toml"),
            "--rebalance-every",
            "20",
            "--explain",
        ],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp_path,
    )
    assert good.returncode == 0
