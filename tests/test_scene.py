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


COLLAPSE = (ROOT / "scenes" / "column_collapse_2d.toml").read_text()
OVERLAP = (
    '\n[[blocks]]\nname = "second"\nmaterial = "water"\nshape = "rectangle"\n'
    "min = [0.03, 0.0]\nmax = [0.1, 0.05]\n"
)
TOUCHING = OVERLAP.replace("min = [0.03, 0.0]", "min = [0.05715, 0.0]")

# Issue 13: inputs that used to end in a traceback, a blow-up or a silent fallback.
# (base scene, edit, key, reason)
REFUSED = {
    "materials is a number": (
        GOOD,
        lambda t: "materials = 3.0\n" + t.split("[materials.water]")[0],
        "materials",
        "valid dictionary",
    ),
    "model is a list": (
        GOOD,
        lambda t: edit(t, 'model = "water"', "model = [1]"),
        "materials.water.model",
        'one of "water", "soil"',
    ),
    "numerics is an array": (GOOD, lambda t: "numerics = []\n" + t, "numerics", "valid dictionary"),
    "NaN in domain.min": (
        GOOD,
        lambda t: edit(t, "min = [0.0, 0.0]", "min = [nan, 0.0]"),
        "domain.min[0]",
        "finite",
    ),
    "end_time is a boolean": (
        GOOD,
        lambda t: edit(t, "end_time = 0.33", "end_time = true"),
        "scene.end_time",
        "valid number",
    ),
    "NaN in gravity": (
        GOOD,
        lambda t: edit(t, "gravity = [0.0, -9.81]", "gravity = [0.0, nan]"),
        "scene.gravity[1]",
        "finite",
    ),
    "inf in gravity": (
        GOOD,
        lambda t: edit(t, "gravity = [0.0, -9.81]", "gravity = [inf, -9.81]"),
        "scene.gravity[0]",
        "finite",
    ),
    "dimension 1": (
        GOOD,
        lambda t: edit(t, "dimension = 2", "dimension = 1"),
        "scene.dimension",
        "must be 2 or 3",
    ),
    "dimension is a boolean": (
        GOOD,
        lambda t: edit(t, "dimension = 2", "dimension = true"),
        "scene.dimension",
        "integer",
    ),
    "dimension is a float": (
        GOOD,
        lambda t: edit(t, "dimension = 2", "dimension = 2.0"),
        "scene.dimension",
        "integer",
    ),
    "overlapping blocks": (GOOD, lambda t: t + OVERLAP, "blocks[1]", "overlaps blocks[0]"),
    "hydrostatic soil": (
        COLLAPSE,
        lambda t: edit(t, "geostatic = true", "hydrostatic = true"),
        "blocks[0].hydrostatic",
        "only water",
    ),
    "boolean as 1": (
        GOOD,
        lambda t: edit(t, "hydrostatic = true", "hydrostatic = 1"),
        "blocks[0].hydrostatic",
        "valid boolean",
    ),
    "material_defaults unknown key": (
        GOOD,
        lambda t: t + "\n[material_defaults.water]\ncolour = 1.0\n",
        "material_defaults.water.colour",
        "unknown key",
    ),
    "material_defaults bad value": (
        GOOD,
        lambda t: t + "\n[material_defaults.water]\nviscosity = -1.0\n",
        "material_defaults.water.viscosity",
        "greater than or equal to 0",
    ),
    "material_defaults unknown model": (
        GOOD,
        lambda t: t + "\n[material_defaults.mud]\nviscosity = 1.0\n",
        "material_defaults.mud",
        "unknown key",
    ),
    "render_field typo": (
        GOOD,
        lambda t: t + 'render_field = "presure"\n',
        "output.render_field",
        "'presure' is not a field",
    ),
    "render_field not written": (
        COLLAPSE,
        lambda t: t + 'render_field = "pressure"\n',
        "output.render_field",
        "needs 'pressure'",
    ),
    "pressure of a soil-only scene": (
        COLLAPSE,
        lambda t: edit(t, 'fields = ["velocity", "density"]', 'fields = ["velocity", "pressure"]'),
        "output.fields",
        "no water",
    ),
    "artificial_stress without soil": (
        GOOD,
        lambda t: edit(t, "[[blocks]]", "[numerics]\nartificial_stress = 0.5\n\n[[blocks]]"),
        "numerics.artificial_stress",
        "soil only",
    ),
    "settling_time without soil": (
        GOOD,
        lambda t: edit(t, "[[blocks]]", "[numerics]\nsettling_time = 0.1\n\n[[blocks]]"),
        "numerics.settling_time",
        "soil only",
    ),
    "no output times": (
        GOOD,
        lambda t: edit(t, "interval = 0.01", "times = []"),
        "output.times",
        "at least one",
    ),
    "name escapes runs/": (
        GOOD,
        lambda t: edit(t, 'name = "dam_break_2d"', 'name = "../../home"'),
        "scene.name",
        "plain name",
    ),
    "spacing far too small": (
        GOOD,
        lambda t: edit(t, "spacing = 0.00142875", "spacing = 1e-7"),
        "scene.spacing",
        "particles",
    ),
    "domain far too large": (
        GOOD,
        lambda t: edit(t, "max = [0.4572, 0.17145]", "max = [1e9, 0.17145]"),
        "domain",
        "neighbour cells",
    ),
    "gravity in the wrong units": (
        GOOD,
        lambda t: edit(t, "gravity = [0.0, -9.81]", "gravity = [0.0, -9.81e30]"),
        "scene.end_time",
        "set by the gravity",
    ),
    "snapshots without end": (
        GOOD,
        lambda t: edit(t, "interval = 0.01", "interval = 1e-9"),
        "output.interval",
        "snapshots",
    ),
    "polygon vertex of one number": (
        GOOD,
        lambda t: edit(
            t,
            'shape = "rectangle"\nmin = [0.0, 0.0]\nmax = [0.05715, 0.1143]',
            'shape = "polygon"\nvertices = [[0.0, 0.0], [0.05], [0.0, 0.1]]',
        ),
        "blocks[0].vertices",
        "three or more",
    ),
    "hydrostatic block under upward gravity": (
        ROOT.joinpath("scenes", "hydrostatic_tank_2d.toml").read_text(),
        lambda t: edit(t, "gravity = [0.0, -9.81]", "gravity = [0.0, 4611686018427387904]"),
        "blocks[0].hydrostatic",
        "gravity pointing down",
    ),
    "block without a shape": (
        GOOD,
        lambda t: edit(t, 'shape = "rectangle"\n', ""),
        "blocks[0].shape",
        'missing value: one of "rectangle", "polygon"',
    ),
    "block of an unknown shape": (
        GOOD,
        lambda t: edit(t, 'shape = "rectangle"', 'shape = "circle"'),
        "blocks[0].shape",
        '\'circle\' is not known: one of "rectangle", "polygon"',
    ),
    "material of an unknown model": (
        GOOD,
        lambda t: edit(t, 'model = "water"', 'model = "mud"'),
        "materials.water.model",
        '\'mud\' is not known: one of "water", "soil"',
    ),
}


@pytest.mark.parametrize("case", list(REFUSED))
def test_issue13_inputs_are_refused_with_key_and_reason(tmp_path, case):
    base, make, key, reason = REFUSED[case]
    path = tmp_path / "bad.toml"
    path.write_text(make(base))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert (err.value.key, reason in err.value.reason) == (key, True), err.value


def test_binary_junk_is_refused(tmp_path):
    path = tmp_path / "junk.toml"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe" + bytes(range(256)))
    with pytest.raises(SceneError) as err:
        load_scene(path)
    assert err.value.key == "(file)" and "UTF-8" in err.value.reason


def test_touching_blocks_are_not_an_overlap(tmp_path):
    path = tmp_path / "touch.toml"
    path.write_text(GOOD + TOUCHING)
    scene = load_scene(path)
    assert len(scene.blocks) == 2


def test_material_defaults_from_the_scene_are_honoured(tmp_path):
    path = tmp_path / "mud.toml"
    path.write_text(edit(GOOD, "viscosity = 1.0e-3\n", "") + "\n[material_defaults.water]\nviscosity = 0.5\n")
    assert load_scene(path).materials["water"].viscosity == 0.5
    path.write_text(GOOD + "\n[material_defaults.water]\nviscosity = 0.5\n")  # the material's own value wins
    assert load_scene(path).materials["water"].viscosity == 1.0e-3
    path.write_text(GOOD + "\n[artificial_viscosity_defaults.water]\nalpha = 0.2\n")
    assert load_scene(path).numerics.artificial_viscosity["water"].alpha == 0.2


def test_shipped_scene_by_name():
    from solver.scene import resolve_scene_path, shipped_scenes

    assert {"dam_break_2d", "hydrostatic_tank_2d", "column_collapse_2d"} <= set(shipped_scenes())
    assert load_scene(resolve_scene_path("dam_break_2d")).scene.name == "dam_break_2d"
    assert load_scene(resolve_scene_path("column_collapse_2d.toml")).scene.name == "column_collapse_2d"
    with pytest.raises(SceneError) as err:
        load_scene(resolve_scene_path("dam_brake_2d"))
    assert "dam_break_2d" in err.value.reason  # the message lists what there is


def _cli(tmp_path, *args):
    return subprocess.run(
        [*SCOURSPH, *args], capture_output=True, text=True, env=ENV, cwd=tmp_path, timeout=120
    )


@pytest.mark.parametrize("threads", ["0", "-3", "two"])
def test_threads_below_one_is_bad_input(tmp_path, threads):
    proc = _cli(tmp_path, "run", "dam_break_2d", "--threads", threads, "--explain")
    assert proc.returncode == 2 and "--threads" in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1


def test_verify_errors_go_to_stderr(tmp_path):
    proc = _cli(tmp_path, "verify", "no_such_case")
    assert proc.returncode == 2 and "unknown verification case" in proc.stderr and proc.stdout == ""


def test_a_run_reaches_end_time_past_its_listed_output_times():
    """scene.end_time is the end of the run: output.times that stop earlier (the seed's figure times in
    scenes/scour_saturated.toml, 0 to 0.025 s) get end_time appended, not a run cut short at 0.025 s
    (found 2026-12-02: `--set scene.end_time=0.25` ran to 0.025 s and reported `completed`)."""
    listed = [0.0, 0.005, 0.01, 0.015, 0.02, 0.025]
    longer = load_scene(ROOT / "scenes" / "scour_saturated.toml", ["scene.end_time=0.25"])
    assert list(longer.output_times()) == [*listed, 0.25]
    as_written = load_scene(ROOT / "scenes" / "scour_saturated.toml")
    assert list(as_written.output_times()) == listed
