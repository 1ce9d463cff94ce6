"""Test doubles of verification cases for the nightly report's tests (tests/test_report*.py):
objects with the attributes a case module offers (docs/nightly_report.md), passed to
`scoursph report --case NAME=report_fakes:CLASS`. SmallHydrostatic is the real still-water
case at its two smallest resolutions (a few seconds); the others are synthetic."""

from __future__ import annotations

import os
import signal
from pathlib import Path

from verification import hydrostatic
from verification.common import CaseResult, Check


def _figure(path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1, 2], [0, 1, 4])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=60)
    plt.close(fig)
    return path


class SmallHydrostatic:
    """The still-water case at H/dx = 10, its study at 10 and 20."""

    NIGHTLY_RESOLUTION = 10
    STUDY_RESOLUTIONS = (10, 20, 40)
    NIGHTLY_STUDY_RESOLUTIONS = (10, 20)
    NIGHTLY_NOTE = "test double: the two smallest resolutions only"
    ACCURACY_COLUMNS = hydrostatic.ACCURACY_COLUMNS
    run = staticmethod(hydrostatic.run)

    @staticmethod
    def study(resolutions, out_dir):
        # the seed's scheme at each resolution, without the H/40 option variants of the full study
        rows = []
        for r in resolutions:
            res = hydrostatic.run(r)
            rows.append(
                dict(
                    resolution=r,
                    particles=res.particles,
                    wall_time_s=res.wall_time,
                    cpu_time_s=res.cpu_time,
                    mean_pressure_error=float(res.series["mean_pressure_error"]),
                    mach=float(res.series["mach"][-1]),
                )
            )
        return rows


class Synthetic:
    """Two passing checks, a figure, an extra figure, a table and a study with errors and times."""

    DEFAULT_RESOLUTION = 4
    STUDY_RESOLUTIONS = (2, 4)
    ACCURACY_COLUMNS = {"error": "synthetic error"}
    VALUES = (0.1, 0.2)

    @classmethod
    def run(cls, resolution, out_dir=None):
        res = CaseResult("synthetic", resolution, 100, 10, 0.5, {}, cpu_time=0.4)
        res.checks = [
            Check("first synthetic metric", cls.VALUES[0], 1.0, "synthetic tolerance"),
            Check("second synthetic metric", cls.VALUES[1], 1.0, "synthetic tolerance"),
        ]
        res.notes = ["a synthetic case for the report's tests"]
        res.figure = _figure(Path(out_dir) / "synthetic.png")
        res.extra_figures = [_figure(Path(out_dir) / "synthetic_extra.png")]
        res.tables = [{"title": "an extra table", "header": ["a", "b"], "rows": [[1, 2.5], [3, "x"]]}]
        return res

    @staticmethod
    def study(resolutions, out_dir):
        return [
            dict(resolution=r, wall_time_s=0.1 * r, cpu_time_s=0.08 * r, error=1.0 / r) for r in resolutions
        ]


class Failing(Synthetic):
    """The second check exceeds its tolerance."""

    VALUES = (0.1, 2.0)


class KnownFailing(Failing):
    """The failing check is declared a known failure: the case passes, the row says why."""

    KNOWN_FAILURES = {"second synthetic metric": "a known failure of the test double"}


class Raising:
    """run() raises: the case is recorded as crashed, the report goes on."""

    DEFAULT_RESOLUTION = 1

    @staticmethod
    def run(resolution, out_dir=None):
        raise RuntimeError("synthetic failure inside run()")


class Segfault:
    """The case process dies of a signal (as a Numba kernel writing out of bounds would)."""

    DEFAULT_RESOLUTION = 1

    @staticmethod
    def run(resolution, out_dir=None):
        os.kill(os.getpid(), signal.SIGSEGV)
