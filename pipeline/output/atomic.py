"""Every file gyrolab writes appears whole or not at all.

A result is written to a temporary file beside its final path (same directory,
so the rename cannot cross file systems), flushed to disk, then renamed over
the final name. A killed process leaves at most a temporary file, named
``.<final name>.<random>.tmp``, which the next run or resume in that directory
removes (``remove_stale_temporaries``). A write that fails for want of space,
quota or permission is one ``OutputError`` sentence naming the file and the
reason, and leaves no partial file.
"""

from __future__ import annotations

import errno
import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from gyrolab.errors import OutputError

#: how a temporary file of ``atomic_path`` is named: prefix "." + final name + ".", suffix
TEMP_SUFFIX = ".tmp"

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


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path to write; on success it is renamed to ``path``, on failure removed.

    OSErrors raised while writing (or by the caller's writer, e.g. netCDF's "HDF error" for a full
    disk surfaces as OSError/RuntimeError) become one ``OutputError`` naming ``path``.
    """
    path = Path(path)
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
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes the file private; results are ordinary files
        os.replace(tmp, path)
    except OSError as error:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {str(path)!r}: {reason(error)}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def _fsync(path: Path) -> None:
    with open(path, "rb") as handle:
        os.fsync(handle.fileno())


def remove_stale_temporaries(directory: str | os.PathLike[str]) -> list[Path]:
    """Remove temporary files that killed writes left in ``directory`` (not recursive); returns them."""
    removed = []
    for leftover in Path(directory).glob(f".*{TEMP_SUFFIX}"):
        if leftover.is_file():
            leftover.unlink(missing_ok=True)
            removed.append(leftover)
    return removed
