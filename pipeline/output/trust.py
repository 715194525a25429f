"""The trust boundary of a directory gyrolab writes into but may not have created (docs/faults.md, "A directory
gyrolab did not create").

gyrolab trusts the directory the user names, never what already sits inside it: its own entries there are never
links or special files (``check_tree``), a file it appends to or locks is opened without following a link
(``open_own_file``), its folders are real folders (``own_dir``), an output the user names is not a link or a
device (``check_output_target``), and pickles are loaded only from folders only the user can write
(``private_dir``). Each refusal is an ``Untrusted`` ConfigError (exit 2): one sentence naming the path.
"""

from __future__ import annotations

import contextlib
import errno
import os
import stat
import sys
from pathlib import Path

from gyrolab.errors import ConfigError, shorten
from gyrolab.kernels.cache import cache_dir

#: gyrolab's folders inside a run or sweep directory
OWN_DIRS = frozenset({"figures", ".hydra", ".submitit"})
#: gyrolab's files inside a run or sweep directory (besides every name ending in OWN_SUFFIXES)
OWN_FILES = frozenset({".gyrolab.lock", "multirun.yaml", "job.json"})
OWN_SUFFIXES = (".nc", ".log", ".yaml", ".json", ".part", ".chunks", ".csv")
REMEDY = "gyrolab never follows links in a directory it writes; remove it or choose another directory"


class Untrusted(ConfigError):
    """Something in a directory gyrolab writes into that it will not follow or overwrite."""


def _where(path: Path) -> str:
    """The path for a sentence: a long folder shortened, the entry's own name always whole (it is what to remove)."""
    text = str(path)
    if len(text) <= 80:
        return repr(text)
    return repr(f"{shorten(str(path.parent), 60)}/{shorten(path.name, 40)}")


def _refusal(path: Path, mode: int) -> Untrusted:
    if stat.S_ISLNK(mode):
        return Untrusted(f"{_where(path)} is a symbolic link; {REMEDY}")
    if path.name in OWN_DIRS and not stat.S_ISDIR(mode):
        return Untrusted(f"{_where(path)} is a file, where gyrolab keeps a folder; remove it or choose another "
                         "directory")
    kind = "a folder" if stat.S_ISDIR(mode) else "a device, a FIFO or a socket"
    return Untrusted(f"{_where(path)} is {kind}, not a regular file gyrolab writes; remove it or choose another "
                     "directory")


def _own(name: str) -> bool:
    return name in OWN_DIRS or name in OWN_FILES or name.endswith(OWN_SUFFIXES)


def check_tree(directory: str | os.PathLike[str], *, sweep: bool = False) -> None:
    """Untrusted for the first of gyrolab's entries in ``directory`` that is a link or of the wrong kind (module
    docstring); ``sweep``: every entry of the sweep directory, and gyrolab's entries in each job directory."""
    directory = Path(directory)
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return  # missing, or unreadable: the writes that follow say so
    for entry in sorted(entries, key=lambda e: e.name):
        if not (sweep or _own(entry.name)):
            continue
        mode = entry.stat(follow_symlinks=False).st_mode
        if stat.S_ISLNK(mode):
            raise _refusal(Path(entry.path), mode)
        if stat.S_ISDIR(mode):
            if entry.name in OWN_DIRS or sweep and not entry.name.startswith("."):
                check_tree(entry.path)  # figures/, .hydra/, a job directory
            continue
        if entry.name in OWN_DIRS or not stat.S_ISREG(mode) and _own(entry.name):
            raise _refusal(Path(entry.path), mode)


def own_dir(path: str | os.PathLike[str]) -> Path:
    """The folder ``path`` (``figures``, ``.hydra``), created if missing; Untrusted when it is a link or a file."""
    path = Path(path)
    try:
        with contextlib.suppress(FileExistsError):
            path.parent.mkdir(parents=True, exist_ok=True)
            os.mkdir(path)
    except OSError:
        return path  # the write that follows names the reason (a read-only directory, a full disk)
    mode = os.lstat(path).st_mode
    if not stat.S_ISDIR(mode):
        raise _refusal(path, mode)
    return path


def open_own_file(path: str | os.PathLike[str], flags: int, mode: int = 0o644) -> int:
    """``os.open`` of a file gyrolab creates or appends to, without following a link, refusing anything but a
    regular file (a FIFO is not waited on)."""
    path = Path(path)
    try:
        fd = os.open(path, flags | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC, mode)
    except OSError as error:
        if error.errno in (errno.ELOOP, errno.EMLINK):
            raise Untrusted(f"{_where(path)} is a symbolic link; {REMEDY}") from None
        if error.errno == errno.ENXIO:  # a FIFO nobody reads
            raise _refusal(path, stat.S_IFIFO) from None
        raise
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise _refusal(path, info.st_mode)
    os.set_blocking(fd, True)
    return fd


def check_output_target(path: str | os.PathLike[str], option: str = "") -> Path:
    """A file gyrolab is about to replace (``option``: the option that named it, ``-o``): refused when it exists and
    is not a regular file (a device node, a link, a folder), which writing would replace."""
    path = Path(path)
    try:
        info = os.lstat(path)
    except OSError:
        return path  # missing (or unreachable: the write says why)
    if not stat.S_ISREG(info.st_mode):
        kind = {stat.S_IFLNK: "a symbolic link", stat.S_IFDIR: "a folder"}.get(stat.S_IFMT(info.st_mode),
                                                                              "a device, a FIFO or a socket")
        raise Untrusted(f"{option + ' ' if option else ''}{_where(path)} exists and is {kind}, not a regular file; "
                        f"gyrolab does not write over it: give another name or remove it")
    return path


def private_dir(path: str | os.PathLike[str], what: str) -> Path:
    """The folder ``path``, which holds pickles gyrolab loads (``what`` says whose): created owner-only (0700) if
    missing; Untrusted when it is a link, belongs to another user, or others may write it."""
    path = Path(path)
    with contextlib.suppress(FileExistsError):
        path.parent.mkdir(parents=True, exist_ok=True)
        os.mkdir(path, 0o700)
    info = os.lstat(path)
    if stat.S_ISLNK(info.st_mode) or not stat.S_ISDIR(info.st_mode):
        raise _refusal(path, info.st_mode)
    if info.st_uid != os.geteuid():
        raise Untrusted(f"{what} {_where(path)} belongs to another user (uid {info.st_uid}); gyrolab loads pickles "
                        "only from a folder only you can write: remove it or choose another directory")
    if info.st_mode & 0o022:
        raise Untrusted(f"{what} {_where(path)} may be written by others (mode {stat.S_IMODE(info.st_mode):o}); "
                        f"gyrolab loads pickles only from a folder only you can write: chmod go-w {shorten(str(path))}"
                        " or remove it")
    return path


def check_kernel_cache() -> None:
    """Untrusted when numba's cache folder (whose index numba unpickles) or its parent belongs to another user or may
    be written by anyone; called before any kernel is loaded (run, batch, reproduce)."""
    # the folder numba uses once it is set up in this process, else the one it will use (found without importing
    # numba, which a run of scipy's integrators never needs)
    numba = sys.modules.get("numba")
    folder = (numba.config.CACHE_DIR if numba is not None and "gyrolab.kernels.compiler" in sys.modules else None) \
        or cache_dir()
    for path in (Path(folder), Path(folder).parent) if folder else ():
        try:
            info = os.lstat(path)
        except OSError:
            continue
        if info.st_uid != os.geteuid() or stat.S_ISLNK(info.st_mode) or (
                info.st_mode & 0o002 and not info.st_mode & stat.S_ISVTX):
            raise Untrusted(f"numba's cache folder {_where(path)} belongs to another user or may be written by anyone "
                            "(numba loads pickles from it); set NUMBA_CACHE_DIR to a folder of yours")


def proc_number(path: str, key: str, base: int = 10) -> int | None:
    """The number after ``key`` in a Linux /proc file (``Umask:`` of ``/proc/self/status``), None without one."""
    with contextlib.suppress(OSError, ValueError, IndexError), open(path, encoding="ascii") as handle:
        return next((int(line.split()[1], base) for line in handle if line.startswith(key)), None)
    return None


def umask() -> int:
    """The process's umask, read without changing it (Linux's /proc; elsewhere set and restored at once)."""
    mask = proc_number("/proc/self/status", "Umask:", 8)
    if mask is None:
        mask = os.umask(0o022)
        os.umask(mask)
    return mask
