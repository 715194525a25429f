"""Compiled integrators (numba): DOP853, RK4 and a high-order Taylor method.

They run the system's compiled model (``System.compiled_model()``) entirely in
machine code; Python only slices the output times into chunks, to report
progress between them. Same contract and statistics as the Python plugins.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from gyrolab.contracts.integrator import (
    CompiledModel,
    Integrator,
    IntegratorStats,
    ProgressCallback,
    RightHandSide,
    Solution,
)
from gyrolab.errors import ConfigError, IntegrationError, as_number
from gyrolab.plugins.integrators.tolerances import Tolerances
from gyrolab.plugins.integrators.step_guard import check_step, compiled_rhs

CHUNKS = 50  # progress reports per run at most


def _chunks(n_out: int) -> list[tuple[int, int]]:
    size = max(1, math.ceil((n_out - 1) / CHUNKS))
    return [(i, min(i + size, n_out)) for i in range(1, n_out, size)]


def _outputs(t_out: np.ndarray, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(output times as floats, a working copy of y0, the output array with y0 in its first row)."""
    y = np.array(y0, dtype=float)
    out = np.empty((len(t_out), len(y)))
    out[0] = y
    return np.asarray(t_out, dtype=float), y, out


def steps_per_interval(t_out: np.ndarray, step: float) -> np.ndarray:
    """Fewest equal steps no longer than ``step`` in each output interval (lands on every output time)."""
    return np.maximum(1, np.ceil(np.diff(t_out) / step * (1.0 - 1e-12))).astype(np.int64)


class DOP853Numba(Tolerances, Integrator):
    name = "dop853_numba"
    adaptive = True
    needs_compiled_model = True

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.plugins.compiled import dop853, models

        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        f = np.empty_like(y)
        models.rhs(compiled.model, t_out[0], y, compiled.params, f)
        stats = np.zeros(3, dtype=np.int64)
        stats[0] = 1
        h0 = dop853.initial_step(compiled.model, compiled.params, t_out[0], y, f, t_out[-1], self.max_step,
                                 self.rtol, self.atol, stats)
        state = np.array([t_out[0], h0])
        for first, stop in _chunks(len(t_out)):
            status, _ = dop853.run(compiled.model, compiled.params, t_out, out, first, stop, state, y, f,
                                   t_out[-1], self.rtol, self.atol, self.max_step, stats)
            if status != dop853.OK:
                reason = "the step size fell below the spacing of floating-point numbers" \
                    if status == dop853.TOO_SMALL_STEP else "the state became non-finite"
                raise IntegrationError(f"{self.name} failed near t={state[0]:.6g}: {reason}")
            if progress is not None:
                progress(state[0])
        wall = time.perf_counter() - start
        return Solution(t_out, out, IntegratorStats(nfev=int(stats[0]), n_steps=int(stats[1]),
                                                    n_rejected=int(stats[2]), wall_time=wall))


class RK4Numba(Integrator):
    name = "rk4_numba"
    adaptive = False
    needs_compiled_model = True

    def __init__(self, *, step: float = 0.01) -> None:
        self.step = as_number(step, "integrator.step", positive=True)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.plugins.compiled import rk4

        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        steps = steps_per_interval(t_out, self.step)
        fun = compiled_rhs(compiled)
        for first, stop in _chunks(len(t_out)):
            check_step(self.name, fun, t_out[first - 1], y, float(np.diff(t_out)[first - 1] / steps[first - 1]))
            reached = rk4.run(compiled.model, compiled.params, t_out, steps, y, out, first, stop)
            if reached != stop:
                raise IntegrationError(f"rk4_numba produced a non-finite state before t={t_out[reached]:.6g} "
                                       f"with step {self.step:.3g}; reduce integrator.step")
            if progress is not None:
                progress(t_out[stop - 1])
        n_steps = int(steps.sum())
        return Solution(t_out, out, IntegratorStats(nfev=4 * n_steps, n_steps=n_steps, n_rejected=0,
                                                    wall_time=time.perf_counter() - start))

    def attributes(self) -> dict[str, Any]:
        return {"integrator_step": self.step}


class Taylor(Integrator):
    """Taylor series method (``gyrolab.plugins.compiled.taylor``): order and step from the tolerance.

    ``order=None`` (the default) takes Jorba and Zou's optimal order for ``tol``; an explicit order
    overrides it. Calls into the kernel are sized by wall time (about ``CHUNK_SECONDS`` each, after a
    short first chunk that measures the speed): a run of a few milliseconds is one or two calls,
    a long run still reports progress regularly.
    """

    name = "taylor"
    adaptive = True
    needs_compiled_model = True
    CHUNK_SECONDS = 0.25

    def __init__(self, *, order: int | None = None, tol: float = 1e-16) -> None:
        from gyrolab.plugins.compiled.taylor import MAX_ORDER, MIN_ORDER, order_for

        self.tol = as_number(tol, "integrator.tol", positive=True)
        if order is None:
            order = order_for(self.tol)
        if isinstance(order, bool) or not isinstance(order, int) or not MIN_ORDER <= order <= MAX_ORDER:
            raise ConfigError(f"integrator.order={order!r} must be an integer from {MIN_ORDER} to {MAX_ORDER} "
                              "(or null: chosen from integrator.tol)")
        self.order = order

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.plugins.compiled import taylor

        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        state = np.array([t_out[0]])
        carry = np.zeros_like(y)
        stats = np.zeros(2, dtype=np.int64)
        first, n_out = 1, len(t_out)
        size = max(1, (n_out - 1) // CHUNKS)  # first chunk: 1/CHUNKS of the outputs, to measure the speed
        while first < n_out:
            stop = min(first + size, n_out)
            began = time.perf_counter()
            status, _ = taylor.run(compiled.model, compiled.params, self.order, self.tol, t_out, out, first, stop,
                                   state, y, carry, stats)
            if status != taylor.OK:
                raise IntegrationError(f"taylor produced a non-finite state near t={state[0]:.6g}")
            if progress is not None:
                progress(state[0])
            per_output = (time.perf_counter() - began) / (stop - first)
            size = max(1, int(self.CHUNK_SECONDS / per_output)) if per_output > 0 else n_out
            first = stop
        # one Taylor step costs about as much as `order` right-hand-side evaluations; report the series count
        return Solution(t_out, out, IntegratorStats(nfev=int(stats[0]), n_steps=int(stats[1]), n_rejected=0,
                                                    wall_time=time.perf_counter() - start))

    def attributes(self) -> dict[str, Any]:
        return {"integrator_order": self.order, "integrator_tol": self.tol}


class LiePoisson(Integrator):
    """Structure-preserving splitting of the fixed-point system (see ``gyrolab.plugins.compiled.lie_poisson``)."""

    name = "lie_poisson"
    adaptive = False
    needs_compiled_model = True
    ORDERS = (2, 4, 6)

    def __init__(self, *, step: float = 0.01, order: int = 4) -> None:
        self.step = as_number(step, "integrator.step", positive=True)
        if order not in self.ORDERS:
            raise ConfigError(f"integrator.order={order!r} is not available; valid choices: 2, 4, 6")
        self.order = order

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.plugins.compiled import lie_poisson, models

        if compiled.model != models.FIXED_POINT:
            raise ConfigError("integrator lie_poisson splits the fixed-point Hamiltonian only; valid systems: fixed_point")
        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        steps = steps_per_interval(t_out, self.step)
        w = lie_poisson.weights(self.order)
        fun = compiled_rhs(compiled)
        for first, stop in _chunks(len(t_out)):
            check_step(self.name, fun, t_out[first - 1], y, float(np.diff(t_out)[first - 1] / steps[first - 1]))
            reached = lie_poisson.run(compiled.params, t_out, steps, w, y, out, first, stop)
            if reached != stop:
                raise IntegrationError(f"lie_poisson produced a non-finite state before t={t_out[reached]:.6g}; "
                                       "reduce integrator.step")
            if progress is not None:
                progress(t_out[stop - 1])
        n_steps = int(steps.sum())
        # per step: len(w) Strang stages, each with 2 kicks (one torque evaluation each)
        return Solution(t_out, out, IntegratorStats(nfev=2 * len(w) * n_steps, n_steps=n_steps, n_rejected=0,
                                                    wall_time=time.perf_counter() - start))

    def attributes(self) -> dict[str, Any]:
        return {"integrator_step": self.step, "integrator_order": self.order}
