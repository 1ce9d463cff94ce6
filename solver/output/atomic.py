"""Write-then-rename, so a crash never leaves a half-written file where a good one was."""

from __future__ import annotations

import contextlib
import os
import re
from pathlib import Path

# the name partial_path gives: a hidden file ".<stem>.partial<suffix>"
PARTIAL_NAME = re.compile(r"\..+\.partial(\.[A-Za-z0-9]+)?")


def partial_path(path) -> Path:
    """The temporary name beside `path` that a write goes to before the rename."""
    path = Path(path)
    return path.with_name(f".{path.stem}.partial{path.suffix}")


def is_partial(path) -> bool:
    """True for a file still under the temporary name of a write in progress (or a crashed one)."""
    return PARTIAL_NAME.fullmatch(Path(path).name) is not None


def commit(tmp, path):
    """Sync the finished temporary file, rename it over `path`, and sync the directory, so the
    rename itself survives a crash of the machine."""
    with open(tmp, "rb") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    try:
        fd = os.open(Path(path).parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_path(path):
    """Yield a temporary path beside `path`; on success it replaces `path` atomically."""
    path = Path(path)
    tmp = partial_path(path)
    try:
        yield tmp
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def atomic_write_text(path, text):
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text)
