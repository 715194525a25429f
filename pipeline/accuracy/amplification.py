"""How much a scene amplifies small errors over its span: the growth of a perturbation along the trajectory.

``auto``'s pilot sees at most the start of a chaotic motion's e^{λt} growth (docs/performance.md, "Chaotic scenes").
What governs the growth of an error committed at time s is the tangent flow from s to the end, so this module
measures it over the whole span: the running maximum of ln|δ(t)| of a tangent vector δ, |δ(0)| = 1 (the fast
Lyapunov indicator's quantity, Froeschlé et al. 1997), at the pilot's end and at the span's end. Their difference
bounds how much more an error present at the pilot's end can grow by the end. Two ways to follow δ, the cheapest
that applies:

* the tangent flow generated from the traced model's equations (``pipeline/kernels/tangent.py``), one compiled DOP853
  run over the span, ln|δ| sampled at ``TANGENT_SAMPLES`` times and the pilot's end;
* without a compiled model, a shadow pair started ``SHADOW_OFFSET`` away, integrated by the given method chunk by
  chunk and renormalised after each (Benettin et al. 1980), so the separation stays in the linear regime.

A growth factor known to a few per cent is plenty for a bound that carries a safety factor: the tangent run is loose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.accuracy.calibration import (MAX_GROWTH, SHADOW_CHUNKS, SHADOW_OFFSET, TANGENT_SAMPLES,
                                          TANGENT_TOLERANCE)
from gyrolab.kernels.model import CompiledModel
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba

#: double precision's unit round-off: the random walk of round-off ``auto`` predicts and the one pass bounds
EPS = float(np.finfo(float).eps)
#: the part of the span after which growth beyond a power law is chaos: ``auto``'s default pilot, and the tenth at
#: which a one-pass run measures its growth (``OwnEstimate.log_growth_tenth``)
PILOT_FRACTION = 0.1


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

    def chaotic(self, fraction: float) -> bool:
        """Whether perturbations grow after the pilot (the first ``fraction`` of the span) faster than any power law
        a pilot fits (t^MAX_GROWTH)."""
        return self.factor > (1.0 / fraction) ** MAX_GROWTH

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


def growth_of(own: Any, span: float) -> Amplification:
    """The growth of perturbations a run measured in its one pass (C8: ``OwnEstimate``'s ln|δ| at the first tenth of
    the span and at its end), as ``amplification`` measures it."""
    return Amplification(own.log_growth_tenth, float(own.log_growth[-1]), span,
                         "a tangent vector carried by the chosen run itself (its one pass)")


def amplification(compiled: Any, fun: Any, y0: np.ndarray, t0: float, t_pilot: float, t_end: float,
                  method: Any) -> Amplification:
    """The growth of a unit perturbation over [t0, t_pilot] and [t0, t_end] (``Amplification``).

    ``method`` is an integrator instance for the shadow pair (``auto``'s loose method) when no tangent flow can be
    generated for ``compiled``.
    """
    span = float(t_end - t0)
    growth = None if compiled is None else _generated(compiled, y0, t0, t_pilot, t_end)
    if growth is not None:
        return Amplification(*growth, span, "tangent flow generated from the equations (compiled DOP853)")
    return Amplification(*_shadow_pair(method, fun, compiled, y0, t0, t_pilot, t_end), span,
                         f"shadow pair renormalised {SHADOW_CHUNKS} times ({method.name})")


def _generated(compiled: Any, y0: np.ndarray, t0: float, t_pilot: float, t_end: float) -> tuple[float, float] | None:
    """(max ln|δ| over [t0, t_pilot], over [t0, t_end]) from the traced model's generated tangent flow; None when the
    run fails. The fixed point's tangent vector starts tangent to |γ| = 1 (``tangent.direction``)."""
    # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
    from gyrolab.kernels import layout, tangent

    augmented = tangent.compiled_megno(compiled, quadratures=False)
    params = tangent.megno_params(augmented, compiled.params)[0]
    times = np.unique(np.concatenate([np.linspace(t0, t_end, TANGENT_SAMPLES + 1), [t_pilot]]))
    if times[0] == 0.0:
        times[0] = tangent.START  # (the generated flow starts there; its ℓ' = u·Ju is finite at t = 0 anyway)
    x0 = np.asarray(y0, dtype=float)[None, :tangent.flow_size(compiled)]
    sphere = slice(layout.GAMMA, layout.GAMMA + 3) if compiled.built_in is not None else None
    method = DOP853Numba(rtol=TANGENT_TOLERANCE, atol=TANGENT_TOLERANCE)
    try:
        z = method.integrate(None, times, tangent.initial_augmented(x0, tangent.direction(x0, sphere), False)[0],
                             None, CompiledModel(params)).y
    except Exception:  # noqa: BLE001  (a failed tangent run: the shadow pair measures instead)
        return None
    log = np.maximum.accumulate(np.maximum(z[:, -1], 0.0))
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
