"""numba, set up once for every kernel: the decorators, and the on-disk cache of compiled code (``cache``)."""

from __future__ import annotations

import os

import numba

from gyrolab.kernels.cache import cache_dir as _cache_dir

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
