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

Candidates, fastest first: an expansion regime's analytic series (no
integration at all), when the scene lies in the regime's domain, starts on the
periodic orbit the series describes, and the series' error — measured over one
period against a tight Taylor run and extrapolated linearly in time, as a
phase drift — meets the target; then the compiled Taylor method when the
scene has a compiled model; otherwise scipy's DOP853.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from gyrolab.contracts.integrator import (
    CompiledModel,
    Integrator,
    IntegratorStats,
    ProgressCallback,
    RightHandSide,
    Solution,
)
from gyrolab.errors import ConfigError, GyrolabError, as_number

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
        self.system: Any = None
        self._pilot_steps = 0

    def prepare(self, system: Any) -> None:
        self.system = system

    def _method(self, compiled: CompiledModel | None, tol: float) -> Integrator:
        if compiled is not None:
            from gyrolab.plugins.integrators.compiled_solvers import Taylor

            return Taylor(order=20, tol=tol)
        from gyrolab.plugins.integrators.scipy_solvers import DOP853

        return DOP853(rtol=tol, atol=tol)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        start = time.perf_counter()
        t_out = np.asarray(t_out, dtype=float)
        scale = max(1.0, float(np.max(np.abs(y0))))
        if self.accuracy < FLOOR * scale:
            raise ConfigError(f"accuracy={self.accuracy:g} is below what double precision reaches on this scene "
                              f"(about {FLOOR * scale:.1g} for states of size {scale:.3g}); ask for more")
        series = self._series(fun, t_out, y0, compiled, start)
        if series is not None:
            return series
        span = t_out[-1] - t_out[0]
        pilot_times = t_out[0] + span * self.pilot_fraction * np.linspace(0.0, 1.0, PILOT_POINTS)
        tau, pilot_nfev = min(1e-6, self.accuracy * 1e-2), 0
        for _ in range(3):  # re-centre the pilot near the chosen tolerance: never extrapolate far in τ
            per_tol, growth, nfev, measured = self._pilot(fun, pilot_times, y0, compiled, tau)
            pilot_nfev += nfev
            if not measured:  # no difference above round-off in the pilot: no licence to loosen τ
                chosen = tau
                break
            chosen = min(self.accuracy / (self.safety * per_tol), 1e-6)
            if abs(math.log10(chosen / tau)) <= 1.0:
                break
            tau = chosen
        # Round-off grows with the number of steps (one rounding per step at most, at the state's scale):
        # a target below it cannot be met in double precision, whatever the tolerance.
        steps = self._pilot_steps / self.pilot_fraction
        roundoff = np.finfo(float).eps * scale * steps
        if roundoff > self.accuracy:
            raise ConfigError(f"accuracy={self.accuracy:g} is below the round-off that double precision accumulates "
                              f"on this scene (about {roundoff:.1g} over ~{steps:.0f} steps); ask for at least that")
        method = self._method(compiled, chosen)
        solution = method.integrate(fun, t_out, y0, progress, compiled)
        self.choice = {
            "auto_method": method.name,
            "auto_tolerance": chosen,
            "auto_predicted_error": max(per_tol * chosen, roundoff),
            "auto_error_growth_exponent": growth,
            "auto_pilot_nfev": pilot_nfev,
            **{f"auto_{k.removeprefix('integrator_')}": v for k, v in method.attributes().items()},
        }
        stats = solution.stats
        return Solution(solution.t, solution.y, IntegratorStats(
            nfev=stats.nfev + pilot_nfev, n_steps=stats.n_steps, n_rejected=stats.n_rejected,
            wall_time=time.perf_counter() - start, njev=stats.njev, nlu=stats.nlu))

    def _series(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
                start: float) -> Solution | None:
        """The first regime whose analytic series is predicted to meet the accuracy on this scene, or None."""
        if self.system is None or compiled is None or t_out[0] != 0.0:
            return None
        from gyrolab.engine import registry
        from gyrolab.plugins.integrators.compiled_solvers import Taylor

        span = t_out[-1] - t_out[0]
        candidates = []  # each regime's variants predicted to meet the target, lowest series order first
        for name in registry.names("regime"):
            try:
                base = registry.load("regime", name)()
                if self.system.name in base.systems:
                    ladder = getattr(base, "series_candidates", lambda system, accuracy: [(base, None)])
                    candidates += [(name, r) for r, _ in ladder(self.system, self.accuracy / self.safety)]
            except GyrolabError:
                continue
        for name, regime in candidates:
            try:
                if regime.check_domain(self.system):
                    continue  # outside the domain, or near its edge (warnings): no confidence in the series
                orbit0 = regime.initial_state(self.system)
            except GyrolabError:
                continue
            if np.max(np.abs(orbit0[:6] - y0[:6])) > self.accuracy / (10 * self.safety):
                continue  # the scene does not start on the orbit the series describes
            window = min(span, regime.period(self.system))
            check = np.linspace(0.0, window, 33)
            truth = Taylor(order=20, tol=1e-15).integrate(fun, check, y0, None, compiled)
            measured = float(np.max(np.abs(regime.solution(self.system, check) - truth.y[:, :6])))
            predicted = measured * max(1.0, span / window)
            if self.safety * predicted > self.accuracy:
                continue
            y = regime.solution(self.system, t_out)
            if len(y0) > 6:  # the scene carries the fixed X axis: from the series' Euler angles
                from gyrolab.physics.attitude import frame_from_angles

                angles = regime.euler_angles(self.system, t_out)
                alpha = np.stack([frame_from_angles(a, b, c)[0] for a, b, c in
                                  zip(angles["psi"], angles["theta"], angles["phi"])])
                y = np.concatenate([y, alpha], axis=1)
            self.choice = {"auto_method": f"regime {name}", "auto_predicted_error": predicted,
                           "auto_series_error_one_period": measured, "auto_check_nfev": truth.stats.nfev,
                           **regime.attributes()}
            return Solution(t_out, y, IntegratorStats(nfev=truth.stats.nfev, n_steps=0, n_rejected=0,
                                                      wall_time=time.perf_counter() - start))
        return None

    def _pilot(self, fun: RightHandSide, times: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
               tau: float) -> tuple[float, float, int, bool]:
        """(predicted final error per unit tolerance, growth exponent q, evaluations, whether the pilot measured
        an error above round-off) from runs at τ and τ/100."""
        loose = self._method(compiled, tau).integrate(fun, times, y0, None, compiled)
        tight = self._method(compiled, tau * 1e-2).integrate(fun, times, y0, None, compiled)
        # Envelope of the error: pointwise errors of periodic motions dip through zero.
        envelope = np.maximum.accumulate(np.max(np.abs(loose.y - tight.y), axis=1))
        # differences within a few hundred ulps are round-off, not a measurement of the truncation error
        measured = bool(envelope[-1] > 100 * np.finfo(float).eps * max(1.0, float(np.max(np.abs(y0)))))
        late = slice(PILOT_POINTS // 4, None)
        # A non-symplectic method on a (near-)integrable motion drifts in energy linearly, hence in phase
        # quadratically: assume q = 2 unless the pilot shows faster growth (its early error is a plateau).
        growth = MIN_GROWTH
        if np.all(envelope[late] > 0):
            slope = np.polyfit(np.log(times[late] - times[0]), np.log(envelope[late]), 1)[0]
            growth = float(np.clip(slope, MIN_GROWTH, 4.0))
        per_tol = envelope[-1] / tau * (1.0 / self.pilot_fraction) ** growth
        self._pilot_steps = tight.stats.n_steps
        return per_tol, growth, loose.stats.nfev + tight.stats.nfev, measured

    def attributes(self) -> dict[str, Any]:
        return {"accuracy": self.accuracy, **self.choice}
