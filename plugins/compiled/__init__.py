"""Compiled (numba) kernels: the fast core under the compiled integrator plugins.

Kernels take plain float arrays; systems pack their parameters (``pack``), the
integrator kernels call ``models.rhs(model, ...)``. Compiled code is cached on
disk between processes. numba only checks the timestamp of the file that
defines a kernel, not of the kernels it calls, so the cache lives in a
directory named after a hash of this package's sources: editing any kernel
starts a fresh cache instead of reusing stale machine code.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path


def _cache_dir() -> str:
    digest = hashlib.sha256()
    for source in sorted(Path(__file__).parent.glob("*.py")):
        digest.update(source.read_bytes())
    root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return str(root / "gyrolab" / f"numba-{digest.hexdigest()[:16]}")


if "NUMBA_CACHE_DIR" not in os.environ:
    import numba

    numba.config.CACHE_DIR = _cache_dir()
