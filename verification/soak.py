"""Soak (issue 14): a long run with outputs on keeps its memory flat, leaks no file handle, and
leaves output that reads back whole.

    python -m verification.soak                       # the dam break for 20x its duration, a/40
    python -m verification.soak --spacing-ratio 10    # coarser (the CI test uses a/10)
    python -m verification.soak --set numerics.image_pressure='"hydrostatic"'

runs `scoursph run` (the real command line, one process, one Numba thread) on
scenes/dam_break_2d.toml with end_time = FACTOR x the scene's end time and samples the process
from outside every SAMPLE_S seconds while it steps (until run.json appears; the one picture
rendered at the end loads VTK, ~200 MB, and is not part of the long run): resident memory (VmRSS
in /proc/PID/status), open file descriptors (/proc/PID/fd) and the snapshots written so far.
Then it reads every snapshot back with h5py (every dataset of every snapshot, through the series
file's links and the snapshot files themselves) and the ParaView series.

Checks (SoakResult.ok):
  memory     RSS growth after warm-up < 5 % (issue 14): warm-up ends when WARMUP of the snapshots
             are written (first allocations, Numba compilation and the neighbour lists' growth
             to their working size are over by then); growth = (max RSS after - RSS at the end of
             warm-up) / RSS at the end of warm-up.
  handles    no fd leak: the floor of the fd count (the fewest open in a quarter of the samples
             after warm-up) is not higher in the last quarter than in the first. A handle on a
             file still under its temporary write name (solver/output/atomic.py) is a write in
             progress and is not counted: a leaked handle outlives the rename, and /proc shows it
             under the final name (or as deleted). Why: the series file (particles.h5) is rewritten
             whole at every snapshot, so its write grows with the snapshot count, and at 331
             snapshots on a slow CI host every sample of the last quarter caught it open (3 -> 4
             with the floor rule alone; 3 -> 4 before that with the quarters' largest counts);
  output     the run completed; every snapshot reads back, with its n_particles rows in every
             dataset, all finite, and times increasing; as many snapshots as output times.
Writes verification/results/soak/soak_<spacing>.md and .csv (the samples).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import subprocess
import sys
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from solver.output.atomic import is_partial

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "dam_break_2d.toml"
OUT = Path(__file__).with_name("results") / "soak"
FACTOR = 20  # x the scene's end time (issue 14)
SAMPLE_S = 0.5
WARMUP = 0.1  # fraction of the snapshots
GROWTH_LIMIT = 0.05  # issue 14: memory growth < 5 % after warm-up


@dataclass
class SoakResult:
    spacing: float
    end_time: float
    status: str = ""
    wall_s: float = 0.0
    snapshots: int = 0
    expected_snapshots: int = 0
    rss_warm_mb: float = 0.0
    rss_max_mb: float = 0.0
    rss_end_mb: float = 0.0
    growth: float = 0.0
    fd_first: int = 0  # fewest open fds (the floor), first quarter after warm-up
    fd_last: int = 0  # the floor, last quarter
    read_ok: bool = False
    read_error: str = ""
    run_json: dict = field(default_factory=dict)
    samples: list = field(default_factory=list)  # (wall s, rss kB, fds, snapshots)
    fd_targets_last: list = field(default_factory=list)  # what the counted fds pointed at, last sample

    @property
    def ok(self):
        return (
            self.status == "completed"
            and self.growth < GROWTH_LIMIT
            and self.fd_last <= self.fd_first
            and self.read_ok
            and self.snapshots == self.expected_snapshots
        )


def _rss_kb(pid):
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def open_files(pid):
    """The targets of a process's open fds, without those on a file under its temporary write name
    (a write in progress, solver/output/atomic.py)."""
    targets = []
    for fd in os.listdir(f"/proc/{pid}/fd"):
        try:
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
        except OSError:  # closed between the listing and the read
            continue
        if not is_partial(target):
            targets.append(target)
    return targets


def _snapshot_count(out):
    d = out / "snapshots"
    return sum(1 for p in d.glob("*.h5")) if d.is_dir() else 0


def read_back(out):
    """Read every snapshot: through the series file (links) and each snapshot file; returns the count."""
    import h5py

    with h5py.File(out / "particles.h5", "r") as f:
        times = f["times"][:]
        keys = sorted(f["snapshots"])
        assert len(keys) == len(times), (len(keys), len(times))
        assert np.all(np.diff(times) > 0), "snapshot times not increasing"
        for key in keys:
            snap = f["snapshots"][key]
            n = int(snap.attrs["n_particles"])
            for name in snap:
                data = snap[name][()]
                assert data.shape[0] == n, (key, name, data.shape, n)
                if data.dtype.kind == "f":
                    assert np.isfinite(data).all(), (key, name)
    files = sorted((out / "snapshots").glob("*.h5"))
    assert [p.stem for p in files] == keys, "snapshot files and series entries differ"
    for p in files:
        with h5py.File(p, "r") as f:
            for name in f:
                f[name][()]
    pvd = out / "particles.pvd"
    if pvd.exists():
        import xml.etree.ElementTree as ET

        datasets = ET.parse(pvd).getroot().iter("DataSet")
        missing = [d.get("file") for d in datasets if not (out / d.get("file")).exists()]
        assert not missing, f"ParaView series names missing files: {missing[:3]}"
    return len(keys)


def soak(spacing_ratio=40, factor=FACTOR, out_dir=None, sets=(), quiet=True):
    raw = tomllib.loads(SCENE.read_text())
    a = raw["blocks"][0]["max"][0]
    spacing = a / spacing_ratio
    end = factor * raw["scene"]["end_time"]
    out = Path(out_dir or f"runs/soak_r{spacing_ratio}")
    cmd = [
        sys.executable,
        "-m",
        "scoursph",
        "run",
        str(SCENE),
        "--out",
        str(out),
        "--quiet",
        "--threads",
        "1",
    ]
    for s in (f"scene.spacing={spacing!r}", f"scene.end_time={end!r}", *sets):
        cmd += ["--set", s]
    env = dict(os.environ, NUMBA_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    from solver.scene import load_scene

    expected = len(
        load_scene(SCENE, [f"scene.spacing={spacing!r}", f"scene.end_time={end!r}", *sets]).output_times()
    )
    res = SoakResult(spacing, end, expected_snapshots=expected)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    while proc.poll() is None:
        if (out / "run.json").exists():  # stepping is over: the end-of-run render is not the soak
            break
        try:
            rss = _rss_kb(proc.pid)
            files = open_files(proc.pid)
        except (OSError, ValueError):
            break
        res.fd_targets_last = files
        res.samples.append((time.perf_counter() - t0, rss, len(files), _snapshot_count(out)))
        time.sleep(SAMPLE_S)
    stdout, stderr = proc.communicate()  # the run's end: series finished, run.json, final.png
    res.wall_s = time.perf_counter() - t0
    run_json = out / "run.json"
    res.run_json = json.loads(run_json.read_text()) if run_json.exists() else {}
    res.status = res.run_json.get("status", f"exit {proc.returncode}: {stderr[-500:]}")
    _judge(res)
    try:
        res.snapshots = read_back(out)
        res.read_ok = True
    except Exception as exc:  # any failure to read back is the finding
        res.read_error = f"{type(exc).__name__}: {exc}"
    if not quiet:
        print(stdout, stderr, file=sys.stderr)
    return res


def _judge(res):
    s = res.samples
    if not s:
        return
    warm_snaps = max(1, int(WARMUP * res.expected_snapshots))
    after = [x for x in s if x[3] >= warm_snaps]
    if len(after) < 4:
        after = s[len(s) // 10 :] or s
    res.rss_warm_mb = after[0][1] / 1024
    res.rss_max_mb = max(x[1] for x in after) / 1024
    res.rss_end_mb = after[-1][1] / 1024
    res.growth = (res.rss_max_mb - res.rss_warm_mb) / res.rss_warm_mb
    q = max(1, len(after) // 4)
    res.fd_first = min(x[2] for x in after[:q])
    res.fd_last = min(x[2] for x in after[-q:])


def write_report(res, out=OUT, note=""):
    out.mkdir(parents=True, exist_ok=True)
    stem = f"soak_dx{res.spacing * 1000:.4g}mm"
    with open(out / f"{stem}.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["wall_s", "rss_kb", "open_fds", "snapshots_written"])
        for row in res.samples:
            w.writerow([f"{row[0]:.2f}", *row[1:]])
    rj = res.run_json
    lines = [
        f"# Soak: dam break at dx = {res.spacing * 1000:.4g} mm to t = {res.end_time:g} s",
        "",
        "`python -m verification.soak` (docstring: what is sampled and checked). " + note,
        "",
        "| check | value | limit |",
        "|---|---|---|",
        f"| run | {res.status} ({rj.get('steps', '?')} steps, {rj.get('particles', '?')} particles) "
        "| completed |",
        f"| RSS at end of warm-up / max after / at end (MB) | {res.rss_warm_mb:.1f} / {res.rss_max_mb:.1f} / "
        f"{res.rss_end_mb:.1f} | |",
        f"| RSS growth after warm-up | {100 * res.growth:.2f} % | < {100 * GROWTH_LIMIT:g} % |",
        f"| open fds, first / last quarter after warm-up (fewest) | {res.fd_first} / {res.fd_last} "
        "| last <= first |",
        f"| snapshots read back (h5py, every dataset) | {res.snapshots} of {res.expected_snapshots}"
        f"{'' if res.read_ok else ' - ' + res.read_error} | all |",
        f"| wall reflections (run.json) | {rj.get('wall_reflections', '?')} | reported |",
        f"| wall time | {res.wall_s:.0f} s (load at end {os.getloadavg()[0]:.1f}) | |",
        f"| outcome | {'pass' if res.ok else 'FAIL'} | |",
    ]
    (out / f"{stem}.md").write_text("\n".join(lines) + "\n")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m verification.soak", description=__doc__)
    ap.add_argument("--spacing-ratio", type=int, default=40, help="a / dx (the scene's default is 40)")
    ap.add_argument("--factor", type=float, default=FACTOR, help="x the scene's end time")
    ap.add_argument("--out", type=Path, help="run directory (default runs/soak_rN)")
    ap.add_argument("--set", action="append", default=[], help="scene override, as for scoursph run")
    ap.add_argument("--note", default="", help="a line for the report (e.g. the load)")
    args = ap.parse_args(argv)
    res = soak(args.spacing_ratio, args.factor, args.out, args.set, quiet=False)
    write_report(res, note=args.note + (f" Options: {' '.join(args.set)}." if args.set else ""))
    print(
        f"soak a/{args.spacing_ratio}: {res.status}; RSS {res.rss_warm_mb:.1f} -> max "
        f"{res.rss_max_mb:.1f} MB "
        f"({100 * res.growth:.2f} %), fds {res.fd_first} -> {res.fd_last}, snapshots read "
        f"{res.snapshots}/{res.expected_snapshots} {'ok' if res.read_ok else res.read_error}; "
        f"{res.wall_s:.0f} s: {'PASS' if res.ok else 'FAIL'}"
    )
    return 0 if res.ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
