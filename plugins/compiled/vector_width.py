"""The host CPU's vector width in doubles, and the lane width the batch kernels were compiled for.

The batch kernels (``batch_taylor``, ``batch_dop853``) advance ``simd.LANES`` trajectories in lock step.
Whether that fills the CPU's vector registers depends on the CPU: 8 doubles on AVX-512, 4 on AVX/AVX2,
2 on SSE2 or NEON. The width is read from the features LLVM compiles for (llvmlite's
``get_host_cpu_features``, which is what numba targets), so it describes the code numba emits, not
only what /proc/cpuinfo claims. Both numbers are recorded next to every batch result and benchmark,
so that a timing says on which vector width it was measured.
"""

from __future__ import annotations

import functools

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
    """The host CPU features LLVM enables (``+name`` entries of llvmlite's feature map)."""
    try:
        from llvmlite import binding

        found = binding.get_host_cpu_features()
    except (ImportError, RuntimeError):
        return frozenset()
    return frozenset(name for name, enabled in found.items() if enabled)


def host_vector_doubles() -> int:
    """Doubles per vector register on this CPU, as LLVM targets it."""
    return vector_doubles(host_features())


def lane_attributes() -> dict[str, int]:
    """The batch kernels' lane width and the host's vector width, as recorded in datasets and results."""
    from gyrolab.plugins.compiled.simd import LANES

    return {"batch_lanes": int(LANES), "host_vector_doubles": host_vector_doubles()}
