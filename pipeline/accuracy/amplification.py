"""How much a scene amplifies small errors over its span: the growth of a perturbation along the trajectory.

``auto``'s pilot measures the integration error over the first part of the span and extrapolates it. On a regular
motion errors grow like a power of t (a phase drift), which the pilot's fit sees; on a chaotic one they grow like
e^{λt}, and a pilot over a tenth of the span sees at most the start of it (issue 22: asked 1e-6 on
``initial=slow_spin`` over t = 300, the old pilot predicted 1e-6 and the error was 1.46). What governs the growth of
an error committed at time s is the tangent flow from s to the end, so this module measures it directly, over the
whole span: the running maximum of ln|δ(t)| of a tangent vector δ, |δ(0)| = 1 (the fast Lyapunov indicator's
quantity, Froeschlé et al. 1997), at the end of the pilot and at the end of the span. Their difference bounds how
much more an error already present at the end of the pilot can grow by the end (up to the direction of δ, which
aligns with the most expanding one within a few Lyapunov times on a chaotic motion).

Two ways to follow δ, the cheapest that applies:

* the variational equations (``pipeline/kernels/variational.py``: the analytic Jacobian of the fixed-point model with
  torques about the vertical, compiled DOP853) — one compiled call over the span;
* the tangent flow generated from a traced model's equations (``pipeline/kernels/tangent.py``: the orbiting
  gyrostat, plugin torques and systems), compiled DOP853 — one compiled call over the span, ln|δ| sampled at
  ``TANGENT_SAMPLES`` times;
* a shadow pair for a model with neither (no compiled model): the trajectory and a companion started ``SHADOW_OFFSET`` away, integrated
  by the given method chunk by chunk and renormalised after each chunk (Benettin et al. 1980), so the
  companion's separation stays in the linear regime.

The tangent run's own accuracy matters little: a growth factor known to a few per cent is plenty for a bound that
carries a safety factor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.accuracy.calibration import SHADOW_CHUNKS, SHADOW_OFFSET, TANGENT_SAMPLES, TANGENT_TOLERANCE

@dataclass(frozen=True)
class Amplification:
    """The growth of a unit perturbation: ``log_pilot`` = max ln|δ| over [t0, t_pilot], ``log_span`` over the span."""

    log_pilot: float
    log_span: float
    span: float
    how: str

    @property
    def factor(self) -> float:
        """How much more than at the pilot's end a perturbation can be at the end (≥ 1)."""
        return math.exp(min(max(self.log_span - self.log_pilot, 0.0), 700.0))

    @property
    def lyapunov(self) -> float:
        """The finite-time Lyapunov exponent over the span, max ln|δ| / span (→ 0 on regular motions as the span
        grows; the largest Lyapunov exponent on chaotic ones)."""
        return max(self.log_span, 0.0) / self.span

    def horizon(self, accuracy: float, floor: float) -> float:
        """The time over which an error ``floor`` (the precision's round-off on the state) grows to ``accuracy`` at
        the rate ``lyapunov`` (inf when it does not grow)."""
        rate = self.lyapunov
        if rate <= 0 or accuracy <= floor:
            return math.inf if rate <= 0 else 0.0
        return math.log(accuracy / floor) / rate


def amplification(compiled: Any, fun: Any, y0: np.ndarray, t0: float, t_pilot: float, t_end: float,
                  method: Any) -> Amplification:
    """The growth of a unit perturbation over [t0, t_pilot] and [t0, t_end] (``Amplification``).

    ``method`` is an integrator instance for the shadow pair (``auto``'s loose method) when the variational
    equations do not apply to ``compiled``.
    """
    # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
    from gyrolab.kernels import models

    span = float(t_end - t0)
    variational = _variational(compiled, y0, t0, t_pilot, t_end)
    if variational is not None:
        how = ("variational equations (compiled DOP853)" if compiled.model != models.TRACED else
               "tangent flow generated from the equations (compiled DOP853)")
        return Amplification(*variational, span, how)
    return Amplification(*_shadow_pair(method, fun, compiled, y0, t0, t_pilot, t_end), span,
                         f"shadow pair renormalised {SHADOW_CHUNKS} times ({method.name})")


def _variational(compiled: Any, y0: np.ndarray, t0: float, t_pilot: float, t_end: float) -> tuple[float, float] | None:
    if compiled is None:
        return None
    # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
    from gyrolab.kernels import variational

    p = _closed_built_in(compiled)
    if p is None:
        return _generated(compiled, y0, t0, t_pilot, t_end)
    # autonomous: the span from t0 is what counts
    logs = variational.tangent_growths(p, np.asarray(y0, dtype=float), t_pilot - t0, t_end - t0, TANGENT_TOLERANCE)
    return None if not all(np.isfinite(logs)) else logs


def _closed_built_in(compiled: Any) -> np.ndarray | None:
    """The built-in fixed point's parameters for the state (ω, γ) alone, when no torque reads α (then (ω, γ) is a
    closed system and the analytic Jacobian covers it); None otherwise (the generated tangent flow runs)."""
    from gyrolab.kernels import layout

    if compiled.built_in is None or layout.torques_on_horizontal_axes(compiled.built_in):
        return None
    p = np.array(compiled.built_in, dtype=float)
    p[layout.CARRIES_ALPHA] = 0.0
    return p


def _generated(compiled: Any, y0: np.ndarray, t0: float, t_pilot: float, t_end: float) -> tuple[float, float] | None:
    """(max ln|δ| over [t0, t_pilot], over [t0, t_end]) from the traced model's generated tangent flow."""
    from gyrolab.kernels import tangent
    from gyrolab.kernels.model import CompiledModel
    from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba

    augmented = tangent.compiled_megno(compiled)
    params = tangent.megno_params(augmented, compiled.params)[0]
    times = np.unique(np.concatenate([np.linspace(t0, t_end, TANGENT_SAMPLES + 1), [t_pilot]]))
    if times[0] == 0.0:
        times[0] = tangent.START  # (the MEGNO quadrature's 2a/t, unused here, is 0/0 at t = 0)
    method = DOP853Numba(rtol=TANGENT_TOLERANCE, atol=TANGENT_TOLERANCE)
    try:
        z = method.integrate(None, times, tangent.initial_augmented(np.asarray(y0, dtype=float)[None, :])[0], None,
                             CompiledModel(augmented.model, params)).y
    except Exception:  # noqa: BLE001  (a failed tangent run: the shadow pair measures instead)
        return None
    log = np.maximum.accumulate(np.maximum(z[:, 2 * len(y0)], 0.0))
    pilot = log[np.searchsorted(times, t_pilot)]
    return (float(pilot), float(log[-1])) if np.all(np.isfinite(log)) else None


def _shadow_pair(method: Any, fun: Any, compiled: Any, y0: np.ndarray, t0: float, t_pilot: float,
                 t_end: float) -> tuple[float, float]:
    """max ln|δ| at the pilot's end and the span's end from a renormalised companion trajectory."""
    y = np.array(y0, dtype=float)
    scale = max(1.0, float(np.max(np.abs(y))))
    direction = np.linspace(1.0, -1.0, y.size) + 0.5  # generic: no symmetry of the body singles it out
    direction /= np.linalg.norm(direction)
    offset = SHADOW_OFFSET * scale
    edges = np.unique(np.concatenate([np.linspace(t0, t_end, SHADOW_CHUNKS + 1), [t_pilot]]))
    log_norm = best = 0.0
    best_pilot = None
    for a, b in zip(edges[:-1], edges[1:]):
        times = np.array([a, b])
        here = method.integrate(fun, times, y, None, compiled).y[-1]
        there = method.integrate(fun, times, y + offset * direction, None, compiled).y[-1]
        separation = there - here
        size = float(np.linalg.norm(separation))
        if not (np.isfinite(size) and size > 0):
            break
        log_norm += math.log(size / offset)
        best = max(best, log_norm)
        direction, y = separation / size, here
        if b <= t_pilot:
            best_pilot = best
    return (best if best_pilot is None else best_pilot), best
