"""Scene and command-line fuzzer (issue 13): every bad input is refused cleanly.

For each shipped scene, N_MUTATIONS seeded mutations (tests/scene_mutations.py: wrong types,
booleans for numbers, NaN and inf, zero, negative, huge and tiny values, empty and
wrong-length arrays, deleted keys and tables, unknown keys, overlapping and inverted blocks,
truncated files, binary junk) must each either be refused with a SceneError (one line naming
the file, a key and a reason) or validate, build a plan and save a scene that reloads to
itself. That part runs in process, all of it, in `make test` (a few seconds).

A run of `python -m scoursph run` must end in exit 0, 1 or 2, within a timeout, never with a
traceback; on failure with one line on standard error; and exit 2 writes nothing. `make test`
runs a handful of these (a valid and a refused mutation of each scene, some bad options);
the nightly set (SCOURSPH_NIGHTLY=1 or `pytest -m nightly`) runs every mutation and every
option mutation this way. Runs use a coarse spacing and a tiny end time (--set), so a scene
that validates runs for a second or two. SCOURSPH_FUZZ_SEED changes the seed (default 13).
"""

import os
import subprocess
import tomllib

import pytest
from conftest import ENV, SCOURSPH
from scene_mutations import CLI_MUTATIONS, Mutation, mutations

from solver.errors import SceneError
from solver.plan import build_plan
from solver.scene import SCENES_DIR, load_scene, parse_scene, scene_to_toml, shipped_scenes

N_MUTATIONS = 200  # per shipped scene (issue 13: at least 200)
SEED = int(os.environ.get("SCOURSPH_FUZZ_SEED", "13"))
TIMEOUT = 600  # s per run: set-up, compile (cached after the first), a few steps, the picture (loaded host)
# a coarse spacing per scene (a/10, H/10, H/20) and a tiny end time: a run that validates is short
COARSE = {
    "dam_break_2d": 0.005715,
    "hydrostatic_tank_2d": 0.01,
    "column_collapse_2d": 0.005,
    "scour_dry": 0.01,  # 2 dx of the seed: a 10 mm layer of particles still fills the 0.095 m soil
    "scour_saturated": 0.01,
    "scour_plunging_dry": 0.01,  # as the seed's scour scenes: 0.6 x 0.095 m of soil at 2 dx of the seed
    "scour_plunging_saturated": 0.01,
    "scour_plunging_seed_sand_dry": 0.01,  # issue 24's scenes, the seed's sand
    "scour_plunging_seed_sand_saturated": 0.01,
}
END = 0.002
SCENES = shipped_scenes()


def scene_mutations(name):
    return mutations((SCENES_DIR / f"{name}.toml").read_text(), N_MUTATIONS, SEED + SCENES.index(name))


def in_process(path):
    """'refused' or 'valid'; any other exception, or a refusal that is not one line naming
    the file, fails the test."""
    try:
        scene = load_scene(path)
    except SceneError as exc:
        message = str(exc)
        assert "\n" not in message and str(path) in message and exc.key and exc.reason, message
        return "refused"
    build_plan(scene)
    again = parse_scene(tomllib.loads(scene_to_toml(scene)), path)
    assert again == scene, "the saved scene does not reload to the same scene"
    return "valid"


def classify(tmp_path, name):
    """[(mutation, outcome)] for every mutation of a scene; failures collected, not stopped at."""
    out, failures = [], []
    for k, m in enumerate(scene_mutations(name)):
        path = tmp_path / f"{name}_{k:03d}.toml"
        path.write_bytes(m.data)
        try:
            out.append((m, in_process(path)))
        except Exception as exc:  # noqa: BLE001 - the fuzzer reports every failure at once
            failures.append(f"{k:03d} {m.label}: {type(exc).__name__}: {str(exc)[:200]}")
    assert not failures, f"{len(failures)} of {N_MUTATIONS} mutations of {name} not handled:\n" + "\n".join(
        failures
    )
    return out


@pytest.mark.parametrize("name", SCENES)
def test_every_mutation_is_refused_or_validates(tmp_path, name):
    outcomes = [o for _, o in classify(tmp_path, name)]
    # the fuzzer must reach both sides, or it tests nothing
    assert outcomes.count("refused") >= N_MUTATIONS // 4 and outcomes.count("valid") >= 5, outcomes


def cli_run(tmp_path, scene_path, name, extra=()):
    """Run the CLI on a scene with the coarse, short overrides; check the exit contract."""
    out = tmp_path / "out"
    args = [
        *SCOURSPH,
        "run",
        str(scene_path),
        "--out",
        str(out),
        "--quiet",
        "--set",
        f"scene.spacing={COARSE[name]}",
        "--set",
        f"scene.end_time={END}",
        "--set",
        f"output.interval={END}",
        *extra,
    ]
    try:
        proc = subprocess.run(args, capture_output=True, text=True, env=ENV, cwd=tmp_path, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        pytest.fail(f"hang: no exit within {TIMEOUT} s: {' '.join(args[2:])}")
    what = f"{' '.join(args[2:])}\nexit {proc.returncode}\nstderr:\n{proc.stderr[-3000:]}"
    assert proc.returncode in (0, 1, 2), what
    assert "Traceback" not in proc.stderr, what
    if proc.returncode != 0:
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("scoursph: error:"), what
    if proc.returncode == 2:
        assert not out.exists(), "exit 2 wrote " + what
    return proc.returncode


def _sample():
    """For `make test`: per scene the first refused mutation, and for the dam break also the
    first that validates (a real short run: ~4 s idle; the other scenes run in the nightly)."""
    picks = []
    for name in SCENES:
        wanted = {"valid", "refused"} if name == "dam_break_2d" else {"refused"}
        for k, m in enumerate(scene_mutations(name)):
            kind = _quick_outcome(m)
            if kind in wanted:
                wanted.discard(kind)
                picks.append(pytest.param(name, k, id=f"{name}-{k:03d}-{kind}"))
            if not wanted:
                break
    return picks


def _quick_outcome(m: Mutation):
    try:
        parse_scene(tomllib.loads(m.data.decode()))
        return "valid"
    except Exception:  # noqa: BLE001 - only used to pick a sample
        return "refused"


def _run_mutation(tmp_path, name, k):
    m = scene_mutations(name)[k]
    path = tmp_path / "scene.toml"
    path.write_bytes(m.data)
    cli_run(tmp_path, path, name)


@pytest.mark.slow
@pytest.mark.parametrize("name,k", _sample())
def test_cli_sample_of_mutations(tmp_path, name, k):
    _run_mutation(tmp_path, name, k)


CLI_SAMPLE = [["--threads", "0"], ["--set", "scene.spacing=["], ["--out", "/dev/null"]]


@pytest.mark.parametrize("extra", CLI_SAMPLE, ids=lambda a: " ".join(a))
def test_cli_sample_of_bad_options(tmp_path, extra):
    assert cli_run(tmp_path, SCENES_DIR / "dam_break_2d.toml", "dam_break_2d", extra) == 2


# -- nightly: the full set through the real command line ------------------------------------------
@pytest.mark.nightly
@pytest.mark.parametrize("name", SCENES)
@pytest.mark.parametrize("k", range(N_MUTATIONS))
def test_nightly_every_mutation_through_the_cli(tmp_path, name, k):
    _run_mutation(tmp_path, name, k)


@pytest.mark.nightly
@pytest.mark.parametrize("extra", CLI_MUTATIONS, ids=lambda a: " ".join(a))
@pytest.mark.parametrize("name", SCENES)
def test_nightly_every_option_mutation(tmp_path, name, extra):
    cli_run(tmp_path, SCENES_DIR / f"{name}.toml", name, extra)
