"""Light test doubles for the nightly's process runner (tests/test_report.py): a case that
burns a known CPU time, one that does nothing, and one that hangs. No solver import, so a
child's CPU time is its imports plus what it burns."""

from __future__ import annotations

import time

from verification.common import CaseResult

BUSY_CPU_S = 2.0


def _result(name):
    return CaseResult(name, 1, 1, 1, 0.0, {})


class Idle:
    DEFAULT_RESOLUTION = 1

    @staticmethod
    def run(resolution, out_dir=None):
        return _result("idle")


class Busy:
    DEFAULT_RESOLUTION = 1

    @staticmethod
    def run(resolution, out_dir=None):
        start = time.process_time()
        while time.process_time() - start < BUSY_CPU_S:
            pass
        return _result("busy")


class Hang:
    DEFAULT_RESOLUTION = 1

    @staticmethod
    def run(resolution, out_dir=None):
        time.sleep(3600)
