"""Accuracy-targeted choice: the cheapest integrator and setting predicted to reach ``accuracy``.

A tolerance is not an accuracy: how the final error depends on it varies
with the scene. So ``auto`` measures that dependence on the scene itself
with a short pilot: two runs over the first ``pilot_fraction`` of the time
span, at tolerances τ and τ/100, give the error of the τ run at the pilot's
end and at its middle (hence a growth exponent q, error ∝ t^q). The error is
proportional to the tolerance for both candidates (checked in the tests), so
the full span at tolerance τ' is predicted to end with error
err(τ) · (τ'/τ) · (T/T_pilot)^q, with q ≥ 2: a non-symplectic method drifts
in energy linearly on a near-integrable motion, so its phase error grows
quadratically (measured on the reference problem: the error of Taylor at
tol 1e-10 grows ×100 from t = 30 to t = 300). ``auto`` picks τ' to meet ``accuracy``
with a safety factor, runs once, and records the choice and the prediction.

Candidates, fastest first: the compiled Taylor method when the scene has a
compiled model, otherwise scipy's DOP853. (The regimes' analytic series join
here once their error bounds are known.)
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from pipeline.contracts.integrator import (
    CompiledModel,
    Integrator,
    IntegratorStats,
    ProgressCallback,
    RightHandSide,
    Solution,
)
from pipeline.errors import ConfigError, as_number

PILOT_POINTS = 65
MIN_GROWTH = 2.0
FLOOR = 1e-13  # below this, double-precision round-off dominates on unit-scale states


class Auto(Integrator):
    name = "auto"
    adaptive = True
    prefers_compiled_model = True

    def __init__(self, *, accuracy: float | None = None, pilot_fraction: float = 0.1, safety: float = 3.0) -> None:
        if accuracy is None:
            raise ConfigError("integrator=auto needs a target: set accuracy=... (max-norm error of the final state)")
        self.accuracy = as_number(accuracy, "accuracy", positive=True)
        self.pilot_fraction = as_number(pilot_fraction, "integrator.pilot_fraction", positive=True)
        if self.pilot_fraction >= 1:
            raise ConfigError(f"integrator.pilot_fraction={pilot_fraction} must be below 1")
        self.safety = as_number(safety, "integrator.safety", positive=True)
        self.choice: dict[str, Any] = {}

    def _method(self, compiled: CompiledModel | None, tol: float) -> Integrator:
        if compiled is not None:
            from plugins.integrators.compiled_solvers import Taylor

            return Taylor(order=20, tol=tol)
        from plugins.integrators.scipy_solvers import DOP853

        return DOP853(rtol=tol, atol=tol)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        start = time.perf_counter()
        t_out = np.asarray(t_out, dtype=float)
        scale = max(1.0, float(np.max(np.abs(y0))))
        if self.accuracy < FLOOR * scale:
            raise ConfigError(f"accuracy={self.accuracy:g} is below what double precision reaches on this scene "
                              f"(about {FLOOR * scale:.1g} for states of size {scale:.3g}); ask for more")
        span = t_out[-1] - t_out[0]
        pilot_times = t_out[0] + span * self.pilot_fraction * np.linspace(0.0, 1.0, PILOT_POINTS)
        tau, pilot_nfev = min(1e-6, self.accuracy * 1e-2), 0
        for _ in range(3):  # re-centre the pilot near the chosen tolerance: never extrapolate far in τ
            per_tol, growth, nfev = self._pilot(fun, pilot_times, y0, compiled, tau)
            pilot_nfev += nfev
            chosen = min(self.accuracy / (self.safety * per_tol), 1e-6) if per_tol > 0 else tau
            if abs(math.log10(chosen / tau)) <= 1.0:
                break
            tau = chosen
        method = self._method(compiled, chosen)
        solution = method.integrate(fun, t_out, y0, progress, compiled)
        self.choice = {
            "auto_method": method.name,
            "auto_tolerance": chosen,
            "auto_predicted_error": per_tol * chosen,
            "auto_error_growth_exponent": growth,
            "auto_pilot_nfev": pilot_nfev,
            **{f"auto_{k.removeprefix('integrator_')}": v for k, v in method.attributes().items()},
        }
        stats = solution.stats
        return Solution(solution.t, solution.y, IntegratorStats(
            nfev=stats.nfev + pilot_nfev, n_steps=stats.n_steps, n_rejected=stats.n_rejected,
            wall_time=time.perf_counter() - start, njev=stats.njev, nlu=stats.nlu))

    def _pilot(self, fun: RightHandSide, times: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
               tau: float) -> tuple[float, float, int]:
        """(predicted final error per unit tolerance, growth exponent q, evaluations) from runs at τ and τ/100."""
        loose = self._method(compiled, tau).integrate(fun, times, y0, None, compiled)
        tight = self._method(compiled, tau * 1e-2).integrate(fun, times, y0, None, compiled)
        # Envelope of the error: pointwise errors of periodic motions dip through zero.
        envelope = np.maximum.accumulate(np.max(np.abs(loose.y - tight.y), axis=1))
        late = slice(PILOT_POINTS // 4, None)
        # A non-symplectic method on a (near-)integrable motion drifts in energy linearly, hence in phase
        # quadratically: assume q = 2 unless the pilot shows faster growth (its early error is a plateau).
        growth = MIN_GROWTH
        if np.all(envelope[late] > 0):
            slope = np.polyfit(np.log(times[late] - times[0]), np.log(envelope[late]), 1)[0]
            growth = float(np.clip(slope, MIN_GROWTH, 4.0))
        per_tol = envelope[-1] / tau * (1.0 / self.pilot_fraction) ** growth
        return per_tol, growth, loose.stats.nfev + tight.stats.nfev

    def attributes(self) -> dict[str, Any]:
        return {"accuracy": self.accuracy, **self.choice}
