"""Run the MPI fault tests of tests/test_mpi.py N times in one process and count failures
(issue 14: "run it 100 times and report"). Not collected by pytest.

    NUMBA_NUM_THREADS=1 nice -n 10 .venv/bin/python tests/repeat_mpi_faults.py 100 [names]

names: comma-separated from bad_scene, blow_up, nan, exc_uncaught, exc_fail, killed, stalled
(default: all). Each failure's traceback goes to stderr; the summary is
{name: (runs, failures, slowest run in s)}.
"""

import sys
import tempfile
import time
import traceback
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent.parent), str(Path(__file__).resolve().parent)]
import test_mpi as T  # noqa: E402

TESTS = {
    "bad_scene": T.test_bad_scene_reported_once,
    "blow_up": T.test_blow_up_on_one_rank_ends_job_with_its_message,
    "nan": T.test_nan_on_one_rank_ends_job_with_its_message_and_keeps_outputs,
    "exc_uncaught": lambda p: T.test_exception_on_one_rank_aborts_all(p, "uncaught"),
    "exc_fail": lambda p: T.test_exception_on_one_rank_aborts_all(p, "fail"),
    "killed": T.test_killed_rank_ends_job_within_bound,
    "stalled": T.test_failure_message_survives_a_stalled_launcher,
}


def main(n, names):
    fails = dict.fromkeys(names, 0)
    slowest = dict.fromkeys(names, 0.0)
    for i in range(n):
        for name in names:
            with tempfile.TemporaryDirectory() as d:
                t0 = time.perf_counter()
                try:
                    TESTS[name](Path(d))
                except BaseException:
                    fails[name] += 1
                    sys.stderr.write(f"=== run {i} {name} FAILED\n{traceback.format_exc()}\n")
                slowest[name] = max(slowest[name], time.perf_counter() - t0)
    summary = {k: (n, fails[k], round(slowest[k], 1)) for k in names}
    print(summary)
    return 1 if any(fails.values()) else 0


if __name__ == "__main__":
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    chosen = sys.argv[2].split(",") if len(sys.argv) > 2 else list(TESTS)
    raise SystemExit(main(count, chosen))
