"""The CPU's vector width (doubles per register) and the batch kernels' lane width, detected and recorded."""

from __future__ import annotations

from pathlib import Path

import pytest

from gyrolab.kernels import vector_width


@pytest.mark.parametrize("features, width", [
    ({"sse2", "avx", "avx2", "fma", "avx512f", "avx512dq"}, 8),   # AVX-512: 512 bits / 64
    ({"sse2", "avx", "avx2", "fma"}, 4),                          # AVX2: 256 bits
    ({"sse2", "sse4.2"}, 2),                                      # SSE: 128 bits
    ({"neon"}, 2),                                                # Arm NEON: 128 bits
    (set(), 1),
])
def test_vector_doubles_from_features(features, width):
    assert vector_width.vector_doubles(features) == width


def _cpuinfo_flags() -> set[str] | None:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                return set(line.split(":", 1)[1].split())
    except OSError:
        return None
    return None


def test_host_width_agrees_with_the_kernel_cpu_flags():
    """LLVM's view of the host (what numba compiles for) and /proc/cpuinfo give the same width on x86."""
    flags = _cpuinfo_flags()
    if flags is None or "sse2" not in flags:
        pytest.skip("no x86 /proc/cpuinfo flags here")
    expected = 8 if "avx512f" in flags else 4 if "avx" in flags else 2
    assert vector_width.host_vector_doubles() == expected


def test_lane_attributes_name_the_compiled_lanes():
    from gyrolab.kernels.batch_taylor import LANES

    record = vector_width.lane_attributes()
    assert record["batch_lanes"] == LANES == max(4, vector_width.host_vector_doubles())
    assert record["host_vector_doubles"] == vector_width.host_vector_doubles()


def test_numba_cache_key_carries_the_features_the_width_follows_from():
    """numba keys a cached kernel by its target's (triple, CPU, features): a kernel compiled for another vector
    width (another feature set) is not loaded. The width must follow from exactly those features."""
    from numba.core.registry import cpu_target

    triple, cpu, features = cpu_target.target_context.codegen().magic_tuple()
    enabled = {f[1:] for f in features.split(",") if f.startswith("+")}
    if features:  # numba passes the host's features explicitly
        assert vector_width.vector_doubles(enabled) == vector_width.host_vector_doubles()


def test_numba_cpu_features_override_sets_the_width(monkeypatch):
    monkeypatch.setenv("NUMBA_CPU_FEATURES", "+sse2,+avx,+avx2,-avx512f")
    vector_width.host_features.cache_clear()
    try:
        assert vector_width.host_vector_doubles() == 4 and vector_width.batch_lanes() == 4
    finally:
        monkeypatch.delenv("NUMBA_CPU_FEATURES")
        vector_width.host_features.cache_clear()


def test_lane_record_only_for_vectorised_kernels():
    from types import SimpleNamespace

    from gyrolab.batch.runner import path_attributes
    from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor
    from gyrolab.plugins.integrators.scipy_solvers import RK45

    for cls in (Taylor, DOP853Numba):
        assert path_attributes(cls, SimpleNamespace(output="final")) == {
            "batch_path": "batch kernel, vectorised across trajectories", **vector_width.lane_attributes()}
        assert path_attributes(cls, SimpleNamespace(output="indicator")) == {"batch_path": "variational kernel"}
    assert path_attributes(RK45, SimpleNamespace(output="final")) == {"batch_path": "one integrate() call per point"}


def test_batch_dataset_records_lane_width(tmp_path):
    """A vectorised batch's dataset says the lane width it ran with and the CPU's vector width."""
    import xarray as xr

    from gyrolab.batch.sweep import run_batch_sweep

    overrides = ["integrator=taylor", "integrator.tol=1e-8", "time.end=1", "time.n_output=3",
                 "output.euler_angles=false", "initial.r0=1,2"]
    with xr.open_dataset(run_batch_sweep(overrides, tmp_path / "a")) as ds:
        assert ds.attrs["batch_path"] == "batch kernel, vectorised across trajectories"
        assert ds.attrs["batch_lanes"] == vector_width.lane_attributes()["batch_lanes"]
        assert ds.attrs["host_vector_doubles"] == vector_width.host_vector_doubles()
