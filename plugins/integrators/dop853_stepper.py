"""scipy's DOP853 stepper in numpy, for ``dop853``: the default run need not import ``scipy.integrate``.

That import pulls in ``scipy.optimize`` and ``scipy.special`` (0.36–0.43 CPU s, more than the default run's whole
integration). This is scipy 1.17's ``DOP853`` and ``select_initial_step`` (``scipy/integrate/_ivp``, BSD-3-Clause,
Copyright (c) 2001-2002 Enthought, Inc. 2003, SciPy Developers), the same operations in the same order: the same steps
and numbers bit for bit (tests/plugins/test_dop853_stepper.py runs both side by side), with the part of scipy's
``OdeSolver`` interface that ``ScipySolver.integrate`` uses. The tableau is the compiled DOP853's, scipy's numbers.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from gyrolab.kernels import dop853_tableau as _c

N_STAGES = _c.N_STAGES
A, B, C = _c.A[:N_STAGES, :N_STAGES], _c.B, _c.C[:N_STAGES]
A_EXTRA, C_EXTRA = _c.A[N_STAGES + 1:], _c.C[N_STAGES + 1:]
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10
ERROR_EXPONENT = -1 / 8  # the embedded error estimator is of order 7
TOO_SMALL_STEP = "Required step size is less than spacing between numbers."


def _rms(x: np.ndarray) -> float:
    return np.linalg.norm(x) / x.size ** 0.5


class DOP853:
    """Dormand–Prince 8(5,3) with scipy's step-size controller, error norm, initial step and dense output."""

    n_stages = N_STAGES
    njev = nlu = 0  # (explicit: no Jacobian, no LU decomposition)

    def __init__(self, fun: Callable[[float, np.ndarray], Any], t0: float, y0: np.ndarray, t_bound: float,
                 rtol: float, atol: float, max_step: float = np.inf) -> None:
        self._fun, self.nfev = fun, 0
        self.t, self.t_old, self.t_bound, self.status = t0, None, t_bound, "running"
        self.y = np.asarray(y0).astype(float, copy=False)
        self.direction = np.sign(t_bound - t0) if t_bound != t0 else 1
        # scipy raises an rtol below 100 machine epsilons to it (ScipySolver reports the one used)
        self.rtol, self.atol, self.max_step = max(rtol, 100 * np.finfo(float).eps), atol, max_step
        self.f = self.fun(self.t, self.y)
        self.h_abs = self._initial_step()
        self.K_extended = np.empty((_c.N_STAGES_EXTENDED, self.y.size))
        self.K = self.K_extended[:N_STAGES + 1]

    def fun(self, t: float, y: np.ndarray) -> np.ndarray:
        self.nfev += 1
        return np.asarray(self._fun(t, y), dtype=float)

    def _initial_step(self) -> float:
        """scipy's ``select_initial_step`` for an error estimator of order 7."""
        t0, y0, f0, direction = self.t, self.y, self.f, self.direction
        interval_length = abs(self.t_bound - t0)
        if interval_length == 0.0:
            return 0.0
        scale = self.atol + np.abs(y0) * self.rtol
        d0, d1 = _rms(y0 / scale), _rms(f0 / scale)
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, interval_length)
        f1 = self.fun(t0 + h0 * direction, y0 + h0 * direction * f0)
        d2 = _rms((f1 - f0) / scale) / h0
        h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** (1 / 8)
        return min(100 * h0, h1, interval_length, self.max_step)

    def step(self) -> str | None:
        """One accepted step (scipy's ``OdeSolver.step``): the message of a failure, else None."""
        if self.t == self.t_bound:
            self.t_old, self.status = self.t, "finished"
            return None
        t = self.t
        if not self._step_impl():
            self.status = "failed"
            return TOO_SMALL_STEP
        self.t_old = t
        if self.direction * (self.t - self.t_bound) >= 0:
            self.status = "finished"
        return None

    def _step_impl(self) -> bool:
        t, y, rtol, atol = self.t, self.y, self.rtol, self.atol
        min_step = 10 * np.abs(np.nextafter(t, self.direction * np.inf) - t)
        h_abs = self.max_step if self.h_abs > self.max_step else min_step if self.h_abs < min_step else self.h_abs
        rejected = False
        while True:
            if h_abs < min_step:
                return False
            t_new = t + h_abs * self.direction
            if self.direction * (t_new - self.t_bound) > 0:
                t_new = self.t_bound
            h = t_new - t
            h_abs = np.abs(h)
            y_new, f_new = self._stages(t, y, h)
            scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
            error_norm = self._error_norm(h, scale)
            if error_norm < 1:
                factor = MAX_FACTOR if error_norm == 0 else min(MAX_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
                h_abs *= min(1, factor) if rejected else factor
                break
            h_abs *= max(MIN_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
            rejected = True
        self.h_previous, self.y_old = h, y
        self.t, self.y, self.h_abs, self.f = t_new, y_new, h_abs, f_new
        return True

    def _stages(self, t: float, y: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        """scipy's ``rk_step``: the twelve stages into K, the new state and its derivative (K's last row)."""
        K = self.K
        K[0] = self.f
        for s, (a, c) in enumerate(zip(A[1:], C[1:]), start=1):
            dy = np.dot(K[:s].T, a[:s]) * h
            K[s] = self.fun(t + c * h, y + dy)
        y_new = y + h * np.dot(K[:-1].T, B)
        K[-1] = f_new = self.fun(t + h, y_new)
        return y_new, f_new

    def _error_norm(self, h: float, scale: np.ndarray) -> float:
        err5 = np.dot(self.K.T, _c.E5) / scale
        err3 = np.dot(self.K.T, _c.E3) / scale
        err5_norm_2, err3_norm_2 = np.linalg.norm(err5) ** 2, np.linalg.norm(err3) ** 2
        if err5_norm_2 == 0 and err3_norm_2 == 0:
            return 0.0
        return np.abs(h) * err5_norm_2 / np.sqrt((err5_norm_2 + 0.01 * err3_norm_2) * len(scale))

    def dense_output(self) -> Callable[[np.ndarray], np.ndarray]:
        """The 7th-order interpolant over the last step: times (m,) -> states (n, m). Three more evaluations."""
        K, h, y_old = self.K_extended, self.h_previous, self.y_old
        for s, (a, c) in enumerate(zip(A_EXTRA, C_EXTRA), start=N_STAGES + 1):
            dy = np.dot(K[:s].T, a[:s]) * h
            K[s] = self.fun(self.t_old + c * h, y_old + dy)
        F = np.empty((_c.INTERPOLATOR_POWER, self.y.size))
        delta_y = self.y - y_old
        F[0] = delta_y
        F[1] = h * K[0] - delta_y
        F[2] = 2 * delta_y - h * (self.f + K[0])
        F[3:] = h * np.dot(_c.D, K)
        t_old, step = self.t_old, self.t - self.t_old

        def interpolate(t: np.ndarray) -> np.ndarray:
            x = ((np.asarray(t) - t_old) / step)[:, None]
            y = np.zeros((len(x), y_old.size))
            for i, f in enumerate(reversed(F)):
                y += f
                y *= x if i % 2 == 0 else 1 - x
            return (y + y_old).T

        return interpolate
