"""Helpers shared by the reference-case pipelines: running external tools with
timing and logs, provenance (manifest.json), host facts.

Nothing here knows about OpenFOAM or LIGGGHTS in particular.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import shlex
import shutil
import subprocess
import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent


class ToolMissing(RuntimeError):
    """An external program the pipeline needs is not on PATH."""


class ToolFailed(RuntimeError):
    """An external program returned a non-zero exit code."""


def require(*programs: str) -> None:
    missing = [p for p in programs if shutil.which(p) is None]
    if missing:
        raise ToolMissing(
            "not on PATH: " + ", ".join(missing) + " (install with: bash reference_cases/install_tools.sh)"
        )


def mpirun_prefix(ranks: int) -> list[str]:
    """`mpirun -np N` with the flags this kind of host needs (root, few slots)."""
    cmd = ["mpirun", "-np", str(ranks), "--oversubscribe", "--bind-to", "none"]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.insert(1, "--allow-run-as-root")
    return cmd


def run(cmd: list[str], cwd: Path, log: Path, env: dict | None = None, record: list | None = None) -> float:
    """Run `cmd` in `cwd`, stdout+stderr to `log`; return wall seconds.

    The command line (relative to the case directory) and its wall time are
    appended to `record` (the manifest's list of exact commands).
    """
    full_env = dict(os.environ)
    if env:
        full_env.update(env)
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.run(cmd, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT, env=full_env)
    wall = time.perf_counter() - t0
    if record is not None:
        record.append(
            {
                "command": shlex.join(cmd),
                "cwd": str(_rel(cwd)),
                "log": str(_rel(log)),
                "wall_s": round(wall, 2),
            }
        )
    if proc.returncode != 0:
        tail = log.read_text(errors="replace")[-3000:]
        raise ToolFailed(f"{shlex.join(cmd)} failed (rc={proc.returncode}) in {cwd}; log {log}:\n{tail}")
    return wall


def _rel(p: Path) -> Path:
    try:
        return Path(p).resolve().relative_to(REPO_ROOT)
    except ValueError:
        return Path(p)


def host_facts() -> dict:
    return {
        "hostname": platform.node(),
        "cpu_cores": os.cpu_count(),
        "os": _os_release(),
        "python": platform.python_version(),
        "nice": os.nice(0) if hasattr(os, "nice") else None,
        "load_avg_at_end": [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None,
    }


def _os_release() -> str:
    try:
        for line in Path("/etc/os-release").read_text().splitlines():
            if line.startswith("PRETTY_NAME="):
                return line.split("=", 1)[1].strip('"')
    except OSError:
        pass
    return platform.platform()


def debian_package_version(pkg: str) -> str | None:
    try:
        out = subprocess.run(
            ["dpkg-query", "-W", "-f=${Version}", pkg], capture_output=True, text=True, check=False
        )
        return out.stdout.strip() or None
    except FileNotFoundError:
        return None


def now_iso() -> str:
    return _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat()


def update_manifest(path: Path, run_key: str, run_entry: dict, top: dict) -> dict:
    """Merge one run's record into manifest.json (other runs are kept)."""
    path = Path(path)
    data = json.loads(path.read_text()) if path.exists() else {}
    data.update(top)
    runs = data.setdefault("runs", {})
    runs[run_key] = run_entry
    data["runs"] = dict(sorted(runs.items()))
    path.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n")
    return data


def set_manifest_section(path: Path, key: str, value) -> None:
    path = Path(path)
    data = json.loads(path.read_text()) if path.exists() else {}
    data[key] = value
    path.write_text(json.dumps(data, indent=2, sort_keys=False) + "\n")


def fill_template(text: str, values: dict) -> str:
    """Replace @KEY@ placeholders; refuse to leave any unreplaced."""
    for k, v in values.items():
        text = text.replace(f"@{k}@", str(v))
    if "@" in text:
        import re

        left = re.findall(r"@[A-Z0-9_]+@", text)
        if left:
            raise ValueError(f"unreplaced placeholders: {sorted(set(left))}")
    return text


def copy_template(template: Path, work: Path, values: dict) -> None:
    """A fresh case directory `work`: every file of `template` with its @KEY@ placeholders filled."""
    if work.exists():
        shutil.rmtree(work)
    for src in template.rglob("*"):
        if src.is_file():
            dst = work / src.relative_to(template)
            dst.parent.mkdir(parents=True, exist_ok=True)
            dst.write_text(fill_template(src.read_text(), values))


def fmt(x: float, digits: int = 8) -> str:
    return f"{x:.{digits}g}"
