"""Where a result came from: package version, git commit, platform, library versions."""

from __future__ import annotations

import platform
import subprocess
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import Any

SOURCE_ROOT = Path(__file__).resolve().parent.parent
LIBRARIES = ("numpy", "scipy", "xarray", "netCDF4", "hydra-core", "omegaconf", "matplotlib")


def gyrolab_version() -> str:
    try:
        return metadata.version("gyrolab")
    except metadata.PackageNotFoundError:
        return "0+unknown"


def _git(*args: str) -> str | None:
    try:
        done = subprocess.run(["git", *args], cwd=SOURCE_ROOT, capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout.strip() if done.returncode == 0 else None


@cache
def provenance() -> dict[str, Any]:
    """Attributes every dataset carries (netCDF-safe)."""
    commit = _git("rev-parse", "HEAD")
    status = _git("status", "--porcelain", "--untracked-files=no") if commit else None
    attrs: dict[str, Any] = {
        "gyrolab_version": gyrolab_version(),
        "git_commit": commit or "unknown",
        "git_dirty": -1 if status is None else int(bool(status)),
        "python_version": platform.python_version(),
        "platform": platform.platform(),
    }
    for lib in LIBRARIES:
        try:
            attrs[f"version_{lib.replace('-', '_')}"] = metadata.version(lib)
        except metadata.PackageNotFoundError:
            pass
    return attrs
