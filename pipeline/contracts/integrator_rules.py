"""The integrator contract's rules, checked on every call of every ``Integrator.integrate``.

``Integrator.__init_subclass__`` wraps each subclass's own ``integrate`` with :func:`checked`, so the
rules hold for gyrolab's integrators and third-party ones alike without asking anyone to rename a
method (as scipy's ``OdeSolver.step`` owns the checks around a solver's ``_step_impl``).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from gyrolab.errors import GyrolabError, IntegrationError, shorten
from gyrolab.kernels.model import state_size

#: marks a wrapped ``integrate`` so that it is never wrapped twice
_CHECKED = "__gyrolab_checked__"


def checked(integrate: Callable[..., Any]) -> Callable[..., Any]:
    """``integrate`` with the contract's rules checked before and after it (see ``Integrator``'s rules 2–4)."""
    if getattr(integrate, _CHECKED, False):
        return integrate

    @functools.wraps(integrate)
    def wrapper(self: Any, fun: Any, t_out: Any, y0: Any, *args: Any, **kwargs: Any) -> Any:
        name = str(getattr(self, "name", type(self).__name__))
        compiled = args[1] if len(args) > 1 else kwargs.get("compiled")
        finite, increasing = _scans(compiled)
        t_out, y0 = check_inputs(name, t_out, y0, finite, increasing)
        if compiled is not None:
            _check_compiled_size(name, compiled, y0)
        try:
            solution = integrate(self, fun, t_out, y0, *args, **kwargs)
        except GyrolabError:
            raise  # already one sentence (a force's torque named by the scene's guard, a failed step, ...)
        except Exception as exc:  # noqa: BLE001 - a plugin may raise anything; the user gets one sentence
            raise IntegrationError(f"integrator {name!r} raised {type(exc).__name__}: "
                                   f"{shorten(str(exc), 200) or '(no message)'}") from exc
        check_solution(name, solution, t_out, len(y0), finite)
        return solution

    setattr(wrapper, _CHECKED, True)
    return wrapper


def _check_compiled_size(name: str, compiled: Any, y0: np.ndarray) -> None:
    """A compiled model's kernels index the state by its own size, unchecked: a state of another size would make them
    read and write past the arrays (a crash, or silently wrong numbers), so it is refused here."""
    size = state_size(compiled)
    if size is not None and size != len(y0):
        raise IntegrationError(f"integrator {name!r} was given an initial state of {len(y0)} components for a "
                               f"compiled model of {size}; pass the system's own state (System.initial_state())")


def _scans(compiled: Any) -> tuple[Callable[[np.ndarray], bool], Callable[[np.ndarray], bool]]:
    """(all finite, strictly increasing): compiled (``gyrolab.kernels.scans``) for a run with a compiled model, which
    has numba loaded; numpy's otherwise (a scipy run never imports numba for them)."""
    if compiled is None:
        return _finite, _increasing
    # start-up: numba is imported only by a run that has a compiled model
    from gyrolab.kernels import scans

    return scans.all_finite, scans.increasing


def _finite(a: np.ndarray) -> bool:
    return bool(np.isfinite(a).all())


def _increasing(t: np.ndarray) -> bool:
    # a NaN compares false, an inf inside makes a step not positive: one comparison of the shifted times
    return math.isfinite(t[0]) and math.isfinite(t[-1]) and bool(np.greater(t[1:], t[:-1]).all())


def check_inputs(name: str, t_out: Any, y0: Any, finite: Callable[[np.ndarray], bool],
                 increasing: Callable[[np.ndarray], bool]) -> tuple[np.ndarray, np.ndarray]:
    """``t_out`` and ``y0`` as float arrays; IntegrationError unless y0 is finite and 1-D and t_out increases."""
    t_out = np.ascontiguousarray(t_out, dtype=float)
    y0 = np.ascontiguousarray(y0, dtype=float)
    if y0.ndim != 1 or not finite(y0):
        raise IntegrationError(f"integrator {name!r} was given an initial state of shape {y0.shape} "
                               f"({np.count_nonzero(~np.isfinite(y0))} non-finite values); it takes one finite "
                               "1-D state")
    if t_out.ndim != 1 or len(t_out) < 1 or not increasing(t_out):
        raise IntegrationError(f"integrator {name!r} was given output times that are not finite and strictly "
                               f"increasing (shape {t_out.shape}); t_out[0] is the initial time, then increasing")
    return t_out, y0


def check_solution(name: str, solution: Any, t_out: np.ndarray, size: int, finite: Callable[[np.ndarray], bool]) -> None:
    """IntegrationError (one sentence naming the integrator and what is wrong) unless ``solution`` keeps the
    contract: a ``Solution`` with ``t`` of len(t_out), ``y`` of shape (len(t_out), size), all finite, and stats."""
    # import cycle: contracts.integrator imports this module
    from gyrolab.contracts.integrator import IntegratorStats, Solution

    rule = "(gyrolab.contracts.Integrator, rules 2–4)"
    if not isinstance(solution, Solution):
        raise IntegrationError(f"integrator {name!r} returned {type(solution).__name__}, not a "
                               f"gyrolab.contracts.Solution {rule}")
    n = len(t_out)
    t, y = np.asarray(solution.t), np.asarray(solution.y)
    if t.shape != (n,):
        raise IntegrationError(f"integrator {name!r} returned times of shape {t.shape} for {n} output times; "
                               f"Solution.t must be t_out {rule}")
    if y.shape != (n, size):
        raise IntegrationError(f"integrator {name!r} returned states of shape {y.shape}; Solution.y must be "
                               f"{n}×{size} (one state of size {size} per output time) {rule}")
    if not isinstance(solution.stats, IntegratorStats):
        raise IntegrationError(f"integrator {name!r} returned stats of type {type(solution.stats).__name__}; "
                               f"Solution.stats must be an IntegratorStats (evaluations, steps, wall time) {rule}")
    # one vectorised pass (the compiled scan takes C-ordered doubles); the rest runs only on failure
    if not (finite(y) if y.dtype == np.float64 and y.flags.c_contiguous else _finite(y)):
        bad = ~np.isfinite(y)
        first = int(np.argmax(bad.any(axis=1)))
        raise IntegrationError(f"integrator {name!r} returned {int(bad.sum())} non-finite values of {n}×{size} "
                               f"(from t = {t_out[first]:.6g}); an integrator must raise IntegrationError saying "
                               f"when and why instead {rule}")


def unchecked(integrator: Any) -> Callable[..., Any]:
    """The integrator's own ``integrate``, without the engine's checks (bound to it): the contract kit
    (``gyrolab.testing.check_integrator``) judges what the plugin itself returns, not what the engine makes of it."""
    method = type(integrator).integrate
    raw = getattr(method, "__wrapped__", method) if getattr(method, _CHECKED, False) else method
    return raw.__get__(integrator, type(integrator))
