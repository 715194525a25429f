"""Where a result came from: package version, git commit, platform, library versions."""

from __future__ import annotations

import contextlib
import hashlib
import platform
import re
import subprocess
from functools import cache
from importlib import metadata
from pathlib import Path
from typing import Any

from gyrolab.contracts import registry

SOURCE_ROOT = Path(__file__).resolve().parents[2]
#: always recorded (when installed), on top of gyrolab's declared dependencies
LIBRARIES = ("numpy", "scipy", "xarray", "netCDF4", "hydra-core", "omegaconf", "matplotlib")
#: what can change a result (docs, tests and the README cannot)
CODE_PATHS = ("pipeline", "plugins", "conf", "hydra_plugins", "pyproject.toml")


@cache
def gyrolab_version() -> str:
    """The installed gyrolab's version (read once per process: every dataset's history line asks for it)."""
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


def _in_own_checkout() -> bool:
    """True when the source is a git checkout of gyrolab itself (not a package inside some other repo)."""
    top = _git("rev-parse", "--show-toplevel")
    return top is not None and Path(top).resolve() == SOURCE_ROOT


@cache
def code_tree() -> str:
    """20 hex digits over the git objects of CODE_PATHS at HEAD ('' outside a git checkout of gyrolab): unlike
    the commit, it stays the same across commits that change only documentation, tests or benchmarks."""
    if not _in_own_checkout():
        return ""
    listed = _git("ls-tree", "HEAD", "--", *CODE_PATHS)
    return hashlib.sha256(listed.encode()).hexdigest()[:20] if listed else ""


def _diff_digest(untracked: list[str]) -> str:
    """sha256 of the uncommitted changes to the code (CODE_PATHS), untracked files included."""
    try:
        done = subprocess.run(["git", "diff", "HEAD", "--binary", "--", *CODE_PATHS], cwd=SOURCE_ROOT,
                              capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    if done.returncode != 0 or not (done.stdout or untracked):
        return ""  # the code is as committed (documentation or tests may differ): nothing to tell apart
    digest = hashlib.sha256(done.stdout)
    for name in untracked:
        try:
            digest.update(f"\0{name}\0".encode() + (SOURCE_ROOT / name).read_bytes())
        except OSError:
            digest.update(f"\0{name}\0(unreadable)".encode())
    return digest.hexdigest()


def _libraries() -> list[str]:
    """LIBRARIES plus every runtime dependency gyrolab declares (so a new dependency is recorded too)."""
    names = list(LIBRARIES)
    try:
        requirements = metadata.requires("gyrolab") or []
    except metadata.PackageNotFoundError:
        requirements = []
    for requirement in requirements:
        if "extra ==" in requirement:
            continue
        match = re.match(r"[A-Za-z0-9][A-Za-z0-9._-]*", requirement)
        if match and match.group(0).lower() not in {n.lower() for n in names}:
            names.append(match.group(0))
    return names


def plugin_packages() -> str:
    """'name==version' of every installed distribution that registers gyrolab plugins, sorted."""
    found = set()
    for ep in registry.plugin_entry_points():
        dist = getattr(ep, "dist", None)
        if dist is not None and dist.metadata["Name"] and dist.metadata["Name"].lower() != "gyrolab":
            found.add(f"{dist.metadata['Name']}=={dist.version}")
    return " ".join(sorted(found))


@cache
def provenance() -> dict[str, Any]:
    """Attributes every dataset carries (netCDF-safe). ``git_dirty``: 1 when the code (``CODE_PATHS``, new files
    too) differs from ``git_commit``, 0 when clean, -1 when unknown; ``git_diff_sha256``: of those changes, so that
    two dirty trees differ ("" when only documentation or tests differ: a job's identity, which reads it, stays)."""
    commit = _git("rev-parse", "HEAD") if _in_own_checkout() else None
    status = _git("status", "--porcelain", "--untracked-files=no") if commit else None
    # new files under CODE_PATHS that git does not track yet (they may be imported all the same)
    listed = _git("ls-files", "--others", "--exclude-standard", "--", *CODE_PATHS) if commit else None
    untracked = sorted(line for line in (listed or "").splitlines() if line)
    dirty = -1 if status is None else int(bool(status or untracked))
    attrs: dict[str, Any] = {
        "gyrolab_version": gyrolab_version(),
        "git_commit": commit or "unknown",
        "git_dirty": dirty,
        "git_diff_sha256": _diff_digest(untracked) if dirty == 1 else "",
        "python_version": platform.python_version(),
        "platform": platform.platform(),
        "plugin_packages": plugin_packages(),
    }
    for lib in _libraries():
        with contextlib.suppress(metadata.PackageNotFoundError):
            attrs[f"version_{lib.replace('-', '_')}"] = metadata.version(lib)
    return attrs
