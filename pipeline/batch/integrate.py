"""Batch mode: many trajectories of one scene (different initial states or parameters) in one call.

The compiled kernels run in parallel over trajectories (``numba.prange``):
- ``rk4``/``rk4_numba``: fixed step; fixed-point (ω, γ) states go by blocks of trajectories
  stored column-wise, so the arithmetic vectorises across trajectories (7× faster than one
  trajectory per thread); other compiled models one trajectory per thread.
- ``dop853_numba``: adaptive, each trajectory with its own step control (scipy's controller,
  as the single run); fixed-point (ω, γ) states by blocks of lanes vectorised across
  trajectories (``plugins/compiled/batch_dop853.py``), other models one trajectory per thread.
- ``taylor``: adaptive, each trajectory with the single run's order and step rule; fixed-point
  (ω, γ) states by 4 lanes vectorised across trajectories (``plugins/compiled/batch_taylor.py``),
  other models one trajectory per thread.
- ``auto accuracy=ε``: chooses method and tolerance on a few trajectories of the batch with the
  single run's pilot (``auto.py``), the tightest tolerance for all, then runs that method's kernel.
``integrate_batch`` (a scene's batch, ``--batch``) falls back to one run per trajectory with the
scene's own integrator for ``auto`` and any other integrator (correct, not fast).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.contracts import CompiledModel, Integrator
from gyrolab.engine.scene import Scene

FAST_PATH = ("rk4", "rk4_numba")
ADAPTIVE = ("dop853_numba", "taylor", "auto")
#: every integrator ``integrate_arrays`` runs (``gyrolab --batch`` accepts these)
BATCH_INTEGRATORS = FAST_PATH + ADAPTIVE
#: trajectories of a batch on which ``auto`` runs its pilot (the first, the largest state, the most unusual parameters)
AUTO_SAMPLE = 3


@dataclass
class BatchSolution:
    t: np.ndarray  # (n_out,)
    y: np.ndarray  # (trajectories, n_out, state size)
    n_steps: int  # per trajectory (adaptive kernels: the largest number of any trajectory)
    wall_time: float
    #: (trajectories,) True where the trajectory failed (non-finite, or an adaptive step below the
    #: spacing of floating-point numbers; its rows from then on are NaN); only with ``failures="mark"``,
    #: else all False (a failure raised instead)
    failed: np.ndarray | None = None
    #: (trajectories,) accepted steps of each trajectory (adaptive kernels; None for fixed steps)
    steps: np.ndarray | None = None
    #: the integrator settings the kernel ran with (``auto``: its choice, e.g. ``auto_method``, ``auto_tolerance``)
    settings: dict | None = None

    @property
    def trajectory_steps_per_second(self) -> float:
        total = self.y.shape[0] * self.n_steps if self.steps is None else int(self.steps.sum())
        return total / self.wall_time


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
    # auto stays one run per trajectory here: each point of a ``--batch`` sweep records its own choice (and
    # may take a regime's analytic series); integrate_arrays runs auto's batch choice for array batches
    if scene.integrator.name not in BATCH_INTEGRATORS or scene.integrator.name == "auto" or compiled is None:
        if params is not None:
            raise ConfigError(f"per-trajectory params need a compiled batch kernel ({_KERNELS}), "
                              f"not {scene.integrator.name}")
        _require_finite(y0s)
        start = time.perf_counter()
        runs = [scene.integrator.integrate(scene.system.rhs, scene.times, y0, None, compiled) for y0 in y0s]
        out = np.stack([r.y for r in runs])
        _require_finite_out(out)
        return BatchSolution(scene.times, out, max(r.stats.n_steps for r in runs), time.perf_counter() - start)
    return integrate_arrays(compiled, scene.integrator, scene.times, y0s, params)


def integrate_arrays(compiled: CompiledModel, integrator: Integrator, times: np.ndarray, initial_states: np.ndarray,
                     params: np.ndarray | None = None, failures: str = "raise") -> BatchSolution:
    """The batch kernel entry point: no scene, only arrays.

    ``compiled`` is a system's compiled model (its ``params`` are used for every trajectory unless
    ``params``, trajectories × ``compiled.params.size``, gives them per trajectory), ``integrator``
    the integrator plugin (its name and settings choose the kernel), ``times`` the output times and
    ``initial_states`` (trajectories × state size) one row per trajectory. A trajectory that fails
    (becomes non-finite; for adaptive kernels also a step below the spacing of floating-point
    numbers) raises IntegrationError (``failures="raise"``) or is marked in ``BatchSolution.failed``
    (``failures="mark"``: a batch keeps its other trajectories).
    """
    y0s = np.ascontiguousarray(initial_states, dtype=float)
    if y0s.ndim != 2:
        raise ConfigError(f"initial_states has shape {y0s.shape}; it must be (trajectories, state size)")
    _require_finite(y0s)
    if integrator.name not in BATCH_INTEGRATORS:
        raise ConfigError(f"batch kernels run integrator {_KERNELS}, not {integrator.name}")
    if failures not in ("raise", "mark"):
        raise ConfigError(f"failures={failures!r} must be 'raise' or 'mark'")
    P = np.tile(compiled.params, (len(y0s), 1)) if params is None else np.ascontiguousarray(params, dtype=float)
    if P.shape != (len(y0s), compiled.params.size):
        raise ConfigError(f"params has shape {P.shape}; it must be ({len(y0s)}, {compiled.params.size})")
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or not np.all(np.isfinite(times)) or np.any(np.diff(times) <= 0):
        raise ConfigError("times must be a non-empty 1-D array of finite, strictly increasing output times")
    if integrator.name in ADAPTIVE:
        return _adaptive(compiled, integrator, times, y0s, P, failures)
    from gyrolab.plugins.compiled import models, rk4
    from gyrolab.plugins.integrators.compiled_solvers import steps_per_interval

    start = time.perf_counter()
    steps = steps_per_interval(times, integrator.step)
    size = y0s.shape[1]
    out = np.empty((len(y0s), len(times), size))
    if _blockable(compiled, size):
        rk4.run_batch_blocks(P, times, steps, y0s, out)
    else:
        rk4.run_batch(models.form(compiled), P, times, steps, y0s, out)
    failed = ~np.all(np.isfinite(out), axis=(1, 2))
    if failures == "raise":
        _require_finite_out(out)
    return BatchSolution(np.asarray(times), out, int(steps.sum()), time.perf_counter() - start, failed)


_KERNELS = "rk4, rk4_numba, dop853_numba, taylor or auto"
_REASONS = {1: "its step fell below the spacing of floating-point numbers", 2: "it became non-finite"}


def _adaptive(compiled: CompiledModel, integrator: Integrator, times: np.ndarray, y0s: np.ndarray, P: np.ndarray,
              failures: str) -> BatchSolution:
    """The adaptive kernels: dop853_numba, taylor, and auto's choice between them."""
    from gyrolab.plugins.compiled import batch_dop853, batch_taylor, models, plugin_taylor

    start = time.perf_counter()
    settings = None
    if integrator.name == "auto":
        integrator, settings = auto_choice(compiled, integrator, times, y0s, P)
    count, size = y0s.shape
    out = np.empty((count, len(times), size))
    out[:, 0] = y0s
    steps = np.zeros(count, dtype=np.int64)
    status = np.zeros(count, dtype=np.int64)
    if len(times) > 1 and integrator.name == "taylor":
        if not plugin_taylor.ready(compiled, P):
            raise ConfigError("integrator taylor has no Taylor coefficients for this compiled model; "
                              "valid choices for this model: rk4_numba, dop853_numba, auto")
        if _blockable(compiled, size):
            batch_taylor.run_blocks(P, integrator.order, integrator.tol, times, y0s, out, steps, status,
                                    batch_taylor.task_size(count))
        else:
            batch_taylor.run_each(models.form(compiled), P, integrator.order, integrator.tol, times, y0s, out, steps,
                                  status)
    elif len(times) > 1:
        rejected, nfev = np.zeros(count, dtype=np.int64), np.zeros(count, dtype=np.int64)
        args = (times, y0s, out, integrator.rtol, integrator.atol, integrator.max_step, steps, rejected, nfev, status)
        if _blockable(compiled, size):
            batch_dop853.run_blocks(P, *args, batch_dop853.task_size(count))
        else:
            batch_dop853.run_each(models.form(compiled), P, *args)
    failed = status != 0
    if failures == "raise" and failed.any():
        bad = int(np.argmax(failed))
        raise IntegrationError(f"trajectory {bad} of the batch failed with {integrator.name}: "
                               f"{_REASONS.get(int(status[bad]), 'unknown status')}")
    return BatchSolution(times, out, int(steps.max(initial=0)), time.perf_counter() - start, failed, steps,
                         settings or integrator.attributes())


def auto_choice(compiled: CompiledModel, auto: Integrator, times: np.ndarray, y0s: np.ndarray,
                P: np.ndarray) -> tuple[Integrator, dict]:
    """``auto``'s method and tolerance for a batch: its single-run choice on a few trajectories, the tightest.

    The sample is the first trajectory, the one with the largest state and the one whose parameters
    lie farthest from the batch's mean (up to AUTO_SAMPLE distinct ones). Each runs ``auto``'s pilot
    and final run; the batch then runs the chosen method at the smallest tolerance chosen. A trajectory
    harder than every sampled one may miss the accuracy: sample it (pass it first) when you know it.
    """
    from gyrolab.contracts import CompiledModel as Model
    from gyrolab.plugins.integrators.auto import Auto
    from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor
    from gyrolab.plugins.integrators.step_guard import compiled_rhs

    spread = np.abs(P - P.mean(axis=0)).max(axis=1) if len(P) > 1 else np.zeros(1)
    sample = list(dict.fromkeys([0, int(np.argmax(np.abs(y0s).max(axis=1))), int(np.argmax(spread))]))[:AUTO_SAMPLE]
    choices = []
    for j in sample:
        single = Auto(accuracy=auto.accuracy, pilot_fraction=auto.pilot_fraction, safety=auto.safety)
        model = Model(compiled.model, P[j])
        single.integrate(compiled_rhs(model), times, y0s[j], None, model)
        choices.append(single.choice)
    choice = min(choices, key=lambda c: c["auto_tolerance"])
    tol = float(choice["auto_tolerance"])
    method = Taylor(order=choice["auto_order"], tol=tol) if choice["auto_method"] == "taylor" \
        else DOP853Numba(rtol=tol, atol=tol)
    settings = {"accuracy": auto.accuracy, **{k: v.item() if isinstance(v, np.generic) else v for k, v in choice.items()},
                "auto_sampled_trajectories": len(sample)}
    auto.choice = {k: v for k, v in settings.items() if k != "accuracy"}
    return method, settings


def _require_finite(y0s: np.ndarray) -> None:
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial_states contains NaN or inf; every initial state must be finite")


def _require_finite_out(out: np.ndarray) -> None:
    if not np.all(np.isfinite(out)):
        bad = int(np.argmax(~np.all(np.isfinite(out), axis=(1, 2))))
        raise IntegrationError(f"trajectory {bad} of the batch became non-finite; reduce integrator.step")


def _blockable(compiled, size: int) -> bool:
    """The block kernel covers the fixed-point model with state (ω, γ)."""
    from gyrolab.plugins.compiled import models

    return compiled.model == models.FIXED_POINT and size == 6
