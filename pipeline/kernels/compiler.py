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
        (root / name).mkdir(parents=True, exist_ok=True)
    except OSError:  # a read-only home (some cluster nodes): cache per machine in the temporary directory
        import tempfile

        root = Path(tempfile.gettempdir()) / "gyrolab"
    return str(root / name)


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
