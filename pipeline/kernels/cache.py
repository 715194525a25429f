"""Where compiled code is cached on disk between processes, found without importing numba.

numba only checks the timestamp of the file that defines a kernel, not of the kernels it calls, so the cache
lives in a directory named after a hash of this package's sources and numba's version: editing any kernel starts
a fresh cache instead of reusing stale machine code. The folder is owner-only: numba unpickles its index, and the
generated kernels (``expression.generated_module``) are imported from it. (numba-free, so that the trust boundary
can check the folder on every run without the half second numba's import costs.)
"""

from __future__ import annotations

import hashlib
import os
import platform
from pathlib import Path


def cache_dir() -> str:
    """NUMBA_CACHE_DIR when set, else gyrolab's folder for this package's sources and numba's version."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        return os.environ["NUMBA_CACHE_DIR"]
    from importlib.metadata import version  # start-up: only where NUMBA_CACHE_DIR is unset

    digest = hashlib.sha256(f"numba {version('numba')} {platform.machine()}".encode())
    for source in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(source.read_bytes())
    name = f"numba-{digest.hexdigest()[:16]}"
    root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gyrolab"
    try:
        _private(root)
        (root / name).mkdir(mode=0o700, exist_ok=True)
    except OSError:  # a read-only home (some cluster nodes): a folder of this user's in the temporary directory
        root = private_temporary()
    return str(root / name)


def _private(folder: Path) -> None:
    """Make ``folder`` (and missing parents) owner-only: numba unpickles its cache index, and the generated kernels
    (``expression.generated_module``) are imported from it, so no one else may write there."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    folder.mkdir(mode=0o700, exist_ok=True)


def private_temporary() -> Path:
    """This user's folder for gyrolab in the temporary directory (``gyrolab-UID``, owner-only): a shared
    ``/tmp/gyrolab`` that another user created first could hold code or pickles gyrolab would load."""
    import tempfile  # (rare: only for a read-only cache)

    folder = Path(tempfile.gettempdir()) / f"gyrolab-{os.getuid() if hasattr(os, 'getuid') else 'user'}"
    _private(folder)
    return folder


