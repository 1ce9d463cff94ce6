"""Which output directories a run may write to, and which files in them are its own.

A run never deletes what ScourSPH did not write. It claims its output directory with a
marker file, MARKER (JSON: solver version, scene name, start time), written before any
other output:

  * a directory that does not exist, or is empty, is claimed;
  * a directory holding an earlier run (it has the marker) is replaced only with
    `overwrite=True`, and then only the files a run writes (OWN_FILES, and the numbered
    snapshot and VTK files in OWN_DIRS) are removed; anything else a user put there stays;
  * any other non-empty directory (`--out .`, a home directory) and any non-directory path
    are refused with RunDirError (exit status 2), before anything is computed or written.

A restart (`--restart`, output/checkpoint.py) continues in a run directory: it calls
`claim(..., mode="continue")`, which keeps the existing outputs and refreshes the marker.
"""

from __future__ import annotations

import datetime
import json
import os
import re
from pathlib import Path

from .. import __version__
from .atomic import atomic_write_text, is_partial  # is_partial: write-then-rename leftovers of a crashed run

MARKER = ".scoursph-run"
OWN_FILES = ("particles.h5", "particles.pvd", "final.png", "scene.toml", "run.json")
# sub-directory -> names of the files a run writes there (snapshot and VTK series)
OWN_DIRS = {
    "snapshots": re.compile(r"\d{6}\.h5"),
    "vtk": re.compile(r"\d{6}\.vtp"),
    "checkpoints": re.compile(r"\d{9}\.h5"),  # output/checkpoint.py
}
MODES = ("new", "overwrite", "continue")


class RunDirError(Exception):
    """An output directory a run must not use: names the directory and the reason (exit 2)."""

    def __init__(self, path, reason):
        self.path, self.reason = str(path), reason
        super().__init__(f"{path}: {reason}")


def read_marker(out_dir) -> dict | None:
    """The marker of a run directory ({} if unreadable), or None if it is not one."""
    marker = Path(out_dir) / MARKER
    if not marker.is_file():
        return None
    try:
        data = json.loads(marker.read_text())
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def check(out_dir, mode="new") -> None:
    """Raise RunDirError if a run in `mode` ("new", "overwrite", "continue") may not write
    to `out_dir`. Writes nothing."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, not {mode!r}")
    path = Path(out_dir)
    if not path.exists():
        if mode == "continue":
            raise RunDirError(path, "no such run directory to continue")
        if path.is_symlink():
            raise RunDirError(path, "is a dangling symbolic link")
        parent = next(p for p in path.absolute().parents if p.exists())
        if not parent.is_dir():
            raise RunDirError(path, f"cannot be created: {parent} is not a directory")
        if not os.access(parent, os.W_OK | os.X_OK):
            raise RunDirError(path, f"cannot be created: {parent} is not writable")
        return
    if not path.is_dir():
        raise RunDirError(path, "exists and is not a directory")
    if not os.access(path, os.R_OK | os.W_OK | os.X_OK):
        raise RunDirError(path, "is not writable")
    if not any(path.iterdir()):
        if mode == "continue":
            raise RunDirError(path, "is empty: no run to continue")
        return
    marker = read_marker(path)
    if marker is None:
        raise RunDirError(
            path,
            f"is not empty and is not a ScourSPH run directory (no {MARKER} marker); ScourSPH never "
            "deletes files it did not write: choose a new or empty directory with --out",
        )
    if mode == "new":
        what = f"scene '{marker.get('scene', '?')}', started {marker.get('started', '?')}"
        raise RunDirError(
            path,
            f"holds an earlier ScourSPH run ({what}); pass --overwrite to replace it, or choose "
            "another directory with --out",
        )


def owned_files(out_dir) -> list[Path]:
    """The files in a run directory that a run wrote (the marker last)."""
    path = Path(out_dir)
    out = [path / name for name in OWN_FILES if (path / name).is_file()]
    out += [p for p in path.iterdir() if p.is_file() and is_partial(p)]
    for sub, pattern in OWN_DIRS.items():
        folder = path / sub
        if folder.is_dir() and not folder.is_symlink():
            out += sorted(
                p for p in folder.iterdir() if p.is_file() and (pattern.fullmatch(p.name) or is_partial(p))
            )
    if (path / MARKER).is_file():
        out.append(path / MARKER)
    return out


def clear(out_dir) -> None:
    """Remove a run's own files (never anything else); its sub-directories go only if emptied."""
    path = Path(out_dir)
    for p in owned_files(path):
        if p.name != MARKER:
            p.unlink()
    for sub in OWN_DIRS:
        folder = path / sub
        if folder.is_dir() and not folder.is_symlink() and not any(folder.iterdir()):
            folder.rmdir()


def claim(out_dir, scene_name, mode="new") -> Path:
    """Check `out_dir` (see `check`), then make it this run's: create it, remove an earlier
    run's own files ("overwrite"; "continue" keeps them) and write the marker."""
    check(out_dir, mode)
    path = Path(out_dir)
    try:
        path.mkdir(parents=True, exist_ok=True)
        if mode == "overwrite" and read_marker(path) is not None:
            clear(path)
    except OSError as exc:
        raise RunDirError(path, f"cannot be prepared: {exc.strerror or exc}") from None
    marker = {
        "solver": "ScourSPH",
        "version": __version__,
        "scene": scene_name,
        "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "mode": mode,
    }
    try:
        atomic_write_text(path / MARKER, json.dumps(marker, indent=2) + "\n")
    except OSError as exc:
        raise RunDirError(path, f"cannot be written: {exc.strerror or exc}") from None
    return path
