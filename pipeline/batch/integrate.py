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
from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import (BATCH_KERNEL, CHOOSES_METHOD, COMPILED_MODEL, PREFERS_COMPILED_MODEL,
                                          BatchSolution, RightHandSide)
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.plugins.integrators.batch_kernels import require_finite_out


def integrate_batch(scene: Scene, initial_states: np.ndarray, params: np.ndarray | None = None) -> BatchSolution:
    """Integrate ``scene`` from each row of ``initial_states`` over ``scene.times``.

    With an integrator that has a compiled batch kernel (``rk4``, ``rk4_numba``, ``dop853_numba``,
    ``taylor``), the trajectories run together in one call; otherwise (and with ``auto``, which
    chooses its method per trajectory) one integration per row.

    Parameters
    ----------
    scene : Scene
        The scene (from `compose_scene`): its system, integrator and output times.
    initial_states : numpy.ndarray
        Shape (trajectories, state size): one initial state per row, finite.
    params : numpy.ndarray, optional
        Shape (trajectories, n): replaces the compiled model's parameters per trajectory (see
        ``gyrolab.kernels.fixed_point.pack``); only with a compiled batch kernel.

    Returns
    -------
    BatchSolution
        ``t`` (n_out,), ``y`` (trajectories, n_out, state size), step counts and wall time.

    Raises
    ------
    gyrolab.errors.ConfigError
        ``initial_states`` of the wrong shape or not finite, or ``params`` with an integrator
        that has no compiled batch kernel.
    """
    size = scene.system.state_size
    y0s = np.ascontiguousarray(initial_states, dtype=float)
    if y0s.ndim != 2 or y0s.shape[1] != size:
        raise ConfigError(f"initial_states has shape {y0s.shape}; it must be (trajectories, {size})")
    compiled = scene.compiled_model  # (traced once per scene: ~5 ms a batch call when it was traced anew)
    integrator = scene.integrator
    # An integrator that chooses its method (auto) chooses once for the batch (choose_batch_method) and runs that
    # choice's vectorised kernel over all trajectories, unless asked to be free to leave double precision per
    # trajectory (auto's integrator.extended_precision=true): then one run, and one choice, per trajectory.
    per_point = integrator.supports(CHOOSES_METHOD) and getattr(integrator, "per_trajectory", False)
    if not integrator.supports(BATCH_KERNEL) or per_point or compiled is None:
        if params is not None:
            raise ConfigError(f"per-trajectory params need an integrator with a compiled batch kernel that does not "
                              f"choose its method per trajectory ({_kernel_choices(choosers=False)}), "
                              f"not {integrator.name}")
        _require_finite(y0s)
        return integrate_points(integrator, lambda j: scene.system.rhs, scene.times, y0s, scene.compiled, None,
                                failures="raise")
    return integrate_arrays(compiled, integrator, scene.times, y0s, params)


def integrate_arrays(compiled: CompiledModel, integrator: Integrator, times: np.ndarray, initial_states: np.ndarray,
                     params: np.ndarray | None = None, failures: str = "raise") -> BatchSolution:
    """Integrate many trajectories on an integrator's batch kernel: no scene, only arrays.

    Parameters
    ----------
    compiled : CompiledModel
        A system's compiled model; its ``params`` are used for every trajectory unless ``params`` is given.
    integrator : Integrator
        An integrator plugin with a batch kernel (capability ``BATCH_KERNEL``: its ``integrate_batch`` and
        settings run the batch). An integrator without one runs through :func:`integrate_points` instead.
    times : numpy.ndarray
        The output times, 1-D, finite and strictly increasing.
    initial_states : numpy.ndarray
        One row per trajectory, shape (trajectories, state size).
    params : numpy.ndarray, optional
        Per-trajectory parameters, shape (trajectories, ``compiled.params.size``).
    failures : {"raise", "mark"}
        What a failed trajectory (non-finite, or for adaptive kernels a step below the spacing of
        floating-point numbers) does: raise ``IntegrationError``, or be marked in ``BatchSolution.failed``
        while the batch keeps its other trajectories.

    Returns
    -------
    BatchSolution
        The states at ``times`` for every trajectory, with the steps taken and the failed mask.

    Raises
    ------
    gyrolab.errors.ConfigError
        On arrays of the wrong shape, non-finite initial states, or an integrator without a batch kernel.
    gyrolab.errors.IntegrationError
        When a trajectory fails and ``failures="raise"``.
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
    """Integrate many trajectories with an integrator that has no batch kernel, one ``integrate`` call each.

    Each trajectory is exactly a single run's, so a third-party integrator joins a batch unchanged.

    Parameters
    ----------
    integrator : Integrator
        Any integrator plugin.
    rhs_of : callable
        ``rhs_of(j)`` is the right-hand side of trajectory ``j``.
    times : numpy.ndarray
        The output times, 1-D and strictly increasing.
    y0s : numpy.ndarray
        Initial states, shape (trajectories, state size).
    compiled : CompiledModel or None
        The system's compiled model, used when the integrator integrates compiled models.
    params : numpy.ndarray or None
        Per-trajectory compiled parameters (``params[j]`` for trajectory ``j``); None: the model's own.
    failures : {"raise", "mark"}
        A trajectory whose integration raises ``IntegrationError`` (or, against the contract, returns
        non-finite values) re-raises, or is marked (NaN after its initial state) while the others go on.

    Returns
    -------
    BatchSolution
        The states at ``times`` for every trajectory, the steps taken and the failed mask.
    """

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
            model = compiled if params is None else CompiledModel(np.array(params[j], dtype=float))
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


def _kernel_choices(choosers: bool = True) -> str:
    """The integrators with a batch kernel as "a, b or c" (without those that choose their method: ``choosers``)."""

    return or_list(integrators_with(BATCH_KERNEL, accept=None if choosers else lambda c: not c.supports(CHOOSES_METHOD)))


def _require_finite(y0s: np.ndarray) -> None:
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial_states contains NaN or inf; every initial state must be finite")
