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
