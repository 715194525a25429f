"""numba, set up once for every kernel: the decorators and the on-disk cache of compiled code.

Compiled code is cached on disk between processes. numba only checks the timestamp of the file that
defines a kernel, not of the kernels it calls, so the cache lives in a
directory named after a hash of this package's sources and numba's version: editing any kernel
starts a fresh cache instead of reusing stale machine code.
"""

from __future__ import annotations

import hashlib
import os
import platform
from pathlib import Path


def _cache_dir() -> str:
    from importlib.metadata import version

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
    (``expression.load_generated``) are imported from it, so no one else may write there."""
    folder.parent.mkdir(parents=True, exist_ok=True)
    folder.mkdir(mode=0o700, exist_ok=True)


def private_temporary() -> Path:
    """This user's folder for gyrolab in the temporary directory (``gyrolab-UID``, owner-only): a shared
    ``/tmp/gyrolab`` that another user created first could hold code or pickles gyrolab would load."""
    import tempfile

    folder = Path(tempfile.gettempdir()) / f"gyrolab-{os.getuid() if hasattr(os, 'getuid') else 'user'}"
    _private(folder)
    return folder


import numba  # noqa: E402

if "NUMBA_CACHE_DIR" not in os.environ:
    numba.config.CACHE_DIR = _cache_dir()


def kernel_cache_dir() -> str:
    """The directory of compiled kernels (also of the generated force modules, ``expression``)."""
    return numba.config.CACHE_DIR or _cache_dir()

#: Decorator of every kernel: cached on disk; numpy's error model (no zero-division checks
#: inside the arithmetic, which cost more than the arithmetic; a zero divisor gives inf/NaN,
#: which the integrators detect and report).
kernel = numba.njit(cache=True, error_model="numpy")
inline_kernel = numba.njit(cache=True, error_model="numpy", inline="always")
