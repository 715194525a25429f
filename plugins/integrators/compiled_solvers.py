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

from gyrolab.contracts.integrator import (BATCH_KERNEL, COMPILED_MODEL, ESTIMATES_ERROR, TIME_DEPENDENT, VARIATIONAL,
                                          VECTOR_LANES, BatchSolution, CompiledModel, Integrator, IntegratorStats,
                                          OwnEstimate, ProgressCallback, RightHandSide, Solution,
                                          VariationalSettings)
from gyrolab.errors import ConfigError, IntegrationError, as_number
from gyrolab.plugins.integrators import batch_kernels
from gyrolab.plugins.integrators.refinement import half_step, interval_steps
from gyrolab.plugins.integrators.rk4 import RK4
from gyrolab.plugins.integrators.tolerances import Tolerances
from gyrolab.plugins.integrators.step_guard import check_step, compiled_rhs

CHUNKS = 50  # progress reports per run at least (when the run has that many output intervals)
PACE = 1.0  # seconds of an adaptive kernel's work between two returns to Python (progress reports), about
#: a fixed-step method's steps per call into its kernel (~0.1–1 s of work). Counted, not timed: where a run is cut
#: between calls must not depend on the machine's speed, since lie_poisson rebuilds its momentum Iω from ω at each
#: call, a change in the last bit (timed chunks made two runs of one config differ at 1e-14)
STEPS_PER_CALL = 2 ** 20


class _Chunks:
    """Output-index ranges ``(first, stop)`` for the compiled kernels.

    Adaptive kernels (no ``steps``) resume exactly where a call ended: their first range is 1/CHUNKS of the outputs,
    later ones follow the measured speed, so a long run reports progress about every ``PACE`` seconds and a short
    one costs only a few calls into the kernel (each call has a fixed cost of some microseconds, which matters for
    millisecond runs). Fixed-step methods (``steps`` per output interval given) take at most 1/CHUNKS of the outputs
    and ``step_budget`` steps at once, at least one interval; an interval alone longer than the budget is advanced
    in pieces (``_interval_in_pieces``).
    """

    step_budget = STEPS_PER_CALL

    def __init__(self, n_out: int, steps: np.ndarray | None = None) -> None:
        self.n_out, self.steps = n_out, steps
        self.size = max(1, math.ceil((n_out - 1) / CHUNKS))

    def __iter__(self):
        first = 1
        while first < self.n_out:
            size = self.size
            if self.steps is not None:
                work = np.cumsum(self.steps[first - 1:first - 1 + size])
                size = max(1, int(np.searchsorted(work, self.step_budget, side="right")))
            stop = min(first + size, self.n_out)
            tic = time.perf_counter()
            yield first, stop
            if self.steps is None:
                self.size = int(max(1, (stop - first) * PACE / max(time.perf_counter() - tic, 1e-6)))
            first = stop


def _interval_in_pieces(advance: Any, t0: float, t1: float, m: int, budget: int,
                        progress: ProgressCallback | None) -> bool:
    """Advance one long output interval of ``m`` equal steps in pieces of at most ``budget`` steps.

    ``advance(tau, sub_steps, j)`` runs the kernel over piece ``j`` of the grid ``tau`` and says
    whether the state stayed finite. The pieces' steps equal the interval's (up to rounding of the
    piece boundaries), so the result is the unsplit one to rounding error; progress is reported
    after each piece.
    """
    marks = np.unique(np.linspace(0, m, math.ceil(m / budget) + 1).round().astype(np.int64))
    tau = t0 + marks * ((t1 - t0) / m)
    tau[-1] = t1
    sub_steps = np.diff(marks)
    for j in range(1, len(tau)):
        if not advance(tau, sub_steps, j):
            return False
        if progress is not None and j < len(tau) - 1:
            progress(tau[j])
    return True


def _outputs(t_out: np.ndarray, y0: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(output times as floats, a working copy of y0, the output array with y0 in its first row)."""
    y = np.array(y0, dtype=float)
    out = np.empty((len(t_out), len(y)))
    out[0] = y
    return np.asarray(t_out, dtype=float), y, out


def _adaptive(advance: Any, t_out: np.ndarray, out: np.ndarray, state: np.ndarray, stats: np.ndarray,
              progress: ProgressCallback | None, failure: Any, start: float) -> Solution:
    """The run since ``start`` (``stats``: the kernel's evaluations, steps and, when it counts them, rejected steps)
    filling ``out[1:]`` by an adaptive kernel ``advance(reached, stop) -> (status, reached)`` called chunk by chunk
    (``_Chunks``), reporting progress after each, or in one call when no one takes progress (each call costs ~5 µs
    of numba's argument typing: 4 % of a 0.13 ms gyrostat run); a non-OK status (the kernels share their codes, 0 is
    OK) raises ``failure(status, t)`` at the time ``state[0]`` it stopped at."""
    reached = 1
    for first, stop in _Chunks(len(t_out)) if progress is not None else [(1, len(t_out))]:
        if reached >= stop:
            continue  # a long step already filled this chunk's outputs
        status, reached = advance(reached, stop)
        if status != 0:
            raise failure(status, state[0])
        if progress is not None:
            progress(state[0])
    return Solution(t_out, out, IntegratorStats(nfev=int(stats[0]), n_steps=int(stats[1]),
                                                n_rejected=int(stats[2]) if len(stats) > 2 else 0,
                                                wall_time=time.perf_counter() - start))


def _fixed_step(method: Any, kernel: Any, t_out: np.ndarray, y0: np.ndarray, compiled: CompiledModel,
                progress: ProgressCallback | None, evaluations: int, step_text: str = "") -> Solution:
    """``method``'s run by a compiled fixed-step ``kernel(grid, steps, y, rows, first, stop) -> reached``
    (``evaluations`` right-hand-side evaluations a step). Progress is reported after each chunk, and after each piece
    of an output interval too long for one chunk; the first output left non-finite is one IntegrationError
    (``step_text`` after its time)."""
    start = time.perf_counter()
    t_out, y, out = _outputs(t_out, y0)
    steps = interval_steps(method, t_out)
    fun, gaps, chunks = compiled_rhs(compiled), np.diff(t_out), _Chunks(len(t_out), steps)
    for first, stop in chunks:
        check_step(method.name, fun, t_out[first - 1], y, float(gaps[first - 1] / steps[first - 1]))
        budget = chunks.step_budget
        if stop - first == 1 and steps[first - 1] > budget:  # one long interval: in pieces
            rows = np.empty((math.ceil(steps[first - 1] / budget) + 1, len(y)))
            finite = _interval_in_pieces(lambda tau, sub, j: kernel(tau, sub, y, rows, j, j + 1) == j + 1,
                                         t_out[first - 1], t_out[first], int(steps[first - 1]), budget, progress)
            out[first] = y
            reached = stop if finite else first
        else:
            reached = kernel(t_out, steps, y, out, first, stop)
        if reached != stop:
            raise IntegrationError(f"{method.name} produced a non-finite state before t={t_out[reached]:.6g}"
                                   f"{step_text}; reduce integrator.step")
        if progress is not None:
            progress(t_out[stop - 1])
    n_steps = int(steps.sum())
    return Solution(t_out, out, IntegratorStats(nfev=evaluations * n_steps, n_steps=n_steps, n_rejected=0,
                                                wall_time=time.perf_counter() - start))


class DOP853Numba(Tolerances, Integrator):
    name = "dop853_numba"
    adaptive = True
    capabilities = frozenset({COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL})
    tolerance_floor = 1e-16  # the compiled controller has no floor of its own; below this it gains nothing

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        return batch_kernels.dop853_batch(self, compiled, times, y0s, params, failures)

    def variational_settings(self) -> VariationalSettings:
        return VariationalSettings(rtol=self.rtol, atol=self.atol, max_step=self.max_step)

    def _failure(self, status: int, t: float) -> IntegrationError:
        from gyrolab.kernels import dop853  # (loaded by then: the run that failed imported it)

        reason = "the step size fell below the spacing of floating-point numbers" \
            if status == dop853.TOO_SMALL_STEP else "the state became non-finite"
        return IntegrationError(f"{self.name} failed near t={t:.6g}: {reason}")

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.kernels import dop853, models  # start-up: the kernel imports numba

        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        f = np.empty_like(y)
        models.evaluate(t_out[0], y, compiled.params, f)
        stats = np.zeros(3, dtype=np.int64)
        stats[0] = 1
        h0 = dop853.initial_step(compiled.params, t_out[0], y, f, t_out[-1], self.max_step,
                                 self.rtol, self.atol, stats)
        state = np.array([t_out[0], h0])
        return _adaptive(lambda reached, stop: dop853.run(compiled.params, t_out, out, reached, stop, state, y, f,
                                                          t_out[-1], self.rtol, self.atol, self.max_step, stats),
                         t_out, out, state, stats, progress, self._failure, start)


class RK4Numba(RK4):
    """``rk4``'s method, settings and batch kernel, its single runs compiled too."""

    name = "rk4_numba"
    capabilities = frozenset({COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL})

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.kernels import rk4  # start-up: the kernel imports numba

        return _fixed_step(self, lambda *run: rk4.run(compiled.params, *run), t_out, y0, compiled, progress, 4,
                           f" with step {self.step:.3g}")


class Taylor(Integrator):
    """Taylor series method (``gyrolab.kernels.taylor``): order and step from the tolerance.

    ``order=None`` (the default) takes Jorba and Zou's optimal order for ``tol``; an explicit order
    overrides it. Calls into the kernel are sized by wall time (``_Chunks``): a run of a few
    milliseconds is one or two calls, a long run still reports progress regularly.
    """

    name = "taylor"
    adaptive = True
    capabilities = frozenset({COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, ESTIMATES_ERROR})
    # one Taylor step costs about as much as `order` right-hand-side evaluations; nfev counts the series
    evaluation_label = "Taylor series evaluations"

    @classmethod
    def refusal(cls, compiled: CompiledModel, system: Any = None) -> str | None:
        from gyrolab.kernels import taylor_series  # start-up: the kernel imports numba

        if taylor_series.ready(compiled):   # (compiles a traced torque's Taylor kernel, once)
            return None
        named = f"system {system.name!r}'s" if system is not None else "this"
        return f"has no Taylor coefficients for {named} compiled model"

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        return batch_kernels.taylor_batch(self, compiled, times, y0s, params, failures)

    def __new__(cls, *args: Any, precision: str = "double", **kwargs: Any) -> Taylor:
        """``precision="double-double"`` makes a ``TaylorDoubleDouble``: the same settings, its own capabilities."""
        if cls is Taylor and precision == DOUBLE_DOUBLE:
            cls = TaylorDoubleDouble
        return super().__new__(cls)

    def __init__(self, *, order: int | None = None, tol: float = 1e-16, precision: str = "double",
                 head: int = 0) -> None:
        """``head`` > 0 (double precision): the series' first ``head`` orders and the state's update in double-double,
        the rest in double (``taylor._steps``): round-off thousands of times below a double run's for ~2–3× its work
        (the error estimate's companion near double precision's floor, and ``auto``'s runs where round-off decides:
        ``gyrolab.accuracy``)."""
        from gyrolab.kernels.taylor import MAX_ORDER, MIN_ORDER, order_for  # start-up: the kernel imports numba

        if not isinstance(precision, str) or precision not in PRECISIONS:
            raise ConfigError(f"integrator.precision={precision!r} is not available; valid choices: "
                              f"{', '.join(PRECISIONS)}")
        self.precision = precision
        self.tol = as_number(tol, "integrator.tol", positive=True)
        if self.precision == DOUBLE_DOUBLE:
            from gyrolab.kernels.taylor_dd import MIN_TOL  # start-up: the kernel imports numba

            if self.tol < MIN_TOL:
                raise ConfigError(f"integrator.tol={tol!r} is below double-double's resolution; with "
                                  f"integrator.precision=double-double it must be at least {MIN_TOL:g}")
        if order is None:  # (a double-double step is series-bound: Jorba & Zou's order, no step overhead)
            order = order_for(self.tol, overhead=0.0) if self.precision == DOUBLE_DOUBLE else order_for(self.tol)
        if isinstance(order, bool) or not isinstance(order, int) or not MIN_ORDER <= order <= MAX_ORDER:
            raise ConfigError(f"integrator.order={order!r} must be an integer from {MIN_ORDER} to {MAX_ORDER} "
                              "(or null: chosen from integrator.tol)")
        self.order = order
        if isinstance(head, bool) or not isinstance(head, int) or not 0 <= head < order:
            raise ConfigError(f"integrator.head={head!r} must be an integer from 0 to integrator.order − 1 = "
                              f"{order - 1} (the series' orders computed in double-double; 0: none)")
        if head and self.precision != DOUBLE:
            raise ConfigError(f"integrator.head={head!r} is for integrator.precision=double (in {self.precision} "
                              "the whole series is)")
        self.head = head

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None,
                  estimate: bool = False, growth_only: bool = False, resume: OwnEstimate | None = None) -> Solution:
        """The run; ``estimate`` (C8): its global error estimated in the same pass (``taylor.run_measured``), and the
        growth of perturbations measured; ``growth_only``: the growth alone (``OwnEstimate.error`` None). ``resume``:
        the measurement of a run that ended at y0, whose error, tangent vector and growth this run carries on (and
        the compensation of its state when y0 is that state, ``OwnEstimate.end``: the low part a double-double head
        carries)."""
        from gyrolab.kernels import layout, taylor, taylor_series, tangent  # start-up: the kernel imports numba

        start = time.perf_counter()
        taylor_series.ready(compiled)  # a traced model's series kernel, compiled on first need (once: then a test)
        if self.head:
            _ready_for_double_double(compiled)  # (the head's series)
        t_out, y, out = _outputs(t_out, y0)
        state = np.array([t_out[0]])
        carry = np.zeros(len(y))  # (np.zeros_like costs 2 µs more, per pilot run)
        stats = np.zeros(2, dtype=np.int64)
        # one Taylor step costs about as much as `order` right-hand-side evaluations; the series count is reported
        if not (estimate or growth_only):
            return _adaptive(lambda reached, stop: taylor.run(compiled.params, self.order, self.tol, t_out, out,
                                                              reached, stop, state, y, carry, stats, self.head),
                             t_out, out, state, stats, progress, _taylor_failure, start)
        error = np.zeros((len(t_out) if estimate else 0, len(y)))
        flow = tangent.flow_size(compiled)
        if resume is None:
            e, log_growth = np.zeros(len(y) if estimate else 0), np.zeros(len(t_out))
            growth = np.array([0.0, 0.0, t_out[0] + 0.1 * (t_out[-1] - t_out[0]), 0.0, 0.0])
            # the tangent vector starts as the chaos measure's does (``tangent.direction`` over the components its
            # flow follows, ``tangent.flow_size``: on the fixed point tangent to |γ| = 1; zeros beyond)
            u = np.zeros(len(y))
            u[:flow] = tangent.direction(y[:flow], slice(layout.GAMMA, layout.GAMMA + 3) if compiled.built_in
                                         is not None else None)[0]
        else:  # (the growth's mark where it resumes; from the state the run ended in, its compensation too)
            e, u, (log, top, walk) = np.array(resume.end[0]), np.array(resume.end[1]), resume.end[2]
            if np.array_equal(y, resume.end[3]):
                carry = np.array(resume.end[4])
            e = e if estimate and e.size else np.zeros(len(y) if estimate else 0)
            growth, log_growth = np.array([log, top, t_out[0], top, walk]), np.full(len(t_out), top)
            if estimate:
                error[0] = e  # (at t_out[0]: the start's own error)
        solution = _adaptive(lambda reached, stop: taylor.run_measured(
            compiled.params, self.order, self.tol, t_out, out, reached, stop, state, y, carry, stats, e, u, error,
            growth, log_growth, flow, self.head), t_out, out, state, stats, progress, _taylor_failure, start)
        m = min(taylor.TANGENT_ORDER, self.order)  # (the error's series; the tangent vector's may be shorter)
        solution.estimate = OwnEstimate(error if estimate else None, log_growth, float(growth[3]), int(stats[1]), (
            f"one pass: each step's truncation error (the series' next {taylor.EXTRA_ORDERS} terms) carried along "
            f"the run by the linearised equations (their Taylor series to order {m} on the run's own steps)"),
            (e, u, (growth[0], growth[1], growth[4]), y, carry), float(growth[4]) if self.head else None)
        return solution

    #: below this tol the double-precision kernel gains nothing (round-off); with a double-double head, below the
    #: second (its round-off ~10⁻⁴ of a double run's a step: benchmarks/companion_head.py)
    TOLERANCE_FLOOR, HEAD_TOLERANCE_FLOOR = 1e-16, 1e-20

    def more_accurate(self, factor: float):
        tol = self.tol / factor
        if tol < (self.HEAD_TOLERANCE_FLOOR if self.head else self.TOLERANCE_FLOOR):
            return None
        head = f", its first {self.head} orders in double-double" if self.head else ""
        return (Taylor(order=self.order, tol=tol, head=self.head), 1.0,
                f"taylor at tol {tol:.3g} ({factor:g}× tighter), same order{head}")

    def climbed(self, factor: float):
        """Rule 11: the double-double rung, ``factor`` times more accurate (None: already on it): at the same order,
        where the error is proportional to the tolerance. (At Jorba & Zou's order for the tighter tolerance, higher,
        the error per unit tolerance is larger: a chaotic top at tol 6.5e-15 in double-double, order 18 instead of
        13, ended 1.7e-10 from real128 instead of 1.7e-11, as far as the double run it measured at tol 6.5e-13,
        whose error it then measured 26× too small: docs/integrators.md, "A companion at the run's order".)"""
        from gyrolab.kernels.taylor_dd import MIN_TOL  # start-up: the kernel imports numba

        tol = max(self.tol / factor, MIN_TOL)
        return None if self.precision != DOUBLE else (Taylor(order=self.order, tol=tol, precision=DOUBLE_DOUBLE), 1.0, (
            f"taylor double-double at tol {tol:.3g}, same order: double precision's floor reached"))

    def attributes(self) -> dict[str, Any]:
        head = {"integrator_double_double_head": self.head} if self.head else {}
        return {"integrator_order": self.order, "integrator_tol": self.tol, "integrator_precision": self.precision,
                **head}


#: ``Taylor``'s arithmetic: ``integrator.precision``
DOUBLE, DOUBLE_DOUBLE = "double", "double-double"
PRECISIONS = (DOUBLE, DOUBLE_DOUBLE)


class TaylorDoubleDouble(Taylor):
    """``Taylor(precision="double-double")`` (``integrator=taylor integrator.precision=double-double``): the Taylor
    method in double-double arithmetic (``gyrolab.kernels.taylor_dd``, ≈ 32 digits), same settings,
    order rule, chunks and progress as ``Taylor``. Capabilities: the compiled model only — every traced model
    whose equations are rational in the state (``series_dd``: the fixed point, the orbiting gyrostat, a polynomial
    plugin torque; a transcendental function of the state is refused, naming it),
    time-dependent ones too; no batch kernel (``--batch`` runs one ``integrate`` per point, each exactly a single
    run)."""

    capabilities = frozenset({COMPILED_MODEL, TIME_DEPENDENT})

    @classmethod
    def refusal(cls, compiled: CompiledModel, system: Any = None) -> str | None:
        return _double_double_refusal_clause(compiled, system)

    integrate_batch = Integrator.integrate_batch  # no batch kernel

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        """``Taylor.integrate`` in double-double (``gyrolab.kernels.taylor_dd``): the state carried in
        double-double between steps and between the chunks (``_Chunks``, as the double path), the outputs rounded
        to double. The initial state is a double, hence exact."""
        from gyrolab.kernels import taylor_dd  # start-up: the kernel imports numba

        _ready_for_double_double(compiled)
        start = time.perf_counter()
        t_out, y, out = _outputs(t_out, y0)
        low = np.zeros(len(y))  # the state's low parts
        no_low = np.empty((0, len(y)))  # outputs are stored as doubles: the kernel's low-part array is not wanted
        state = np.array([t_out[0]])
        stats = np.zeros(2, dtype=np.int64)
        return _adaptive(lambda reached, stop: taylor_dd.run(compiled.params, self.order, self.tol, t_out, out, no_low,
                                                             reached, stop, state, y, low, stats),
                         t_out, out, state, stats, progress, _taylor_failure, start)

    def more_accurate(self, factor: float):
        from gyrolab.kernels.taylor_dd import MIN_TOL  # start-up: the kernel imports numba

        tol = self.tol / factor
        if tol < MIN_TOL:
            return None
        return (Taylor(order=self.order, tol=tol, precision=DOUBLE_DOUBLE), 1.0,
                f"taylor double-double at tol {tol:.3g} ({factor:g}× tighter), same order")


def _double_double_refusal_clause(compiled: CompiledModel, system: Any = None) -> str | None:
    """None when double-double can run ``compiled`` (compiling a traced model's series on first need), else why."""
    from gyrolab.kernels import series_dd  # start-up: the kernel imports numba
    from gyrolab.kernels.expression import NotCompilable

    try:
        series_dd.ready(compiled)
    except NotCompilable as exc:
        named = f"system {system.name!r}" if system is not None else "this model"
        plugins = [f"{f.name!r}" for f in getattr(system, "forces", []) if f.compiled_terms() is None]
        if plugins:
            named += f" with force {', '.join(plugins)}"
        return f"in double-double precision cannot run {named}: {exc}"
    except ValueError as exc:
        return f"in double-double precision cannot run this model: {exc}"
    return None


def _ready_for_double_double(compiled: CompiledModel) -> None:
    clause = _double_double_refusal_clause(compiled)
    if clause is not None:
        raise ConfigError(f"integrator 'taylor' {clause}")


def taylor_samples(compiled: CompiledModel, tol: float, t_out: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """The states at ``t_out`` of the Taylor method at ``tol`` (Jorba & Zou's order), in one call into the kernel:
    for runs over a few periods inside another method (``auto``'s screen), which need neither progress nor
    statistics (``Taylor.integrate``'s chunks and records cost ~10 µs more, a tenth of the screen)."""
    from gyrolab.kernels import taylor, taylor_series  # start-up: the kernel imports numba

    taylor_series.ready(compiled)  # a traced model's series kernel (a scene carrying α is one)
    t_out, y, out = _outputs(t_out, y0)
    state = np.array([t_out[0]])
    # auto's screen: Jorba & Zou's order (a short bare run near one period; its order moves no calibration)
    status, _ = taylor.run(compiled.params, taylor.order_for(tol, overhead=0.0), tol, t_out, out, 1,
                           len(t_out), state, y, np.zeros(len(y)), np.zeros(2, dtype=np.int64))
    if status != taylor.OK:
        raise _taylor_failure(status, state[0])
    return out


def _taylor_failure(status: int, t: float) -> IntegrationError:
    """The one-sentence error for a Taylor kernel's non-OK ``status``, stopped at time ``t``."""
    from gyrolab.kernels import taylor  # start-up: the kernel imports numba

    if status == taylor.TOO_SMALL_STEP:
        return IntegrationError(f"taylor's step fell below the spacing of floating-point numbers near t={t:.6g} "
                                "(a singularity of the solution, or integrator.tol too small)")
    return IntegrationError(f"taylor produced a non-finite state near t={t:.6g}")


class LiePoisson(Integrator):
    """Structure-preserving splitting of the fixed-point system (see ``gyrolab.kernels.lie_poisson``)."""

    name = "lie_poisson"
    adaptive = False
    capabilities = frozenset({COMPILED_MODEL})
    evaluation_label = "exact sub-flow evaluations"
    ORDERS = (2, 4, 6)

    @classmethod
    def refusal(cls, compiled: CompiledModel, system: Any = None) -> str | None:
        if compiled.built_in is not None:
            return None
        traced = ", ".join(f.name for f in system.forces if f.compiled_terms() is None) if system is not None else ""
        return ("evaluates the built-in torque forms only, and "
                + (f"force {traced} is a compiled plugin torque" if traced else "this compiled model is not one of them"))

    def __init__(self, *, step: float = 0.01, order: int = 4) -> None:
        self.step = as_number(step, "integrator.step", positive=True)
        if order not in self.ORDERS:  # (more_accurate below halves the step at the same order)
            raise ConfigError(f"integrator.order={order!r} is not available; valid choices: 2, 4, 6")
        self.order = order

    def more_accurate(self, factor: float):
        return half_step(self, self.order, order=self.order)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.kernels import lie_poisson  # start-up: the kernel imports numba

        if compiled.built_in is None:
            raise ConfigError("integrator lie_poisson splits the fixed-point Hamiltonian with the built-in torque "
                              "forms only; valid systems: fixed_point with uniform_gravity, newtonian, magnetic")
        w = lie_poisson.weights(self.order)
        # per step: len(w) Strang stages, each with 2 kicks (one torque evaluation each)
        return _fixed_step(self, lambda grid, n, *run: lie_poisson.run(compiled.built_in, grid, n, w, *run), t_out, y0,
                           compiled, progress, 2 * len(w))

    def attributes(self) -> dict[str, Any]:
        return {"integrator_step": self.step, "integrator_order": self.order}
