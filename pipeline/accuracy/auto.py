"""Accuracy-targeted choice: the cheapest integrator and setting predicted to reach ``accuracy``.

A tolerance is not an accuracy (on the reference scene the Taylor method's final error is 24 to 470 times its
tolerance, depending on the order), so ``auto`` measures the dependence on the scene itself: a pilot over the first
``pilot_fraction`` of the span, two runs at τ and τ_t ≤ τ/10 with one order, gives the error at τ and its growth
exponent q (error ∝ t^q, q ≥ 2: a non-symplectic method's phase error grows at least quadratically). At a fixed order
the error is proportional to the tolerance, so the span at τ' is predicted to end with err(τ) · (τ'/τ) ·
(T/T_pilot)^q, recorded times ``CALIBRATION`` (``calibration.TABLE``). The pilot's tight run is the start of the
trajectory, and the final run continues from its end; a later pilot round reuses the previous round's τ run as its
tight run.

Candidates, fastest first: a regime's analytic series (the scene starts on its orbit and the series' measured error
meets the target), the compiled Taylor method when the scene has a compiled model, else DOP853. Where double
precision's round-off (a random walk, eps·|y|·√steps, amplified on a chaotic scene) is above the target, ``auto``
climbs to double-double unless ``extended_precision`` is false, and refuses only what the highest rung allowed cannot
reach. The measurements behind each step: docs/performance.md, "integrator=auto accuracy=ε" and "Chaotic scenes".
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import replace
from typing import Any

import numpy as np

from gyrolab.accuracy.amplification import EPS, PILOT_FRACTION, Amplification, amplification, growth_of
from gyrolab.accuracy.calibration import (AUTO_SAMPLE, CALIBRATION, CHAOS_MARGIN, DOUBLE_DOUBLE_BELOW,
                                          DOUBLE_DOUBLE_FLOOR, ESTIMATE_SLACK, FIRST_RATIO, FLOOR, HEAD_ORDERS,
                                          MAX_GROWTH, MAX_TOLERANCE, MIN_GROWTH, MIN_PILOT_STEPS, MIN_TOLERANCE,
                                          MISS_MARGIN, PILOT_POINTS, RECENTRE, SCREEN_POINTS, SCREEN_TOLERANCE,
                                          SHADOW_TOLERANCE, TIGHT_RATIO, TIGHTER, UNMEASURED_PER_TOL)
from gyrolab.contracts.integrator import (BATCH_KERNEL, CHOOSES_METHOD, ESTIMATES_ERROR, PRECISIONS,
                                          PREFERS_COMPILED_MODEL, TIME_DEPENDENT, VECTOR_LANES, BatchSolution, Choice,
                                          CompiledModel, Integrator, IntegratorStats, OwnEstimate, ProgressCallback,
                                          RightHandSide, Solution)
from gyrolab.errors import ConfigError, GyrolabError, as_number
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor, TaylorDoubleDouble, taylor_samples
from gyrolab.plugins.integrators.step_guard import compiled_rhs

#: what ``auto_predicted_error`` is, stored beside it in every run
PREDICTION_MEANING = ("an upper estimate of the max-norm error of the stored state at every output time (model units): "
                      "the pilot's error extrapolated over the span, raised by the measured growth of perturbations, "
                      "times a calibration factor, plus the round-off of the precision that ran; checked at every "
                      "output time by output.error_estimate (gyrolab.accuracy.promise), a prediction only without it")
#: the unit round-off of double-double arithmetic (a 106-bit significand), for auto's extended-precision choice
DOUBLE_DOUBLE_EPS = 2.0 ** -104
_PILOT_GRID = np.linspace(0.0, 1.0, PILOT_POINTS)


class Auto(Integrator):
    name = "auto"
    adaptive = True
    # a batch runs its choice's kernel (Taylor or DOP853, both vectorised across trajectories)
    capabilities = frozenset({PREFERS_COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, CHOOSES_METHOD})
    evaluation_label = "pilot and chosen method's evaluations"

    def __init__(self, *, accuracy: float | None = None, pilot_fraction: float = PILOT_FRACTION, safety: float = 1.0,
                 extended_precision: bool | None = None) -> None:
        if accuracy is None:
            raise ConfigError("integrator=auto needs a target: set accuracy=... (max-norm error of the stored states)")
        self.accuracy = as_number(accuracy, "accuracy", positive=True)
        self.pilot_fraction = as_number(pilot_fraction, "integrator.pilot_fraction", positive=True)
        if self.pilot_fraction >= 1:
            raise ConfigError(f"integrator.pilot_fraction={pilot_fraction} must be below 1")
        self.safety = as_number(safety, "integrator.safety", positive=True)
        if extended_precision is not None and not isinstance(extended_precision, (bool, np.bool_)):
            raise ConfigError(f"integrator.extended_precision={extended_precision!r} must be true, false or null")
        #: a target double precision cannot reach is met in double-double instead of refused, unless false
        self.extended_precision = extended_precision is not False
        #: true: a batch runs one choice per trajectory, each free to climb (by default it chooses once, in double
        #: precision, for its vectorised kernel: one run per trajectory in Python costs ~23× the CPU)
        self.per_trajectory = extended_precision is True
        self.system: Any = None  # the scene's system (``prepare``): its regimes' series are candidates

    def prepare(self, system: Any) -> None:
        self.system = system
        # the floor of integrate(), checked when the scene is built: a refusal before the run directory exists
        self._check_floor(max(1.0, *map(abs, system.initial_state())))

    def _check_floor(self, scale: float) -> None:
        """One sentence for an accuracy below what the highest precision allowed reaches on states of size ``scale``
        (double-double unless ``extended_precision`` is false; whether the model has a double-double form is
        asked when it is needed)."""
        floor, what = (DOUBLE_DOUBLE_FLOOR, "double-double") if self.extended_precision else (FLOOR, "double precision")
        if self.accuracy < floor * scale:
            advice = "" if self.extended_precision else ", or integrator.extended_precision=true"
            raise ConfigError(f"accuracy={self.accuracy:g} is below what {what} reaches on this scene "
                              f"(about {floor * scale:.1g} for states of size {scale:.3g}, stored as doubles); ask "
                              f"for accuracy ≥ {at_least(10 * floor * scale)}{advice}")

    def attributes(self) -> dict[str, Any]:
        return {"accuracy": self.accuracy}

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, progress: ProgressCallback | None = None,
                  compiled: CompiledModel | None = None, series: bool = True, estimated: bool = False,
                  amp: Amplification | None = None) -> Solution:
        """The cheapest method predicted to meet the accuracy (``series``: a regime's analytic series among the
        candidates), run; what it chose and promises is the solution's ``choice`` (nothing is kept on ``self``).
        ``estimated``: the caller measures the run's error (``gyrolab.accuracy.promise``), so a climb predicted from a
        chaotic scene's growth is tried in double first (``Choice.measure_first``). ``amp``: the growth of
        perturbations, already measured (by default measured here: by the final run itself where that is the double
        Taylor method, C8, else by a tangent run first)."""
        # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
        from gyrolab.kernels.taylor_series import ready

        start = time.perf_counter()
        scale = max(1.0, *map(abs, y0))  # a few components: Python's max is several times faster than numpy's
        self._check_floor(scale)
        if series:
            solution = self._series(fun, t_out, y0, compiled, start)
            if solution is not None:
                solution.choice.instead = lambda: self.integrate(fun, t_out, y0, progress, compiled, series=False,
                                                                 estimated=estimated)
                return solution
        span = t_out[-1] - t_out[0]
        t_pilot = t_out[0] + span * self.pilot_fraction
        # the pilot's grid holds the output times it covers: its tight run is the start of the trajectory
        inside = t_out[t_out < t_pilot]
        pilot_times = np.union1d(t_out[0] + span * self.pilot_fraction * _PILOT_GRID, inside)
        tau, pilot_nfev = min(max(self.accuracy * FIRST_RATIO, MIN_TOLERANCE), MAX_TOLERANCE / 10), 0
        # one order for the pilot and the final run (error ∝ tolerance), for the expected tolerance
        order = measured_order(min(self.accuracy * FIRST_RATIO, MAX_TOLERANCE / 10))
        taylor = compiled is not None and ready(compiled)  # whether the compiled model has Taylor coefficients
        make = functools.partial(_method, compiled, order if taylor else None)
        # how much the motion amplifies an error present at the pilot's end by the end of the span (chaos: e^{λt}):
        # measured by the double Taylor run itself (its one pass, C8, which measures it at the first tenth: the
        # default pilot's end), kept where that growth confirms the choice made without it; else by a tangent run
        # first (~1.5 ms on the reference scene, the run's 3×), which the chaos margins were calibrated with
        tangent_run = functools.partial(amplification, compiled, fun, y0, t_out[0], t_pilot, t_out[-1],
                                        make(SHADOW_TOLERANCE))
        provisional = amp is None and taylor and self.pilot_fraction == PILOT_FRACTION
        if amp is None:
            amp = Amplification(0.0, 0.0, span, "none yet") if provisional else tangent_run()
        loose = None  # the previous round's loose run (tolerance, solution): the next round's tight run
        # a measured final run resumes from the pilot's tight run measured the same way (C8): measured in the pilot,
        # it need not run again (on the reference scene 0.09 ms at 1e-6, 0.14 at 1e-10)
        measuring = _measuring(make(MAX_TOLERANCE), estimated or provisional, estimated)
        for _ in range(3):
            pilot_tau = tau
            per_tol, growth, nfev, measured, (tight_tol, tight), loose = self._pilot(fun, pilot_times, y0, compiled,
                                                                                     tau, loose, make, measuring)
            per_tol = _amplified(per_tol, growth, amp.factor, self.pilot_fraction, CHAOS_MARGIN)
            pilot_nfev += nfev
            # per_tol bounds the truncation error even when the pilot saw only round-off
            chosen = MAX_TOLERANCE if per_tol == 0 else \
                min(self.accuracy / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9), MAX_TOLERANCE)
            if not measured and tau < MAX_TOLERANCE / 100:  # only round-off seen: measure with a looser pilot
                tau *= 100
            elif chosen > RECENTRE * tau:  # re-centre: never extrapolate far towards looser tolerances
                tau = chosen
            else:  # at a fixed order, extrapolating to tighter tolerances is safe (the leading term dominates more)
                break
        if loose[1].stats.n_steps < MIN_PILOT_STEPS:
            # a pilot of a few steps, clipped by its end rather than set by τ, measures nothing of the error's
            # dependence on the tolerance (MIN_PILOT_STEPS): the span is a few dozen steps, take the prior
            per_tol = max(per_tol, UNMEASURED_PER_TOL)
            chosen = min(self.accuracy / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9), MAX_TOLERANCE)
        elif not measured:  # only round-off seen up to pilot_tau: never extrapolate far beyond the loosest τ tried
            chosen = min(chosen, RECENTRE * pilot_tau)
        # round-off of the compensated Taylor update grows as a random walk over the steps, that of scipy's plain
        # update by up to an ulp per step: a target below it is not met in double precision, whatever the tolerance
        steps = tight.stats.n_steps / self.pilot_fraction * max(1.0, (tight_tol / chosen) ** (1.0 / order))
        roundoff = EPS * scale * (math.sqrt(steps) if taylor else steps)
        chaotic = amp.chaotic(self.pilot_fraction)  # faster than any power law the pilot fits
        chaos = _chaos_attributes(amp, chaotic)
        if chaotic:  # round-off committed early grows with the perturbations: up to e^{max ln|δ|}
            roundoff *= CHAOS_MARGIN * math.exp(min(max(amp.log_span, 0.0), 700.0))
            chaos["auto_precision_horizon"] = amp.horizon(self.accuracy, roundoff / math.exp(amp.log_span))
        climbed = roundoff > self.accuracy
        why = (f"double precision's round-off on this scene (about {roundoff:.1g} over ~{steps:.0f} steps) is below "
               f"accuracy={self.accuracy:g}")
        final = functools.partial(self._final, fun, t_out, y0, progress, compiled, start, per_tol, growth,
                                  pilot_nfev, chaos, estimated=estimated)
        if climbed and provisional:  # a climb, or a refusal, is chosen with the growth measured first
            return self.integrate(fun, t_out, y0, progress, compiled, False, estimated, tangent_run())
        if climbed:
            up = self._climb(compiled, make, per_tol, roundoff, steps, amp, chaotic, t_out)  # raises if dd can't
            predicted = functools.partial(final, *up) if isinstance(up, tuple) else functools.partial(_raise, up)
            if not (chaotic and estimated):
                return predicted()
            # A chaotic scene's round-off is predicted from the tangent run's growth, which scatters by orders of
            # magnitude (docs/integrators.md, "Needless climbs"): run in double first and keep it only when its
            # error estimate measures the target met; else climb as predicted (``Choice.measure_first``).
            chosen = max(min(self.accuracy / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9), MAX_TOLERANCE),
                         Taylor.TOLERANCE_FLOOR)  # (the tolerance recorded is the one run)
            # That run carries a double-double head (HEAD_ORDERS): its round-off thousands of times smaller for ~2× a
            # double run's work, it keeps targets plain double cannot (the chaotic top over t = 200 at 1e-8: 7.6e-10
            # away where double ends ~1e-6 away), without the whole series in double-double (~15× a double run).
            solution = final(make(chosen, head=HEAD_ORDERS), chosen, 0.0, (
                f"double precision's round-off on this chaotic scene is predicted at about {roundoff:.1g} over "
                f"~{steps:.0f} steps, above accuracy={self.accuracy:g}, from a growth that scatters: run in double "
                f"first (with a double-double head), kept only where its error estimate measures the target met"),
                resumed=None)  # (the head measures its round-off from the start: not from a double pilot's)
            promised = self.accuracy / ESTIMATE_SLACK
            solution.choice = replace(solution.choice, promised=promised, measure_first=True,
                                      attributes={**solution.choice.attributes, "auto_predicted_error": promised},
                                      instead=predicted)
            return solution
        if CALIBRATION * per_tol * chosen + roundoff > self.accuracy:  # leave room for the round-off
            chosen = (self.accuracy - roundoff) / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9)
        # the pilot's tight run is as accurate when its tolerance is: the run continues from its end
        resumed = (tight, make(tight_tol), pilot_times, inside, t_pilot) if tight_tol <= chosen else None
        # A run kept only when measured ESTIMATE_SLACK below the target, whose predicted round-off is not far below
        # that, is kept or not by its round-off's luck (the reference scene at 1e-13: 3.3e-14 or 5.3e-14 against
        # 5e-14, then a double-double run): it carries a double-double head (round-off ~100× smaller; the
        # round-off predicted is kept, a margin)
        head = HEAD_ORDERS if estimated and taylor and 2 * ESTIMATE_SLACK * roundoff > self.accuracy else 0
        return final(make(chosen, head=head), chosen, roundoff, why, resumed,
                     provisional=tangent_run if provisional else None)

    def _final(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, progress: ProgressCallback | None,
               compiled: CompiledModel | None, start: float, per_tol: float, growth: float, pilot_nfev: int,
               chaos: dict, method: Integrator, chosen: float, roundoff: float, why: str,
               resumed: tuple | None = None, estimated: bool = False, provisional: Any = None) -> Solution:
        """``method``'s run at tolerance ``chosen`` over the output times, with what it promises (its truncation error
        and ``roundoff``) and the attributes saying what was chosen and why (``why``); ``estimated``: its error
        estimated in the same pass where the method can (C8). ``provisional`` (the tangent run, a callable): chosen
        without the growth of perturbations, which the run measures (C8): kept where that growth is no chaos and
        leaves the target met, else the choice is made again with the tangent run's growth (the measure the chaos
        margins were calibrated with: deciding climbs and refusals with the run's own, audit seed 2026 refused three
        targets double-double reaches), ``integrate(amp=...)``. A growth that is no chaos but raises the prediction
        above the accuracy, on a run whose error is ``estimated``: the run is kept where its error estimate measures
        the target met, and the choice made again only where not (``Choice.measure_first``): the growth after the
        pilot of a regular motion is ~10× (a tangent vector's linear drift over the other nine tenths), at the edge
        of what the pilot's t² law allows, and one random scene in six crossed it (each then ran its tangent run,
        pilot and run again: 5–15 ms)."""
        y, final_stats, n_steps, own = _final_run(method, fun, t_out, y0, progress, compiled, resumed,
                                                  estimated or provisional is not None, estimated)
        raised = None

        def again() -> Solution:  # the choice made again with the tangent run's growth
            return self.integrate(fun, t_out, y0, progress, compiled, False, estimated, provisional())

        if provisional is not None:
            amp = growth_of(own, t_out[-1] - t_out[0])
            measured = _amplified(per_tol, growth, amp.factor, self.pilot_fraction, CHAOS_MARGIN)
            if self.safety * CALIBRATION * measured * chosen + roundoff > self.accuracy:
                raised = CALIBRATION * measured * chosen + roundoff
            if amp.chaotic(self.pilot_fraction) or (raised is not None and not estimated):
                return again()
            per_tol, chaos = measured, _chaos_attributes(amp, False)
            own = own if estimated else None
        promised = CALIBRATION * per_tol * chosen + roundoff
        choice = {
            "auto_method": method.name,
            "auto_tolerance": chosen,
            "auto_predicted_error": promised,
            "auto_predicted_error_bounds": PREDICTION_MEANING,
            # before CALIBRATION and round-off: what benchmarks/perf_reference.py --calibration measures
            "auto_raw_predicted_error": per_tol * chosen,
            "auto_error_growth_exponent": growth,
            "auto_pilot_nfev": pilot_nfev,
            **chaos,
            **{f"auto_{k.removeprefix('integrator_')}": v for k, v in method.attributes().items()},
            "auto_precision": method.precision,
            "auto_precision_reason": why,
        }
        measure_first, instead = False, None
        if raised is not None:  # kept only where its error estimate measures the target met, else ``again``
            promised, measure_first, instead = self.accuracy / ESTIMATE_SLACK, True, again
            choice.update({"auto_predicted_error": promised, "auto_predicted_error_by_growth": raised,
                           "auto_precision_reason": f"{why}; the growth of perturbations the run measured raises the "
                           f"prediction to {raised:.2g}: kept only where its error estimate measures the target met"})
        return Solution(t_out, y, IntegratorStats(
            nfev=final_stats.nfev + pilot_nfev, n_steps=n_steps, n_rejected=final_stats.n_rejected,
            wall_time=time.perf_counter() - start, njev=final_stats.njev, nlu=final_stats.nlu),
            Choice(method, choice, self.accuracy, promised, self.extended_precision, measure_first=measure_first,
                   instead=instead), own)

    def _climb(self, compiled: CompiledModel | None, make: Any, per_tol: float, roundoff: float, steps: float,
               amp: Any, chaotic: bool, t_out: np.ndarray) -> tuple[Integrator, float, float, str] | ConfigError:
        """(the method one rung up the precision ladder, its tolerance, its round-off, why) where double precision's
        round-off on this scene (``roundoff``) is above the accuracy; else one ConfigError sentence (``_refusal``):
        raised when double-double cannot reach the target either, returned when the ladder stops at double
        precision. The truncation error per unit tolerance is the pilot's (the double-double run keeps the pilot's
        order, ``climbed``); the round-off is double precision's scaled by the ratio of the unit round-offs."""
        # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
        from gyrolab.kernels.taylor_dd import MIN_TOL

        roundoff_dd = roundoff * DOUBLE_DOUBLE_EPS / EPS
        best_dd = roundoff_dd + self.safety * CALIBRATION * per_tol * MIN_TOL  # the best double-double does here
        tol = (self.accuracy - roundoff_dd) / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9)
        tol = min(max(tol, MIN_TOL), MAX_TOLERANCE)
        up = make(tol).climbed(1.0)  # the next rung's method at tol, when the chosen method has one
        if up is not None and (compiled is None or type(up[0]).refusal(compiled, self.system) is not None):
            up = None  # (a model without a double-double form)
        if up is not None and self.extended_precision:
            if best_dd < self.accuracy:
                return up[0], tol, roundoff_dd, (
                    f"double precision's round-off on this scene (about {roundoff:.1g} over ~{steps:.0f} steps) is "
                    f"above accuracy={self.accuracy:g}; double-double's is about {roundoff_dd:.1g}")
            raise self._refusal("double-double", best_dd, chaotic, amp, t_out, "")
        climb = ", or integrator.extended_precision=true (auto then climbs to double-double)" if (
            up is not None and best_dd < self.accuracy) else ""
        # returned, not raised: on a chaotic scene the caller may try double first, measured (``integrate``)
        return self._refusal("double precision", roundoff, chaotic, amp, t_out, climb)

    def _refusal(self, rung: str, error: float, chaotic: bool, amp: Any, t_out: np.ndarray,
                 climb: str) -> ConfigError:
        """One sentence: ``rung``'s error on this scene (``error``) is above the accuracy, naming λ and the horizon
        (how long ``rung`` keeps the accuracy: e^{λt} growth on a chaotic scene, a random walk ∝ √t otherwise); its
        advice is a target 3× above the error (when below the state's size) or a time.end inside the horizon."""
        span, scale = t_out[-1] - t_out[0], max(1.0, *map(abs, self.system.initial_state())) if self.system else 1.0
        if chaotic:
            horizon = amp.horizon(self.accuracy, error / math.exp(min(max(amp.log_span, 0.0), 700.0)))
            growth = f"λ ≈ {amp.lyapunov:.2g}, perturbations grow ~{amp.factor:.1g}× after the pilot: "
        else:
            horizon, growth = span * (self.accuracy / error) ** 2, ""
        horizon = min(horizon, span)
        asks = [f"accuracy ≥ {at_least(3 * error)}"] if 3 * error < 0.1 * scale else []
        if horizon > 0.01 * span:
            end = t_out[0] + 0.8 * horizon
            digits = 10.0 ** (math.floor(math.log10(abs(end))) - 2) if end else 1.0
            asks.append(f"time.end ≤ {math.floor(end / digits) * digits:.4g}")
        word = "" if rung == "double precision" else " even"
        return ConfigError(
            f"accuracy={self.accuracy:g} cannot be reached{word} in {rung} on this scene ({growth}error about "
            f"{error:.1g}, so {rung} keeps {self.accuracy:g} only to t ≈ {t_out[0] + horizon:.4g} of "
            f"{t_out[-1]:.4g}); ask for {' or '.join(asks) or 'a shorter time.end'}{climb}")

    def _series(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
                start: float) -> Solution | None:
        """The first regime whose analytic series is predicted to meet the accuracy on this scene, or None."""
        if self.system is None or compiled is None or t_out[0] != 0.0 or compiled.built_in is None:
            return None  # the regimes' series describe the built-in torques only
        from gyrolab.contracts import registry

        span = t_out[-1] - t_out[0]
        candidates = []  # each regime's variants predicted to meet the target, lowest series order first
        for name in registry.names("regime"):
            try:
                base = registry.load("regime", name)()
                if self.system.name in base.systems and not self._misses_orbits(base, fun, y0, compiled, span):
                    ladder = getattr(base, "series_candidates", lambda system, accuracy: [(base, None)])
                    candidates += [(name, r, float("nan") if e is None else float(e))
                                   for r, e in ladder(self.system, self.accuracy / self.safety)]
            except GyrolabError:
                continue
        tolerance = self.accuracy / (10 * self.safety)  # how far from the orbit's start the scene may begin
        far: set[str] = set()  # regimes whose orbit the scene is known to miss by far more than any variant's error
        for name, regime, estimate in candidates:
            if name in far and np.isfinite(estimate):
                continue
            try:
                # a variant with a predicted error has a built series whose start is cheap: checked before the
                # domain (most scenes miss the orbit); otherwise the domain check is the cheap one (a shooting)
                if not np.isfinite(estimate) and regime.check_domain(self.system):
                    continue  # outside the domain, or near its edge (warnings): no confidence in the series
                with np.errstate(all="ignore"):  # an orbit may evaluate to inf/nan: a miss
                    distance = float(np.max(np.abs(regime.initial_state(self.system)[:6] - y0[:6])))
                if not distance <= tolerance:
                    # a regime's variants approximate one orbit, each within accuracy/safety of it: the scene
                    # misses every one by ≥ distance − 2·accuracy/safety (MISS_MARGIN: the prediction is an estimate)
                    if np.isfinite(estimate) and distance > tolerance + 2 * MISS_MARGIN * self.accuracy / self.safety:
                        far.add(name)
                    continue  # the scene does not start on the orbit the series describes
                if np.isfinite(estimate) and regime.check_domain(self.system):
                    continue
            except GyrolabError:
                continue
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
            attributes = {"auto_method": f"regime {name}", "auto_predicted_error": predicted,
                          "auto_series_error_one_period": measured, "auto_check_nfev": truth.stats.nfev,
                          "auto_precision": PRECISIONS[0], "auto_precision_reason": "an analytic series, evaluated "
                          "in double precision: no integration", **regime.attributes()}
            # measured against the full model by the compiled Taylor method at tol 1e-15 (the series' check run)
            return Solution(t_out, y, IntegratorStats(nfev=truth.stats.nfev, n_steps=0, n_rejected=0,
                                                      wall_time=time.perf_counter() - start),
                            Choice(None, attributes, self.accuracy, predicted, self.extended_precision,
                                   check=Taylor(tol=1e-15)))
        return None

    def _misses_orbits(self, base: Any, fun: RightHandSide, y0: np.ndarray, compiled: CompiledModel,
                       span: float) -> bool:
        """Whether the scene is certainly on none of the orbits ``base``'s variants describe: its own motion stays
        farther than 1.1·accuracy/safety + max|Φ'|·h/2 from y0 over the period range ``period_spread`` allows.
        A necessary condition of the series check, before any series is built (~2 ms warm, ~0.4 s on a process's
        first call); the argument: docs/performance.md, "The series check, screened"."""
        spread = getattr(base, "period_spread", None)
        if spread is None:
            return False
        try:
            with np.errstate(all="ignore"):
                period = float(base.period(self.system))
        except GyrolabError:
            return False  # no cheap period: the full check decides (and refuses what does not apply)
        lo, hi = period / spread, period * spread
        if not (np.isfinite(hi) and 0 < lo) or hi > span:
            return False  # the check's window is then the span, not a period: no periodicity to use
        times = np.empty(SCREEN_POINTS + 1)  # 0, then np.linspace(lo, hi, SCREEN_POINTS)'s values in a third of its time
        times[0], times[1:] = 0.0, np.arange(SCREEN_POINTS) * ((hi - lo) / (SCREEN_POINTS - 1)) + lo
        times[-1] = hi
        y = taylor_samples(compiled, SCREEN_TOLERANCE, times, y0)
        margin = 1.1 * self.accuracy / self.safety + 1e3 * SCREEN_TOLERANCE * max(1.0, *map(abs, y0[:6]))
        return not _fast(_comes_back, compiled)(y, y0, margin)

    def _pilot(self, fun: RightHandSide, times: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
               tau: float, previous: tuple[float, Solution] | None, make: Any, measuring: dict
               ) -> tuple[float, float, int, bool, tuple[float, Solution], tuple[float, Solution]]:
        """(raw predicted final error per unit tolerance, growth exponent q, evaluations, whether the pilot
        measured an error above round-off, the tight run and the loose run as (tolerance, solution)) from runs
        at τ and a tighter τ_t: the previous round's loose run when τ_t ≤ τ/10 (a re-centred or loosened round
        reuses it), else a new run at min(τ/100, accuracy/TIGHT_RATIO), measured as ``measuring`` says (the final run
        may resume from it: ``_final_run``). The error at τ is then the runs' difference × τ/(τ − τ_t)."""
        loose = make(tau).integrate(fun, times, y0, None, compiled)
        if previous is not None and previous[0] <= tau / 10:
            tight_tol, tight = previous
            tight_nfev = 0
        else:
            # τ/100, or tighter where τ is held at MIN_TOLERANCE far above the final tolerance (~accuracy/1000): the
            # tight run must be at least as accurate as the final one to be its start
            tight_tol = min(tau * 1e-2, self.accuracy / TIGHT_RATIO)
            tight = make(tight_tol).integrate(fun, times, y0, None, compiled, **measuring)
            tight_nfev = tight.stats.nfev
        final, slope = _fast(_error_growth, compiled)(loose.y, tight.y, times)
        # differences within a few hundred ulps are round-off, not a measurement of the truncation error
        measured = bool(final > 100 * EPS * max(1.0, *map(abs, y0)))
        # A non-symplectic method on a (near-)integrable motion drifts in energy linearly, hence in phase
        # quadratically: assume q = 2 unless the pilot shows faster growth (its early error is a plateau).
        growth = MIN_GROWTH if math.isnan(slope) else min(max(slope, MIN_GROWTH), MAX_GROWTH)
        per_tol = final / (tau - tight_tol) * (1.0 / self.pilot_fraction) ** growth
        return per_tol, growth, loose.stats.nfev + tight_nfev, measured, (tight_tol, tight), (tau, loose)

    def choose_batch_method(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray,
                            params: np.ndarray) -> tuple[Integrator, dict[str, Any]]:
        """The method and tolerance for a batch: the single-run choice on a few trajectories, the tightest.

        The sample is the first trajectory, the one with the largest state and the one whose parameters
        lie farthest from the batch's mean (up to AUTO_SAMPLE distinct ones). Each runs the pilot and final
        run; the batch then runs the chosen method at the smallest tolerance chosen. A trajectory harder
        than every sampled one may miss the accuracy: sample it (pass it first) when you know it.
        """
        P = params
        spread = np.abs(P - P.mean(axis=0)).max(axis=1) if len(P) > 1 else np.zeros(1)
        sample = list(dict.fromkeys([0, int(np.argmax(np.abs(y0s).max(axis=1))), int(np.argmax(spread))]))[:AUTO_SAMPLE]
        choices = []
        for j in sample:
            single = type(self)(accuracy=self.accuracy, pilot_fraction=self.pilot_fraction, safety=self.safety,
                                extended_precision=False)  # the vectorised kernels run in double precision
            model = CompiledModel(P[j])
            choices.append(single.integrate(compiled_rhs(model), times, y0s[j], None, model, series=False).choice)
        choice = min(choices, key=lambda c: c.attributes["auto_tolerance"])  # the chosen method (Taylor or DOP853)
        return choice.method, {"accuracy": self.accuracy, "auto_sampled_trajectories": len(sample),
                               **{k: v.item() if isinstance(v, np.generic) else v for k, v in choice.attributes.items()}}

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        """The batch's choice (``choose_batch_method``), then that method's kernel; the wall time includes the pilot."""
        start = time.perf_counter()
        method, settings = self.choose_batch_method(compiled, times, y0s, params)
        solution = method.integrate_batch(compiled, times, y0s, params, failures)
        solution.wall_time = time.perf_counter() - start
        solution.settings = settings
        return solution


def measured_order(tol: float) -> int:
    """The order of ``auto``'s pilot and final run at the expected tolerance ``tol``: the ``taylor`` integrator's
    (``order_for``: least work per unit time with a step's work besides its series; the measured run's one pass
    makes that work larger still), but no higher than Jorba & Zou's at the run tolerance below which the error
    estimate turns to a twin run or companions (DOUBLE_DOUBLE_BELOW × TIGHTER: order 16), and never below Jorba &
    Zou's at ``tol``. On the reference scene the measured run took 0.69× its time with Jorba & Zou's order at tol
    1e-7 (16 against 10), 0.87× at 1e-10 (15 against 13); the whole call 0.93–1.00× at ε = 1e-6 … 1e-9 in the
    interleaved benchmark, where its Python parts weigh more.
    Higher orders measured faster still but weakened the pilot's prediction at loose tolerances (the chaos audit's
    fast top at ε = 1e-4 ended 1.7e-4 from its first run at order 16) and, uncapped, sent tight targets to
    companions or broke ε = 1e-12 without an estimate (docs/performance.md, "The order of a measured run")."""
    from gyrolab.kernels.taylor import order_for  # start-up: the kernel imports numba

    cap = order_for(DOUBLE_DOUBLE_BELOW * TIGHTER, overhead=0.0)
    return max(order_for(tol, overhead=0.0), min(order_for(tol), cap))


def _method(compiled: CompiledModel | None, order: int | None, tol: float, head: int = 0) -> Integrator:
    """The method auto runs at ``tol``: the compiled Taylor method at ``order`` (None: a compiled model without
    Taylor coefficients, compiled DOP853 instead), with a double-double ``head`` where the model has a double-double
    series; scipy's DOP853 without a compiled model."""
    if compiled is not None:
        if order is None:
            return DOP853Numba(rtol=tol, atol=tol)
        return Taylor(order=order, tol=tol, head=head if head and TaylorDoubleDouble.refusal(compiled) is None else 0)
    # start-up: scipy.integrate (~0.35 s) only for a scene without a compiled model
    from gyrolab.plugins.integrators.scipy_solvers import DOP853

    return DOP853(rtol=tol, atol=tol)


def at_least(value: float) -> str:
    """``value`` rounded up to one significant digit, as a refusal's advice writes it (to nearest could advise a
    target the scene refuses again)."""
    exponent = math.floor(math.log10(value))
    digit = math.ceil(value / 10.0 ** exponent * (1 - 1e-12))
    return f"{digit}e{exponent}" if digit < 10 else f"1e{exponent + 1}"


def _chaos_attributes(amp: Amplification, chaotic: bool) -> dict[str, Any]:
    """The dataset attributes saying how the scene amplifies perturbations (``amp``) and whether that is chaos."""
    return {"auto_lyapunov_exponent": amp.lyapunov, "auto_amplification": amp.factor,
            "auto_amplification_method": amp.how, "auto_chaotic": int(chaotic)}


def _amplified(per_tol: float, growth: float, factor: float, fraction: float, margin: float) -> float:
    """The pilot's predicted final error per unit tolerance, raised where the motion amplifies errors faster than
    the pilot's power law: an error E at the pilot's end grows by up to ``factor`` (``amplification``) and each of
    the 1/fraction − 1 later stretches commits as much at most, so the final error is ≤ E · factor / fraction.
    Beyond the largest power law (chaos) the factor carries ``margin``: one numerical trajectory's growth scatters."""
    extrapolated = (1.0 / fraction) ** growth
    if factor > (1.0 / fraction) ** MAX_GROWTH:
        factor *= margin
    return per_tol / extrapolated * max(extrapolated, factor / fraction)


#: the statistics below compiled, by name (``_fast``)
_COMPILED: dict[str, Any] = {}


def _fast(function: Any, compiled: CompiledModel | None) -> Any:
    """``function`` compiled with numba (cached on disk) when the scene runs compiled code, hence has numba loaded;
    the same function in Python otherwise (scipy's runs around it take ~1000× longer). Written as loops over
    small arrays: in numpy they were a dozen calls of ~5–15 µs each per pilot round, ~10 % of a millisecond run."""
    if compiled is None:
        return function
    if function.__name__ not in _COMPILED:
        # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
        from gyrolab.kernels.compiler import kernel

        _COMPILED[function.__name__] = kernel(function)
    return _COMPILED[function.__name__]


def _error_growth(loose: np.ndarray, tight: np.ndarray, times: np.ndarray) -> tuple[float, float]:
    """(E(T), q) for two runs on ``times``: E the envelope (running maximum) of their max-norm difference (pointwise
    errors of periodic motions dip through zero), and q the least-squares slope of log E against log(t − t0)
    over the last three quarters of the span (the early error is a plateau), or NaN where E is zero there.
    The slope is centred, as ``np.polyfit(x, y, 1)[0]`` (no LAPACK call: BLAS threads spin after it)."""
    n = loose.shape[0]
    envelope = np.empty(n)
    top = 0.0
    for i in range(n):
        for k in range(loose.shape[1]):
            d = abs(loose[i, k] - tight[i, k])
            if d > top or math.isnan(d):  # a NaN stays (as in np.maximum.accumulate)
                top = d
        envelope[i] = top
    span = times[n - 1] - times[0]
    first = 0
    while times[first] - times[0] < span / 4:
        first += 1
    if not envelope[first] > 0:  # the envelope is non-decreasing: zero somewhere late, or NaN
        return top, math.nan
    m = n - first
    x, y = np.empty(m), np.empty(m)
    for i in range(m):
        x[i] = math.log(times[first + i] - times[0])
        y[i] = math.log(envelope[first + i])
    x_mean, y_mean = np.mean(x), np.mean(y)
    sxy = sxx = 0.0
    for i in range(m):
        sxy += (x[i] - x_mean) * (y[i] - y_mean)
        sxx += (x[i] - x_mean) * (x[i] - x_mean)
    return top, sxy / sxx


def _comes_back(y: np.ndarray, y0: np.ndarray, margin: float) -> bool:
    """Whether the motion sampled in ``y`` (row 0: the start y0; rows 1…: an equally spaced grid) comes within
    ``margin`` + max|Φ'|·h/2 of y0 in every one of its first six components at some grid time. max|Φ'|·h/2 is
    taken as the largest step between neighbouring rows: the secants' slope, doubled (it falls short of max|Φ'|
    by O(h²)), times h/2."""
    jump = 0.0
    for i in range(2, y.shape[0]):
        for k in range(6):
            jump = max(jump, abs(y[i, k] - y[i - 1, k]))
    limit = margin + jump
    for i in range(1, y.shape[0]):
        near = True
        for k in range(6):
            if not abs(y[i, k] - y0[k]) <= limit:
                near = False
                break
        if near:
            return True
    return False


def _measuring(method: Integrator, measured: bool, estimated: bool) -> dict:
    """The keywords of ``method.integrate`` for a run that measures the growth of perturbations (``measured``) and its
    own error too (``estimated``), where the method can (C8); none otherwise."""
    return {"estimate": estimated, "growth_only": not estimated} if measured and method.supports(ESTIMATES_ERROR) \
        else {}


def _raise(error: Exception) -> Any:
    raise error


def _final_run(method: Integrator, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
               progress: ProgressCallback | None, compiled: CompiledModel | None,
               resumed: tuple | None, measured: bool, estimated: bool
               ) -> tuple[np.ndarray, IntegratorStats, int, OwnEstimate | None]:
    """(outputs, the run's stats, steps, its own measurement or None) of ``auto``'s chosen ``method`` over ``t_out``:
    from y0, or, with ``resumed`` = (the pilot's tight run, its method, its times, the output times inside the pilot,
    the pilot's end), from the end of the pilot's tight run, whose outputs inside the pilot are kept. ``measured``:
    the run measures the growth of perturbations where the method can (C8), and its own error too where
    ``estimated``; resumed, it carries on the tight run's measurement (the pilot measured it the same way, else it runs
    again measured: the same states)."""
    kind = _measuring(method, measured, estimated)
    if resumed is None:
        solution = method.integrate(fun, t_out, y0, progress, compiled, **kind)
        return solution.y, solution.stats, solution.stats.n_steps, solution.estimate
    tight, tight_method, pilot_times, inside, t_pilot = resumed
    if kind:
        if tight.estimate is None:  # (a later pilot round's tight run is the previous round's loose run, unmeasured)
            tight = tight_method.integrate(fun, pilot_times, y0, None, compiled, **kind)
        kind["resume"] = tight.estimate
    head = np.searchsorted(pilot_times, inside)  # the outputs inside the pilot
    rest = t_out[t_out >= t_pilot]
    # (from the state the tight run ended in, with its compensation: the low part of a double-double head's state)
    start = tight.estimate.end[3] if kind and tight.estimate is not None else tight.y[-1]
    tail = method.integrate(fun, np.concatenate([[t_pilot], rest]) if rest[0] > t_pilot else rest, start,
                            progress, compiled, **kind)
    steps = tail.stats.n_steps + tight.stats.n_steps
    own = tail.estimate
    if own is not None:  # the pilot's part and the rest, as one run's
        head_own = tight.estimate
        # (a double-double head resumed from a pilot without one measured the round-off of its own steps only: not
        # measured for the whole run, so a companion measures it, ``estimate.one_pass``)
        roundoff = own.roundoff if getattr(tight_method, "head", 0) == getattr(method, "head", 0) else None
        own = replace(own, error=None if own.error is None else np.concatenate([head_own.error[head],
                                                                                own.error[-len(rest):]]),
                      log_growth=np.concatenate([head_own.log_growth[head], own.log_growth[-len(rest):]]), steps=steps,
                      roundoff=roundoff)
    return np.concatenate([tight.y[head], tail.y[-len(rest):]]), tail.stats, steps, own
