"""The host CPU's vector width in doubles, and the lane width the batch kernels were compiled for.

The batch Taylor kernel (``batch_taylor``) advances ``batch_lanes()`` trajectories in lock step, one
vector register of doubles: 8 on AVX-512, 4 on AVX/AVX2 (2 on SSE2 or NEON, where it keeps 4). The width is read from the features LLVM compiles for (llvmlite's
``get_host_cpu_features``, which is what numba targets), so it describes the code numba emits, not
only what /proc/cpuinfo claims. Both numbers are recorded next to every batch result and benchmark,
so that a timing says on which vector width it was measured.
"""

from __future__ import annotations

import functools
import os

#: doubles per vector register for each feature, widest first
WIDTHS = (("avx512f", 8), ("avx", 4), ("sse2", 2), ("neon", 2), ("asimd", 2))


def vector_doubles(features: set[str] | frozenset[str]) -> int:
    """Doubles per vector register given a set of enabled CPU feature names (1: no vector unit known)."""
    for name, width in WIDTHS:
        if name in features:
            return width
    return 1


@functools.cache
def host_features() -> frozenset[str]:
    """The CPU features numba compiles for: NUMBA_CPU_FEATURES when set (``+avx2,-avx512f,...``; numba's
    portable-cache setting), else the host's as LLVM sees them (llvmlite's ``get_host_cpu_features``)."""
    override = os.environ.get("NUMBA_CPU_FEATURES", "").strip()
    if override:
        return frozenset(f[1:] for f in override.split(",") if f.startswith("+"))
    try:
        from llvmlite import binding  # start-up: LLVM's binding loads only when the lanes' width is asked

        found = binding.get_host_cpu_features()
    except (ImportError, RuntimeError):
        return frozenset()
    return frozenset(name for name, enabled in found.items() if enabled)


def host_vector_doubles() -> int:
    """Doubles per vector register on this CPU, as LLVM targets it."""
    return vector_doubles(host_features())


def batch_lanes() -> int:
    """Trajectories per lane group of the batch Taylor kernel: one vector register of doubles, at least 4."""
    return max(4, host_vector_doubles())


def lane_attributes() -> dict[str, int]:
    """The batch Taylor kernel's lane width and the CPU's vector width, as recorded in datasets and results."""
    return {"batch_lanes": batch_lanes(), "host_vector_doubles": host_vector_doubles()}
