"""One writer per directory: a run directory, a sweep job's directory or a sweep's ``sweep.nc`` (docs/faults.md,
"One writer per directory").

A lock is an exclusive ``flock`` on ``.gyrolab.lock`` in the directory (holding the owner's pid and host for the
messages), which the kernel drops when its process ends however it ends; the file is removed on release. On a
file system without flock the lock is taken without effect and a warning is logged. A process may take a lock
it already holds (the hold is counted).
"""

from __future__ import annotations

import atexit
import contextlib
import errno
import fcntl
import logging
import os
import socket
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from gyrolab.errors import ConfigError, OutputError
from gyrolab.output.atomic import reason, remove_stale_temporaries
from gyrolab.output.trust import open_own_file

log = logging.getLogger("gyrolab")

LOCK_NAME = ".gyrolab.lock"


class Busy(ConfigError):
    """The directory is locked by another live process (``owner`` says which, when it wrote it)."""

    def __init__(self, message: str, owner: str) -> None:
        super().__init__(message)
        self.owner = owner


#: directory (resolved) -> [file descriptor, hold count] for the locks this process holds
_held: dict[Path, list[int]] = {}


def owner_of(directory: Path) -> str:
    """Who holds (or last held) ``directory``'s lock, as its lock file says: 'pid N on HOST', or ''."""
    try:
        fd = open_own_file(Path(directory) / LOCK_NAME, os.O_RDONLY)
    except (OSError, ConfigError):
        return ""
    with os.fdopen(fd, "rb") as handle:
        text = handle.read(MAX_OWNER_BYTES).decode("utf-8", "replace").strip()
    return "".join(c for c in text if c.isprintable())[:120]  # a planted file's escape sequences are not echoed


def try_lock(directory: str | os.PathLike[str], *, blocking: bool = False) -> bool:
    """Take ``directory``'s lock if free (True), or say it is held by another live process (False).

    ``blocking``: wait for it instead. Release it with ``unlock``. The directory is created if needed.
    """
    key = Path(directory).resolve()
    if key in _held:
        _held[key][1] += 1
        return True
    try:
        key.mkdir(parents=True, exist_ok=True)
        fd = _acquire(key / LOCK_NAME, blocking=blocking)
    except OSError as error:
        raise OutputError(f"cannot lock {str(directory)!r}: {reason(error)}") from None
    if fd is None:
        return False
    _held[key] = [fd, 1]
    return True


def release_all() -> None:
    """Release every lock this process holds and remove its lock file (the end of a command, however it ends: Hydra
    skips the callback's ``on_run_end`` when a run fails, which would leave its ``.gyrolab.lock``)."""
    for key in list(_held):
        _held[key][1] = 1
        unlock(key)


atexit.register(release_all)  # on every exit Python sees (sys.exit, an uncaught exception, Ctrl-C)


def unlock(directory: str | os.PathLike[str]) -> None:
    key = Path(directory).resolve()
    entry = _held.get(key)
    if entry is None:
        return
    entry[1] -= 1
    if entry[1] > 0:
        return
    del _held[key]
    with contextlib.suppress(OSError):
        (key / LOCK_NAME).unlink(missing_ok=True)  # still ours: nobody else can hold it while we do
    os.close(entry[0])  # releases the flock


def lock(directory: str | os.PathLike[str], what: str = "run directory") -> None:
    """Take ``directory``'s lock (release it with ``unlock``); ``Busy`` (a ConfigError, exit 2) if another
    process holds it, ``OutputError`` if no lock file can be made there."""
    if not try_lock(directory):
        owner = owner_of(Path(directory))
        raise Busy(f"{what} {str(directory)!r} is in use by another gyrolab run"
                   f"{f' ({owner})' if owner else ''}; wait for it to end or choose another directory", owner)


@contextmanager
def writing_in(directory: str | os.PathLike[str], what: str = "run directory") -> Iterator[Path]:
    """Hold ``directory``'s lock for the block (see ``lock``), first removing the temporary files killed writes left
    in it and its ``figures``."""
    directory = Path(directory)
    lock(directory, what)
    try:
        clear_temporaries(directory)
        yield directory
    finally:
        unlock(directory)


def clear_temporaries(directory: str | os.PathLike[str]) -> None:
    """Remove what killed writes left in ``directory`` and its ``figures``; hold the directory's lock."""
    directory = Path(directory)
    for place in (directory, directory / "figures"):
        for leftover in remove_stale_temporaries(place):
            log.info("removed %s, left by an interrupted write", leftover)


def wait_for(directory: str | os.PathLike[str]) -> None:
    """Block until no other process holds ``directory``'s lock (returns at once when it is free)."""
    path = Path(directory) / LOCK_NAME
    if not path.exists() or Path(directory).resolve() in _held:
        return
    try:
        fd = _acquire(path, blocking=True, create=False)
    except OSError:
        return
    if fd is not None:
        os.close(fd)  # taken and given back at once; the file stays for whoever else waits


def _acquire(path: Path, *, blocking: bool, create: bool = True) -> int | None:
    """An fd holding an exclusive flock on ``path`` (the file now in the directory), or None when busy. The file is
    opened without following a link (a planted ``.gyrolab.lock`` link is refused, never truncated); the owner's
    line is written only into a file this call created, or a lock file of gyrolab's (``_write_owner``)."""
    while True:
        fd, created = _open_lock_file(path, create)
        if fd is None:
            return None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | (0 if blocking else fcntl.LOCK_NB))
        except OSError as error:
            os.close(fd)
            if error.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                return None
            if error.errno in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS):
                log.warning("the file system of %s has no file locks; two gyrolab runs in this directory "
                            "would not be told apart", path.parent)
                return open_own_file(path, os.O_RDWR)
            raise
        try:
            info = os.fstat(fd)
            same = info.st_ino == os.lstat(path).st_ino
        except OSError:
            same = False
        if not same:  # the holder released and removed the file between our open and our flock: again
            os.close(fd)
            if not create:
                return None
            continue
        if create:
            _write_owner(fd, created, info)
        return fd


def _open_lock_file(path: Path, create: bool) -> tuple[int | None, bool]:
    """(an fd on ``path``, whether this call created the file); (None, False) when it is gone and not to be
    created."""
    if not create:
        try:
            return open_own_file(path, os.O_RDWR), False
        except FileNotFoundError:
            return None, False
    while True:
        try:
            return open_own_file(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644), True
        except FileExistsError:
            with contextlib.suppress(FileNotFoundError):  # removed between the two opens: again
                return open_own_file(path, os.O_RDWR), False


def _write_owner(fd: int, created: bool, info: os.stat_result) -> None:
    """Who holds the lock, for the messages of others: into a file this call created, or a lock file of gyrolab's
    (one link, the user's, a line long)."""
    if created or (info.st_nlink == 1 and info.st_uid == os.geteuid() and info.st_size <= MAX_OWNER_BYTES):
        with contextlib.suppress(OSError):  # a full disk may refuse this, the lock holds anyway
            os.ftruncate(fd, 0)
            os.write(fd, f"pid {os.getpid()} on {socket.gethostname()}\n".encode())


#: a lock file holds one line; a larger file is not overwritten
MAX_OWNER_BYTES = 4096
