"""Batch mode: many trajectories of one scene (different initial states or parameters) in one call.

The fast path runs fixed-step RK4 compiled, in parallel over trajectories
(``numba.prange``): fixed-point (ω, γ) states go by blocks of trajectories
stored column-wise, so the arithmetic vectorises across trajectories (7×
faster than one trajectory per thread); other compiled models one trajectory
per thread. Any other integrator falls back to one run per trajectory with
the scene's own integrator (correct, not fast).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.contracts import CompiledModel, Integrator
from gyrolab.engine.scene import Scene

FAST_PATH = ("rk4", "rk4_numba")


@dataclass
class BatchSolution:
    t: np.ndarray  # (n_out,)
    y: np.ndarray  # (trajectories, n_out, state size)
    n_steps: int  # per trajectory
    wall_time: float
    #: (trajectories,) True where the trajectory became non-finite (its rows from then on are NaN);
    #: only with ``failures="mark"``, else all False (a failure raised instead)
    failed: np.ndarray | None = None

    @property
    def trajectory_steps_per_second(self) -> float:
        return self.y.shape[0] * self.n_steps / self.wall_time


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
    if scene.integrator.name not in FAST_PATH or compiled is None:
        if params is not None:
            raise ConfigError(f"per-trajectory params need integrator rk4 or rk4_numba, not {scene.integrator.name}")
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
    ``initial_states`` (trajectories × state size) one row per trajectory. A trajectory that becomes
    non-finite raises IntegrationError (``failures="raise"``) or is marked in ``BatchSolution.failed``
    (``failures="mark"``: a batch keeps its other trajectories).
    """
    y0s = np.ascontiguousarray(initial_states, dtype=float)
    if y0s.ndim != 2:
        raise ConfigError(f"initial_states has shape {y0s.shape}; it must be (trajectories, state size)")
    _require_finite(y0s)
    if integrator.name not in FAST_PATH:
        raise ConfigError(f"batch kernels run integrator rk4 or rk4_numba, not {integrator.name}")
    from gyrolab.plugins.compiled import rk4
    from gyrolab.plugins.integrators.compiled_solvers import steps_per_interval

    P = np.tile(compiled.params, (len(y0s), 1)) if params is None else np.ascontiguousarray(params, dtype=float)
    if P.shape != (len(y0s), compiled.params.size):
        raise ConfigError(f"params has shape {P.shape}; it must be ({len(y0s)}, {compiled.params.size})")
    start = time.perf_counter()
    steps = steps_per_interval(times, integrator.step)
    size = y0s.shape[1]
    out = np.empty((len(y0s), len(times), size))
    if _blockable(compiled, size):
        rk4.run_batch_blocks(P, times, steps, y0s, out)
    else:
        rk4.run_batch(compiled.model, P, times, steps, y0s, out)
    failed = ~np.all(np.isfinite(out), axis=(1, 2))
    if failures == "raise":
        _require_finite_out(out)
    return BatchSolution(np.asarray(times), out, int(steps.sum()), time.perf_counter() - start, failed)


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
