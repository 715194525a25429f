"""The built-in integrators' batch kernels (capability BATCH_KERNEL): many trajectories of one compiled model per call.

They run in parallel over trajectories and vectorise across them, every model's stages generated from its equations
(``models.block_rhs``, ``pipeline/kernels/batch_dop853.py``, ``batch_taylor.py``): RK4 (``rk4``, ``rk4_numba``) with a
fixed step; DOP853 (``dop853_numba``) and Taylor (``taylor``) adaptive, each trajectory with the single run's step
control. Each function is an integrator's ``integrate_batch``: the arrays come validated from
``gyrolab.batch.integrate.integrate_arrays``. Measurements: docs/performance.md, "Batches: adaptive kernels".
"""

from __future__ import annotations

import time

import numpy as np

from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import BATCH_KERNEL, BatchSolution, CompiledModel
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels.model import bind
from gyrolab.plugins.integrators.refinement import steps_per_interval

#: why an adaptive batch kernel stopped a trajectory, by its status code
_REASONS = {1: "its step fell below the spacing of floating-point numbers", 2: "it became non-finite"}


def rk4_batch(compiled: CompiledModel, step: float, times: np.ndarray, y0s: np.ndarray, P: np.ndarray,
              failures: str) -> BatchSolution:
    """Fixed-step RK4 with the fewest equal steps no longer than ``step`` in each output interval."""
    from gyrolab.kernels import models, rk4  # start-up: the kernel imports numba

    start = time.perf_counter()
    P = bind(compiled, P)
    steps = steps_per_interval(times, step)
    out = np.empty((len(y0s), len(times), y0s.shape[1]))
    rk4.run_batch_blocks(models.block_rhs(compiled), P, times, steps, y0s, out)
    failed = ~np.all(np.isfinite(out), axis=(1, 2))
    if failures == "raise":
        require_finite_out(out)
    return BatchSolution(np.asarray(times), out, int(steps.sum()), time.perf_counter() - start, failed)


def taylor_batch(integrator: object, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, P: np.ndarray,
                 failures: str) -> BatchSolution:
    """The Taylor method at ``integrator.order`` and ``integrator.tol`` (``Taylor``'s settings)."""
    from gyrolab.kernels import batch_taylor, taylor_series  # start-up: the kernel imports numba

    P = bind(compiled, P)

    def kernel(out: np.ndarray, steps: np.ndarray, status: np.ndarray) -> None:
        if not taylor_series.ready(compiled, P):  # the registered batch kernels that can run it are the choices
            valid = or_list(integrators_with(BATCH_KERNEL, accept=lambda cls: cls.refusal(compiled) is None))
            raise ConfigError(f"integrator {integrator.name} has no Taylor coefficients for this compiled model; "
                              f"valid choices for this model: {valid}")
        batch_taylor.run_lanes(compiled, P, integrator.order, integrator.tol, times, y0s, out, steps, status)

    return _adaptive(integrator, kernel, times, y0s, failures)


def dop853_batch(integrator: object, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, P: np.ndarray,
                 failures: str) -> BatchSolution:
    """DOP853 with ``integrator.rtol``, ``atol`` and ``max_step`` (scipy's step control)."""
    from gyrolab.kernels import batch_dop853, models  # start-up: the kernel imports numba

    P = bind(compiled, P)

    def kernel(out: np.ndarray, steps: np.ndarray, status: np.ndarray) -> None:
        count = y0s.shape[0]
        rejected, nfev = np.zeros(count, dtype=np.int64), np.zeros(count, dtype=np.int64)
        args = (times, y0s, out, integrator.rtol, integrator.atol, integrator.max_step, steps, rejected, nfev, status)
        batch_dop853.run_blocks(models.block_rhs(compiled), P, *args, batch_dop853.task_size(count))

    return _adaptive(integrator, kernel, times, y0s, failures)


def _adaptive(integrator: object, kernel: object, times: np.ndarray, y0s: np.ndarray, failures: str) -> BatchSolution:
    """An adaptive kernel's common frame: outputs, per-trajectory steps and status, the failure sentence."""
    start = time.perf_counter()
    count, size = y0s.shape
    out = np.empty((count, len(times), size))
    out[:, 0] = y0s
    steps = np.zeros(count, dtype=np.int64)
    status = np.zeros(count, dtype=np.int64)
    if len(times) > 1:
        kernel(out, steps, status)
    failed = status != 0
    if failures == "raise" and failed.any():
        bad = int(np.argmax(failed))
        raise IntegrationError(f"trajectory {bad} of the batch failed with {integrator.name}: "
                               f"{_REASONS.get(int(status[bad]), 'unknown status')}")
    return BatchSolution(times, out, int(steps.max(initial=0)), time.perf_counter() - start, failed, steps,
                         integrator.attributes())


def require_finite_out(out: np.ndarray) -> None:
    """IntegrationError naming the first trajectory of ``out`` (trajectories × times × state) that is not finite."""
    if not np.all(np.isfinite(out)):
        bad = int(np.argmax(~np.all(np.isfinite(out), axis=(1, 2))))
        raise IntegrationError(f"trajectory {bad} of the batch became non-finite; reduce integrator.step")
