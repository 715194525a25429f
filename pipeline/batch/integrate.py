"""Batch mode: many trajectories of one scene (different initial states or parameters) in one call.

An integrator with a batch kernel (capability ``BATCH_KERNEL``) integrates a whole batch in one call of its
``integrate_batch`` (the built-ins' compiled kernels, parallel over trajectories and, with ``VECTOR_LANES``,
vectorised across them: ``gyrolab.plugins.integrators.batch_kernels``); one that chooses its method
(``CHOOSES_METHOD``: ``auto accuracy=ε``) chooses on a few trajectories of the batch and runs that
method's kernel. Any other integrator runs one ``integrate`` call per trajectory (``integrate_points``):
correct, not fast. Nothing here asks for an integrator's name.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from gyrolab.contracts import CompiledModel, Integrator
from gyrolab.contracts.integrator import BATCH_KERNEL, CHOOSES_METHOD, BatchSolution, RightHandSide
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.plugins.integrators.auto import AUTO_SAMPLE  # auto's pilot sample of a batch (importable here, as before)

# BATCH_INTEGRATORS (like FAST_PATH, ADAPTIVE) is computed from the registry's capabilities by __getattr__ below
__all__ = ["AUTO_SAMPLE", "BATCH_INTEGRATORS", "BatchSolution",  # noqa: F822 "auto_choice", "batch_kernel_integrators",
           "integrate_arrays", "integrate_batch", "integrate_points"]


def batch_kernel_integrators() -> list[str]:
    """The registered integrators with a batch kernel (capability BATCH_KERNEL), fixed-step ones first."""
    from gyrolab.contracts.capabilities import integrators_with

    return integrators_with(BATCH_KERNEL)


def __getattr__(name: str) -> object:
    """``BATCH_INTEGRATORS``, ``FAST_PATH``, ``ADAPTIVE``: the old tables of names, now derived from capabilities
    (computed when asked for: listing them loads every registered integrator class)."""
    from gyrolab.contracts.capabilities import integrator_classes

    if name == "BATCH_INTEGRATORS":
        return tuple(batch_kernel_integrators())
    if name in ("FAST_PATH", "ADAPTIVE"):
        adaptive = name == "ADAPTIVE"
        return tuple(n for n, cls in integrator_classes().items()
                     if cls.supports(BATCH_KERNEL) and bool(getattr(cls, "adaptive", False)) == adaptive)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def integrate_batch(scene: Scene, initial_states: np.ndarray, params: np.ndarray | None = None) -> BatchSolution:
    """Integrate ``scene`` from each row of ``initial_states`` over ``scene.times``.

    ``params`` (trajectories × n) optionally replaces the compiled model's
    parameters per trajectory (see ``gyrolab.plugins.compiled.fixed_point.pack``).
    """
    size = scene.system.state_size
    y0s = np.ascontiguousarray(initial_states, dtype=float)
    if y0s.ndim != 2 or y0s.shape[1] != size:
        raise ConfigError(f"initial_states has shape {y0s.shape}; it must be (trajectories, {size})")
    compiled = scene.system.compiled_model()
    integrator = scene.integrator
    # An integrator that chooses its method (auto) chooses once for the batch, on a few of its trajectories
    # (its choose_batch_method: the tightest of their choices), and runs that choice's vectorised kernel over all
    # of them; one run per trajectory in Python cost ~23x the CPU. Only a choice that may leave double precision
    # (auto's extended_precision) keeps one run, and one choice, per trajectory.
    per_point = integrator.supports(CHOOSES_METHOD) and getattr(integrator, "extended_precision", False)
    if not integrator.supports(BATCH_KERNEL) or per_point or compiled is None:
        if params is not None:
            raise ConfigError(f"per-trajectory params need an integrator with a compiled batch kernel that does not "
                              f"choose its method per trajectory ({_kernel_choices(choosers=False)}), "
                              f"not {integrator.name}")
        _require_finite(y0s)
        solution = integrate_points(integrator, lambda j: scene.system.rhs, scene.times, y0s,
                                    scene.compiled, None, failures="raise")
        return solution
    return integrate_arrays(compiled, integrator, scene.times, y0s, params)


def integrate_arrays(compiled: CompiledModel, integrator: Integrator, times: np.ndarray, initial_states: np.ndarray,
                     params: np.ndarray | None = None, failures: str = "raise") -> BatchSolution:
    """The batch kernel entry point: no scene, only arrays.

    ``compiled`` is a system's compiled model (its ``params`` are used for every trajectory unless
    ``params``, trajectories × ``compiled.params.size``, gives them per trajectory), ``integrator``
    an integrator plugin with a batch kernel (capability BATCH_KERNEL: its ``integrate_batch`` and settings
    run the batch), ``times`` the output times and ``initial_states`` (trajectories × state size) one row per
    trajectory. A trajectory that fails (becomes non-finite; for adaptive kernels also a step below the
    spacing of floating-point numbers) raises IntegrationError (``failures="raise"``) or is marked in
    ``BatchSolution.failed`` (``failures="mark"``: a batch keeps its other trajectories). An integrator
    without a batch kernel runs through ``integrate_points`` instead.
    """
    y0s = np.ascontiguousarray(initial_states, dtype=float)
    if y0s.ndim != 2:
        raise ConfigError(f"initial_states has shape {y0s.shape}; it must be (trajectories, state size)")
    _require_finite(y0s)
    if not integrator.supports(BATCH_KERNEL):
        raise ConfigError(f"batch kernels run integrator {_kernel_choices()}, not {integrator.name}")
    if failures not in ("raise", "mark"):
        raise ConfigError(f"failures={failures!r} must be 'raise' or 'mark'")
    P = np.tile(compiled.params, (len(y0s), 1)) if params is None else np.ascontiguousarray(params, dtype=float)
    if P.shape != (len(y0s), compiled.params.size):
        raise ConfigError(f"params has shape {P.shape}; it must be ({len(y0s)}, {compiled.params.size})")
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise ConfigError("times must be a non-empty 1-D array of finite, strictly increasing output times")
    solution = integrator.integrate_batch(compiled, times, y0s, P, failures)
    if failures == "raise" and solution.failed is not None and solution.failed.any():
        # a third-party kernel that only marks its failures: the rule of failures="raise" holds all the same
        raise IntegrationError(f"trajectory {int(np.argmax(solution.failed))} of the batch failed with "
                               f"{integrator.name}")
    return solution


def integrate_points(integrator: Integrator, rhs_of: Callable[[int], RightHandSide], times: np.ndarray,
                     y0s: np.ndarray, compiled: CompiledModel | None, params: np.ndarray | None,
                     failures: str = "raise") -> BatchSolution:
    """A batch for an integrator without a batch kernel: one ``integrate`` call per trajectory, each exactly a
    single run's (its right-hand side ``rhs_of(j)``; the compiled model with ``params[j]`` when the integrator
    uses compiled models). A trajectory whose integration raises IntegrationError (or, against the contract,
    returns non-finite values) fails: ``failures="raise"`` re-raises, ``"mark"`` marks it (NaN after its
    initial state) and goes on."""
    from gyrolab.contracts.integrator import COMPILED_MODEL, PREFERS_COMPILED_MODEL
    from gyrolab.plugins.integrators.batch_kernels import require_finite_out

    start = time.perf_counter()
    times = np.asarray(times, dtype=float)
    count, size = y0s.shape
    uses_model = compiled is not None and (integrator.supports(COMPILED_MODEL)
                                           or integrator.supports(PREFERS_COMPILED_MODEL))
    out = np.full((count, len(times), size), np.nan)
    out[:, 0] = y0s
    failed = np.zeros(count, dtype=bool)
    steps = np.zeros(count, dtype=np.int64)
    for j in range(count):
        model = None
        if uses_model:
            model = compiled if params is None else CompiledModel(compiled.model, np.array(params[j], dtype=float))
        try:
            run = integrator.integrate(rhs_of(j), times, y0s[j], None, model)
        except IntegrationError:
            if failures == "raise":
                raise
            failed[j] = True
            continue
        out[j] = run.y
        steps[j] = run.stats.n_steps
        failed[j] = not np.all(np.isfinite(run.y))
    if failures == "raise":
        require_finite_out(out)
    return BatchSolution(times, out, int(steps.max(initial=0)), time.perf_counter() - start, failed, steps,
                         integrator.attributes())


def auto_choice(compiled: CompiledModel, auto: Integrator, times: np.ndarray, y0s: np.ndarray,
                P: np.ndarray) -> tuple[Integrator, dict]:
    """The method and tolerance an integrator that chooses its method (CHOOSES_METHOD, e.g. ``auto``) runs for a
    batch: its ``choose_batch_method`` (kept under this name for callers of the old module)."""
    return auto.choose_batch_method(compiled, times, y0s, P)


def _kernel_choices(choosers: bool = True) -> str:
    """The integrators with a batch kernel as "a, b or c" (without those that choose their method: ``choosers``)."""
    from gyrolab.contracts.capabilities import integrators_with, or_list

    return or_list(integrators_with(BATCH_KERNEL, accept=None if choosers else lambda c: not c.supports(CHOOSES_METHOD)))


def _require_finite(y0s: np.ndarray) -> None:
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial_states contains NaN or inf; every initial state must be finite")
