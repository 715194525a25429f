"""Every file gyrolab writes appears whole or not at all (docs/faults.md, "Every file appears whole or not at all").

A result is written to a temporary file beside its final path (``.<final name>.<random>.tmp``), flushed, then
renamed over the final name; the next run or resume in that directory removes what a killed write left
(``remove_stale_temporaries``, while the directory is locked). A failed write is one ``OutputError`` sentence
naming the file and the reason; the netCDF library reports a full disk or a file-size limit without an errno
("HDF error"), so ``diagnose`` then finds the reason after the failure.
"""

from __future__ import annotations

import contextlib
import errno
import os
import resource
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from gyrolab.errors import OutputError
from gyrolab.output.trust import OWN_DIRS, check_output_target, own_dir, umask

#: how a temporary file of ``atomic_path`` is named: prefix "." + final name + ".", suffix
TEMP_SUFFIX = ".tmp"
#: bytes written by the probe that looks for the reason of a write failure without an errno
PROBE_BYTES = 1 << 20

_REASONS = {
    errno.ENOSPC: "no space left on device",
    errno.EFBIG: "file too large for this file system or the process's file-size limit",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EACCES: "permission denied",
    errno.EPERM: "operation not permitted",
}


def reason(error: OSError) -> str:
    """A short human reason for an OSError."""
    return _REASONS.get(error.errno, error.strerror or type(error).__name__)


#: what netCDF's RuntimeErrors say when the write itself failed (a full disk or a file-size limit is "HDF error")
_LIBRARY_WRITE_FAILURES = ("HDF error", "Write to read only", "Permission denied", "No space", "Disk quota",
                           "File too large", "Can't create file", "I/O failure")


def _library_failure(error: BaseException) -> bool:
    """An error of a writing library that stands for a failed write, not for bad content (a bug)."""
    return isinstance(error, RuntimeError) and any(text in str(error) for text in _LIBRARY_WRITE_FAILURES)


@contextmanager
def atomic_path(path: str | os.PathLike[str], *, expected_bytes: int | None = None) -> Iterator[Path]:
    """Yield a temporary path to write; on success it is renamed to ``path``, on failure removed, and a failed write
    (an OSError, netCDF's "HDF error") is one ``OutputError`` naming ``path`` and the reason. ``expected_bytes``
    (the finished file's approximate size) lets the reason of an errno-less failure be found from the free space."""
    path = Path(path)
    if path.parent.name in OWN_DIRS:
        own_dir(path.parent)  # figures/, .hydra/: a real folder, not a link out of the run directory
    check_output_target(path)  # a link or a device there is refused, not replaced
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=TEMP_SUFFIX, dir=path.parent)
        os.close(fd)
    except OSError as error:
        raise OutputError(f"cannot write {str(path)!r}: {reason(error)}") from None
    tmp = Path(name)
    try:
        yield tmp
        _fsync(tmp)
        os.chmod(tmp, 0o666 & ~umask())  # mkstemp makes the file private; results are ordinary files
        os.replace(tmp, path)
        _fsync_directory(path.parent)
    except BaseException as error:  # the temporary file goes; a failed write (not bad content) is one sentence
        failed_write = not isinstance(error, OutputError) and (isinstance(error, OSError) or _library_failure(error))
        why = diagnose(error, tmp, expected_bytes) if failed_write else ""
        tmp.unlink(missing_ok=True)
        if failed_write:
            raise OutputError(f"cannot write {str(path)!r}: {why}") from None
        raise


@contextmanager
def atomic_open(path: str | os.PathLike[str], mode: str = "w", **kwargs) -> Iterator:
    """``open`` for writing, atomically: the file appears at ``path`` whole when the block ends."""
    with atomic_path(path) as tmp, open(tmp, mode, **kwargs) as handle:
        yield handle


#: errnos that say what happened; others (netCDF reports a failed create on a full disk as EACCES) are checked
_TRUSTED = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG, errno.EROFS)


def diagnose(error: BaseException, tmp: Path, expected_bytes: int | None = None) -> str:
    """Why writing ``tmp`` failed: the error's own errno when it is unambiguous, else what the file system
    says now (file-size limit, a probe write, the free space), else the error's own reason."""
    if isinstance(error, OSError) and error.errno in _TRUSTED:
        return reason(error)
    try:
        written = tmp.stat().st_size
    except OSError:
        written = 0
    limit, _ = resource.getrlimit(resource.RLIMIT_FSIZE)
    if limit != resource.RLIM_INFINITY and max(written + PROBE_BYTES, expected_bytes or 0) >= limit:
        return f"file too large for the process's file-size limit of {_size(limit)} (ulimit -f)"
    try:  # a full disk or quota fails this small write too, with the errno the library did not report
        with open(tmp, "ab") as handle:
            handle.write(bytes(PROBE_BYTES))
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as probe:
        if probe.errno in _TRUSTED:
            return reason(probe)
    with contextlib.suppress(OSError):
        stats = os.statvfs(tmp.parent)
        free = (stats.f_bfree if os.geteuid() == 0 else stats.f_bavail) * stats.f_frsize
        free += written + PROBE_BYTES  # the temporary file is removed: its blocks count as free
        if expected_bytes is not None and free < expected_bytes:
            return f"{_REASONS[errno.ENOSPC]} ({_size(free)} free, about {_size(expected_bytes)} needed)"
    if isinstance(error, OSError):
        return reason(error)
    return f"the netCDF library failed ({error})"


def _size(n: int) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.0f} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n} bytes"  # pragma: no cover - unreachable


def _fsync(path: Path) -> None:
    with open(path, "rb") as handle:
        os.fsync(handle.fileno())


def _fsync_directory(directory: Path) -> None:
    """Flush the rename itself (POSIX keeps it in the directory's metadata)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        with contextlib.suppress(OSError):  # some file systems cannot fsync a directory; the rename happened
            os.fsync(fd)
    finally:
        os.close(fd)


def remove_stale_temporaries(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove (and return) the temporary files that killed writes left in ``directory`` (not recursive). Only while
    holding the directory's lock: a temporary file of a write in progress looks like a stale one."""
    removed = []
    for leftover in Path(directory).glob(f".*{TEMP_SUFFIX}"):
        with contextlib.suppress(OSError):  # gone already, or not ours to remove: nothing is lost by leaving it
            if leftover.is_file():
                leftover.unlink()
                removed.append(leftover)
    return removed
