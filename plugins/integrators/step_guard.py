"""A fixed step must resolve the motion: refuse steps that turn the state by more than half a radian.

Without it a fixed-step method can return finite garbage (a splitting stays bounded whatever the step; RK4 is stable up
to h·rate ≈ 2.8 but wrong long before). The rate is estimated from the right-hand side, ‖f(y)‖∞ / ‖y‖∞: for the
rotations of rigid-body motion it is the fastest angular velocity.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gyrolab.errors import IntegrationError

MAX_ANGLE_PER_STEP = 0.5


def check_step(name: str, fun: Callable[[float, np.ndarray], np.ndarray], t: float, y: np.ndarray, step: float) -> None:
    """IntegrationError if ``step`` is too long for the rate of change of ``y`` at ``t``."""
    rate = jacobian_norm(fun, t, y)
    if rate * step > MAX_ANGLE_PER_STEP:
        raise IntegrationError(f"{name}: integrator.step={step:.3g} is too long at t={t:.6g}, where the state turns "
                               f"at {rate:.3g} rad per time unit ({rate * step:.2g} rad per step, limit "
                               f"{MAX_ANGLE_PER_STEP}); use integrator.step ≤ {MAX_ANGLE_PER_STEP / rate:.2g}")


def jacobian_norm(fun: Callable[[float, np.ndarray], np.ndarray], t: float, y: np.ndarray) -> float:
    """‖∂f/∂y‖ by eight power iterations on finite-difference Jacobian-vector products."""
    f0 = fun(t, y)
    eps = 1e-7 * max(1.0, float(np.max(np.abs(y))))
    v = np.linspace(1.0, 2.0, y.size)  # deterministic start with every component present
    v /= np.linalg.norm(v)
    rate = 0.0
    for _ in range(8):
        w = (fun(t, y + eps * v) - f0) / eps
        rate = float(np.linalg.norm(w))
        if rate == 0.0 or not np.isfinite(rate):
            return rate
        v = w / rate
    return rate


def compiled_rhs(compiled) -> Callable[[float, np.ndarray], np.ndarray]:
    """The compiled model's right-hand side as a Python callable (for occasional checks only)."""
    from gyrolab.kernels import models  # start-up: the kernel imports numba

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        out = np.empty_like(y)
        models.evaluate(t, y, compiled.params, out)  # the compiled call the kernels share
        return out

    return fun
