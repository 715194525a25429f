"""Classical fourth-order Runge–Kutta with a fixed step: the method of Ismail (2021) and Shaker et al.

The step ``step`` is an upper bound: each interval between output times is split into the fewest equal steps not longer
than ``step``, so the method lands exactly on every output time (the papers tabulate at such times).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from gyrolab.contracts.integrator import (BATCH_KERNEL, TIME_DEPENDENT, VARIATIONAL, VECTOR_LANES, BatchSolution,
                                          CompiledModel, Integrator, IntegratorStats, ProgressCallback, RightHandSide,
                                          Solution, VariationalSettings)
from gyrolab.errors import IntegrationError, as_number
from gyrolab.plugins.integrators.batch_kernels import rk4_batch
from gyrolab.plugins.integrators.refinement import half_step, interval_steps
from gyrolab.plugins.integrators.step_guard import check_step

GUARD_CHECKS = 50  # as often as the compiled methods check (once per output chunk)
PROGRESS_STEPS = 1000  # steps between calls of the progress callback within an output interval (~20 ms)


class RK4(Integrator):
    name = "rk4"
    adaptive = False
    # a batch runs the compiled RK4 kernel (the same method and steps as this one, compiled)
    capabilities = frozenset({TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL})

    def __init__(self, *, step: float = 0.01) -> None:
        self.step = as_number(step, "integrator.step", positive=True)

    def more_accurate(self, factor: float):
        return half_step(self, 4)

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        return rk4_batch(compiled, self.step, times, y0s, params, failures)

    def variational_settings(self) -> VariationalSettings:
        return VariationalSettings(step=self.step)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        start = time.perf_counter()
        y = np.array(y0, dtype=float)
        out = np.empty((len(t_out), len(y)))
        out[0] = y
        with np.errstate(over="ignore", invalid="ignore"):  # a blow-up is reported below, in one sentence
            n_steps = self._march(fun, t_out, y, out, progress)
        stats = IntegratorStats(nfev=4 * n_steps, n_steps=n_steps, n_rejected=0, wall_time=time.perf_counter() - start)
        return Solution(t=np.asarray(t_out, dtype=float), y=out, stats=stats)

    def _march(self, fun: RightHandSide, t_out: np.ndarray, y: np.ndarray, out: np.ndarray,
               progress: ProgressCallback | None) -> int:
        """Fill ``out[1:]``; return the number of steps taken."""
        n_steps = 0
        stride = max(1, math.ceil((len(t_out) - 1) / GUARD_CHECKS))
        steps = interval_steps(self, t_out)
        for i in range(1, len(t_out)):
            t0, interval = t_out[i - 1], t_out[i] - t_out[i - 1]
            m = int(steps[i - 1])
            h = interval / m
            if (i - 1) % stride == 0:  # the guard costs ~9 evaluations: at most GUARD_CHECKS times per run
                check_step(self.name, fun, t0, y, h)
            for j in range(m):
                t = t0 + j * h
                k1 = fun(t, y)
                k2 = fun(t + 0.5 * h, y + (0.5 * h) * k1)
                k3 = fun(t + 0.5 * h, y + (0.5 * h) * k2)
                k4 = fun(t + h, y + h * k3)
                y = y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
                if progress is not None and j % PROGRESS_STEPS == PROGRESS_STEPS - 1:
                    progress(t + h)  # inside a long output interval too (Progress reports by elapsed time)
            n_steps += m
            if not np.all(np.isfinite(y)):
                raise IntegrationError(f"rk4 produced a non-finite state before t={t_out[i]:.6g} with step {h:.3g}; "
                                       "reduce integrator.step")
            out[i] = y
            if progress is not None:
                progress(t_out[i])
        return n_steps

    def attributes(self) -> dict[str, Any]:
        return {"integrator_step": self.step}
