import os
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def disordered_lattice(n_side, dim, dx, rng, jitter=0.15):
    """A lattice of n_side^dim points with random displacements (a lattice hides bugs)."""
    axes = [(np.arange(n_side) + 0.5) * dx] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    return pts + rng.uniform(-jitter, jitter, pts.shape) * dx


def write_scene(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def water_and_sand_scene(
    name, spacing, end_time, domain_max, gravity="[0.0, -9.81]", walls=True, youngs_modulus="1.0e6",
    friction_angle="33.0", seepage=None,
):  # fmt: skip
    """The head of the two-phase test scenes (tests/test_seepage*.py, test_mpi.py) in TOML: [scene] in 2D,
    [domain] from the origin to domain_max (TOML text, as gravity), free-slip walls on the sides and floor
    (walls), water, a sand (n = 0.4, k = 1e-3 m/s) that a saturated block fills with pore water, and
    numerics.seepage if given. The caller appends its blocks (rectangle_block)."""
    wall_lines = '\n[walls]\nx_min = "free_slip"\nx_max = "free_slip"\ny_min = "free_slip"\n' if walls else ""
    return f"""
[scene]
name = "{name}"
dimension = 2
spacing = {spacing}
end_time = {end_time}
gravity = {gravity}

[domain]
min = [0.0, 0.0]
max = {domain_max}
{wall_lines}
[materials.water]
model = "water"
density = 1000.0
typical_velocity = 2.0

[materials.sand]
model = "soil"
density = 1590.0
youngs_modulus = {youngs_modulus}
poisson_ratio = 0.3
friction_angle = {friction_angle}
cohesion = 0.0
porosity = 0.4
permeability = 1.0e-3
""" + (f'\n[numerics]\nseepage = "{seepage}"\n' if seepage is not None else "")


def rectangle_block(name, material, lo, hi, extra=""):
    """A [[blocks]] rectangle in TOML from lo to hi (TOML lists), then extra lines ("saturated = true")."""
    head = f'\n[[blocks]]\nname = "{name}"\nmaterial = "{material}"\nshape = "rectangle"\n'
    return head + f"min = {lo}\nmax = {hi}\n" + (extra + "\n" if extra else "")


SCOURSPH = [sys.executable, "-m", "scoursph"]
ENV = {**os.environ, "NUMBA_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}


NIGHTLY = os.environ.get("SCOURSPH_NIGHTLY") == "1"


def pytest_collection_modifyitems(config, items):
    """Tests marked `nightly` (the full fuzzer, the whole stability matrix, long studies) run with
    SCOURSPH_NIGHTLY=1 or `pytest -m nightly`; `make test` skips them and says why."""
    if NIGHTLY or "nightly" in (config.option.markexpr or ""):
        return
    skip = pytest.mark.skip(
        reason="nightly: the full set runs with SCOURSPH_NIGHTLY=1 (or pytest -m nightly)"
    )
    for item in items:
        # the marker itself: item.keywords also holds every parent node's name, so a test file or a
        # checkout directory named *nightly* would skip everything in it
        if item.get_closest_marker("nightly") is not None:
            item.add_marker(skip)
