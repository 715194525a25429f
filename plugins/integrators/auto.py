"""Accuracy-targeted choice: the cheapest integrator and setting predicted to reach ``accuracy``.

A tolerance is not an accuracy: how the final error depends on it varies
with the scene (on the reference scene the final error of the Taylor method
is 24 to 470 times its per-step tolerance depending on the order; on the
extremes matrix the ratio spans four decades), and no per-step error control
predicts how local errors grow into the global one. So ``auto`` measures
that dependence on the scene itself with a short pilot: two runs over the
first ``pilot_fraction`` of the time span, at tolerances τ and τ_t ≤ τ/10 and the
same order, give the error of the τ run along the pilot (hence a growth
exponent q, error ∝ t^q). At a fixed order the error is proportional to the
tolerance (checked in the tests), so the full span at tolerance τ' is
predicted to end with error err(τ) · (τ'/τ) · (T/T_pilot)^q, with q ≥ 2: a
non-symplectic method drifts in energy linearly on a near-integrable motion,
so its phase error grows quadratically (measured on the reference problem:
the error of Taylor at tol 1e-10 grows ×100 from t = 30 to t = 300).
``auto`` picks τ' to meet ``accuracy`` with a safety factor and records the
prediction multiplied by ``CALIBRATION`` (``tests/test_extremes.py`` and
``tests/test_compiled.py`` check that the recorded prediction bounds the actual
error on the extremes matrix and the reference scene). The pilot is not wasted:
its tight run is at least as accurate as the final one, so it is the first
``pilot_fraction`` of the trajectory and the final run continues from its end.
A pilot round that re-centres τ (the first prediction asked for a tolerance
more than ``RECENTRE`` = 20× looser) or loosens it (only round-off seen) reuses the previous
round's τ run as its tight run, so each later round costs one run, not two.

Calibration, measured 2026-11-24 with ``python benchmarks/perf_reference.py
--calibration`` (the pilot as it is now: re-centred rounds reuse their previous
run, tight runs down to accuracy/3000): the largest ratio of the actual final
error to the raw prediction (before CALIBRATION and round-off) over the
extremes matrix and the reference scene at accuracies 1e-3 to 1e-13, counting
only errors at least 100 times above the references' disagreement, is 0.94
(reference scene, accuracy 1e-5); on the extremes scenes it is at most 0.19.
The previous pilot gave 0.86 there. CALIBRATION = 3 leaves a factor 3.2.

Candidates, fastest first: an expansion regime's analytic series (no
integration at all), when the scene lies in the regime's domain, starts on the
periodic orbit the series describes, and the series' error — measured over one
period against a tight Taylor run and extrapolated linearly in time, as a
phase drift — meets the target; then the compiled Taylor method when the
scene has a compiled model; otherwise scipy's DOP853. Before any series is
built, a regime that declares ``period_spread`` is ruled out when the scene's
own motion never comes back near its start over the orbit's period range
(``Auto._misses_orbits``: a necessary condition of the series check, ~0.25 ms;
building and checking the series costs ~2 ms, 0.4 s on a process's first call).

Round-off: the Taylor state update is compensated (Kahan), so round-off no
longer grows by an ulp per step but as a random walk, about eps·|y|·√steps
(measured floor on the reference scene: 9e-15 over 2,700 steps, where this
estimate gives 6e-14); targets below that estimate are refused.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from gyrolab.contracts.integrator import (
    BATCH_KERNEL,
    CHOOSES_METHOD,
    PREFERS_COMPILED_MODEL,
    TIME_DEPENDENT,
    VECTOR_LANES,
    BatchSolution,
    CompiledModel,
    Integrator,
    IntegratorStats,
    ProgressCallback,
    RightHandSide,
    Solution,
)
from gyrolab.errors import ConfigError, GyrolabError, as_number
from gyrolab.plugins.integrators.amplification import amplification

PILOT_POINTS = 65
MIN_GROWTH = 2.0
#: the pilot's power law t^q is capped at this q; an amplification beyond (1/pilot_fraction)^MAX_GROWTH after the
#: pilot is exponential growth: a chaotic scene
MAX_GROWTH = 4.0
#: what ``auto_predicted_error`` is, stored beside it in every run
PREDICTION_MEANING = ("an upper estimate of the max-norm error of the final state against the exact solution (model "
                      "units): the pilot's measured error extrapolated over the span, raised by the amplification of "
                      "perturbations measured over the whole span (chaotic scenes), times a calibration factor, plus "
                      "the round-off of double precision (amplified likewise); checked by output.error_estimate "
                      "(rule 11: a run that breaks it runs again or is refused), a prediction only without it")
#: on a chaotic scene the amplification (and the round-off it carries) is taken this many times larger: one tangent
#: run's growth factor scatters by up to e^2 ≈ 7 between nearby tolerances (``amplification.TANGENT_TOLERANCE``),
#: and the round-off estimate is an estimate (benchmarks/chaos_promise.py: with no margin, slow_spin at t = 300
#: was accepted at 1e-6 and ended at 1.4e-6)
CHAOS_MARGIN = 10.0
#: tolerance of the shadow pair that measures the amplification where the variational equations do not apply
SHADOW_TOLERANCE = 1e-9
FLOOR = 1e-15  # relative to the state's size: nothing in double precision reaches below this
#: the same for double-double (its Taylor method's smallest tolerance is 1e-32; its round-off ~1e-31 per step)
DOUBLE_DOUBLE_FLOOR = 1e-30
MIN_TOLERANCE = 1e-13  # first pilot: tighter tolerances differ from τ/100 by round-off only on O(1) states
MAX_TOLERANCE = 1e-5  # looser per-step tolerances take steps near the Taylor series' radius of convergence
FIRST_RATIO = 1e-3  # first pilot tolerance relative to the accuracy (the typical error/tolerance ratio is 10–500)
#: the pilot's tight run is at most accuracy/TIGHT_RATIO (final tolerances on the reference scene: accuracy/420 to
#: accuracy/1300; the tight run is the start of the final one only when at least as accurate)
TIGHT_RATIO = 3000.0
#: a pilot whose loose run took fewer steps than this measured nothing about the tolerance (its steps were clipped by the
#: pilot's end); the error per unit tolerance is then taken as UNMEASURED_PER_TOL, above the final error / tolerance
#: ratios measured on the reference scene (24–470) and on the short fast scene that showed the case (5.7)
MIN_PILOT_STEPS = 8
UNMEASURED_PER_TOL = 1.0 / FIRST_RATIO
#: a first prediction more than this many times looser than the pilot's τ is measured again at its own tolerance
#: (one more run over the pilot's span). 20, not 10: over the extremes matrix and the reference scene at four
#: accuracies per decade (1e-3 to 1e-13) the largest actual / raw predicted final error is 1.09 at every
#: threshold from 10 to 100 and no recorded prediction is exceeded; at 20 the pilot re-measures in 267 of the
#: 369 runs instead of 295 (docs/performance.md)
RECENTRE = 20.0
#: the recorded prediction is the raw one times this: the largest actual / raw predicted final error measured on the
#: extremes matrix and the reference scene (accuracies 1e-3 to 1e-13) is 0.94 (module docstring)
CALIBRATION = 3.0
#: a series' predicted error (its first omitted term) is an estimate: trusted to within this factor when ruling
#: out the other orders of a regime whose orbit the scene misses
MISS_MARGIN = 1000.0
#: the screen before the series check (``Auto._misses_orbits``): its grid over the period range and the tolerance
#: of its Taylor run (whose error, far below 1e3 × this on the one to four periods it covers, is added to its margin)
SCREEN_POINTS = 512
SCREEN_TOLERANCE = 1e-9
EPS = float(np.finfo(float).eps)
#: the unit round-off of double-double arithmetic (a 106-bit significand), for auto's extended-precision choice
DOUBLE_DOUBLE_EPS = 2.0 ** -104
#: a run whose measured error (``output.error_estimate``) exceeds its recorded prediction is run again aimed this many
#: times below the target that would have met it, at most ``MAX_RECHECKS`` times (``Auto.tightened_for``)
RECHECK_MARGIN = 3.0
MAX_RECHECKS = 2
#: trajectories of a batch on which ``auto`` runs its pilot (the first, the largest state, the most unusual parameters)
AUTO_SAMPLE = 3
_PILOT_GRID = np.linspace(0.0, 1.0, PILOT_POINTS)


class Auto(Integrator):
    name = "auto"
    adaptive = True
    # a batch runs its choice's kernel (Taylor or DOP853, both vectorised across trajectories)
    capabilities = frozenset({PREFERS_COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, CHOOSES_METHOD})
    evaluation_label = "pilot and chosen method's evaluations"

    def __init__(self, *, accuracy: float | None = None, pilot_fraction: float = 0.1, safety: float = 1.0,
                 extended_precision: bool | None = None) -> None:
        if accuracy is None:
            raise ConfigError("integrator=auto needs a target: set accuracy=... (max-norm error of the final state)")
        self.accuracy = as_number(accuracy, "accuracy", positive=True)
        self.pilot_fraction = as_number(pilot_fraction, "integrator.pilot_fraction", positive=True)
        if self.pilot_fraction >= 1:
            raise ConfigError(f"integrator.pilot_fraction={pilot_fraction} must be below 1")
        self.safety = as_number(safety, "integrator.safety", positive=True)
        if extended_precision is not None and not isinstance(extended_precision, (bool, np.bool_)):
            raise ConfigError(f"integrator.extended_precision={extended_precision!r} must be true, false or null")
        #: whether a target double precision cannot reach may be met in double-double (integrator=taylor
        #: integrator.precision=double-double) instead of being refused: yes unless forbidden (false)
        self.extended_precision = extended_precision is not False
        #: asked for explicitly (true): a batch then runs one choice per trajectory, each free to climb; by default
        #: (null) a batch chooses once, in double precision, for its vectorised kernel (one run per trajectory in
        #: Python costs ~23× the CPU)
        self.per_trajectory = extended_precision is True
        #: the measured errors of the earlier runs that broke their prediction (``tightened_for``)
        self.measured_before: tuple[float, ...] = ()
        #: a run again after a failed check (``tightened_for``): (the method, made more accurate by the factor the
        #: measurement asked for; the earlier run's choice); None: choose as usual
        self._recheck: tuple[Integrator, dict[str, Any]] | None = None
        self._no_series = False  # a series whose measured error broke its prediction is not taken again
        self.choice: dict[str, Any] = {}
        self.chaos: dict[str, Any] = {}  # the amplification measured over the span (auto_lyapunov_exponent, ...)
        self.chosen: Integrator | None = None  # the method the last integrate ran (None: an analytic series)
        self.system: Any = None
        self._pilot_steps = 0
        self._order: int | None = None
        self._taylor: bool | None = None  # whether the compiled model has Taylor coefficients (asked once per run)

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
            advice = "" if self.extended_precision else " or allow integrator.extended_precision"
            raise ConfigError(f"accuracy={self.accuracy:g} is below what {what} reaches on this scene "
                              f"(about {floor * scale:.1g} for states of size {scale:.3g}); ask for more{advice}")

    def _method(self, compiled: CompiledModel | None, tol: float) -> Integrator:
        if compiled is not None:
            from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor

            if self._taylor is None:
                from gyrolab.kernels.taylor_series import ready

                self._taylor = ready(compiled)
            # a compiled model without Taylor coefficients: compiled DOP853 instead
            if self._taylor:
                return Taylor(order=self._order, tol=tol)
            return DOP853Numba(rtol=tol, atol=tol)
        from gyrolab.plugins.integrators.scipy_solvers import DOP853

        return DOP853(rtol=tol, atol=tol)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        from gyrolab.kernels.taylor import order_for

        start = time.perf_counter()
        t_out = np.asarray(t_out, dtype=float)
        self._taylor = None
        scale = max(1.0, *map(abs, y0))  # a few components: Python's max is several times faster than numpy's
        self._check_floor(scale)
        if self._recheck is not None:
            return self._run_recheck(fun, t_out, y0, progress, compiled, start)
        series = None if self._no_series else self._series(fun, t_out, y0, compiled, start)
        if series is not None:
            return series
        span = t_out[-1] - t_out[0]
        t_pilot = t_out[0] + span * self.pilot_fraction
        # the pilot's grid holds the output times it covers: its tight run is the start of the trajectory
        inside = t_out[t_out < t_pilot]
        pilot_times = np.union1d(t_out[0] + span * self.pilot_fraction * _PILOT_GRID, inside)
        tau, pilot_nfev = min(max(self.accuracy * FIRST_RATIO, MIN_TOLERANCE), MAX_TOLERANCE / 10), 0
        # one order for the pilot and the final run (error ∝ tolerance), the optimal one for the expected tolerance
        self._order = order_for(min(self.accuracy * FIRST_RATIO, MAX_TOLERANCE / 10))
        # how much the motion amplifies an error present at the pilot's end by the end of the span (chaos: e^{λt})
        amp = amplification(compiled, fun, y0, t_out[0], t_pilot, t_out[-1], self._method(compiled, SHADOW_TOLERANCE))
        loose = None  # the previous round's loose run (tolerance, solution): the next round's tight run
        for _ in range(3):
            pilot_tau = tau
            per_tol, growth, nfev, measured, (tight_tol, tight), loose = self._pilot(fun, pilot_times, y0, compiled,
                                                                                     tau, loose)
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
            # The pilot's stretch held a few steps, clipped by its end rather than set by τ: its runs at τ and τ_t
            # take nearly the same steps, so their difference says nothing of the error's dependence on the
            # tolerance (initial.r0=32 time.end=0.25: one step each, difference 0, tol 1e-5 chosen for 1e-9, error
            # 5.7e-5). The whole span is then a few dozen steps: take the prior, cheaply conservative.
            per_tol = max(per_tol, UNMEASURED_PER_TOL)
            chosen = min(self.accuracy / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9), MAX_TOLERANCE)
        elif not measured:  # only round-off seen up to pilot_tau: never extrapolate far beyond the loosest τ tried
            chosen = min(chosen, RECENTRE * pilot_tau)
        # Round-off of the compensated Taylor update grows as a random walk over the steps (see the module's
        # note), that of scipy's plain update by up to an ulp per step: a target below it cannot be met in
        # double precision, whatever the tolerance.
        steps = self._pilot_steps / self.pilot_fraction * max(1.0, (tight_tol / chosen) ** (1.0 / self._order))
        compensated = bool(self._taylor)  # Taylor's update is compensated (None: no compiled model, scipy's DOP853)
        roundoff = EPS * scale * (math.sqrt(steps) if compensated else steps)
        chaotic = amp.factor > (1.0 / self.pilot_fraction) ** MAX_GROWTH  # faster than any power law the pilot fits
        if chaotic:  # round-off committed early grows with the perturbations: up to e^{max ln|δ|}
            roundoff *= CHAOS_MARGIN * math.exp(min(max(amp.log_span, 0.0), 700.0))
        self.chaos = {"auto_lyapunov_exponent": amp.lyapunov, "auto_amplification": amp.factor,
                      "auto_amplification_method": amp.how, "auto_chaotic": int(chaotic)}
        if chaotic:
            self.chaos["auto_precision_horizon"] = amp.horizon(self.accuracy, roundoff / math.exp(amp.log_span))
        extended = None
        if roundoff > self.accuracy and self.extended_precision:
            extended = self._extended(compiled, per_tol, roundoff)
        if roundoff > self.accuracy and extended is None:
            roundoff_dd = roundoff * DOUBLE_DOUBLE_EPS / EPS
            if self.extended_precision and compiled is not None and roundoff_dd > self.accuracy:
                raise ConfigError(
                    f"accuracy={self.accuracy:g} cannot be reached even in double-double on this scene (λ ≈ "
                    f"{amp.lyapunov:.2g}, perturbations grow ~{amp.factor:.1g}× after the pilot: round-off about "
                    f"{roundoff_dd:.1g}); ask for accuracy ≥ {roundoff_dd:.1g} or a shorter time.end")
            if chaotic:
                horizon = amp.horizon(self.accuracy, roundoff / math.exp(amp.log_span))
                raise ConfigError(
                    f"accuracy={self.accuracy:g} cannot be reached in double precision on this chaotic scene: "
                    f"λ ≈ {amp.lyapunov:.2g}, so round-off grows ~{amp.factor:.1g}× after the pilot and double "
                    f"precision keeps {self.accuracy:g} only to t ≈ {t_out[0] + horizon:.4g} of {t_out[-1]:.4g}; ask "
                    f"for accuracy ≥ {roundoff:.1g}, a shorter time.end, integrator.extended_precision=true (auto then "
                    f"runs double-double where it can) or integrator=taylor integrator.precision=double-double")
            raise ConfigError(f"accuracy={self.accuracy:g} is below the round-off that double precision accumulates "
                              f"on this scene (about {roundoff:.1g} over ~{steps:.0f} steps); ask for at least that")
        if extended is not None:  # double-double: its own round-off, its own tolerance, from the start
            method, chosen, roundoff = extended
        elif CALIBRATION * per_tol * chosen + roundoff > self.accuracy:  # leave room for the round-off
            chosen = (self.accuracy - roundoff) / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9)
        if extended is None:
            method = self._method(compiled, chosen)
        self.chosen = method  # what ran: more_accurate answers for it
        if tight_tol <= chosen and extended is None:  # the pilot's tight run is as accurate: continue from its end
            head = np.searchsorted(pilot_times, inside)  # the outputs inside the pilot
            rest = t_out[t_out >= t_pilot]
            tail = method.integrate(fun, np.concatenate([[t_pilot], rest]) if rest[0] > t_pilot else rest,
                                    tight.y[-1], progress, compiled)
            y = np.concatenate([tight.y[head], tail.y[-len(rest):]])
            final_stats = tail.stats
            n_steps = tail.stats.n_steps + tight.stats.n_steps
        else:
            solution = method.integrate(fun, t_out, y0, progress, compiled)
            y, final_stats, n_steps = solution.y, solution.stats, solution.stats.n_steps
        self.raw_predicted_error = per_tol * chosen  # before CALIBRATION and round-off: what the calibration measures
        self.choice = {
            "auto_method": method.name,
            "auto_tolerance": chosen,
            "auto_predicted_error": CALIBRATION * per_tol * chosen + roundoff,
            "auto_predicted_error_bounds": PREDICTION_MEANING,
            "auto_error_growth_exponent": growth,
            "auto_pilot_nfev": pilot_nfev,
            **self.chaos,
            **{f"auto_{k.removeprefix('integrator_')}": v for k, v in method.attributes().items()},
        }
        return Solution(t_out, y, IntegratorStats(
            nfev=final_stats.nfev + pilot_nfev, n_steps=n_steps, n_rejected=final_stats.n_rejected,
            wall_time=time.perf_counter() - start, njev=final_stats.njev, nlu=final_stats.nlu))

    def _extended(self, compiled: CompiledModel | None, per_tol: float,
                  roundoff: float) -> tuple[Integrator, float, float] | None:
        """(the double-double Taylor method, its tolerance, its round-off) that meets the accuracy where double
        precision cannot, or None when the model has no double-double kernel or even it cannot.

        The truncation error per unit tolerance is the pilot's (measured at its order; the double-double run takes
        the optimal, higher order for its tolerance, hence fewer and larger steps: no more error per unit
        tolerance); the round-off is double precision's estimate scaled by the ratio of the two unit round-offs."""
        if compiled is None:
            return None
        from gyrolab.kernels.taylor_dd import MIN_TOL
        from gyrolab.plugins.integrators.compiled_solvers import DOUBLE_DOUBLE, Taylor, TaylorDoubleDouble

        if TaylorDoubleDouble.refusal(compiled, self.system) is not None:
            return None
        roundoff_dd = roundoff * DOUBLE_DOUBLE_EPS / EPS
        if roundoff_dd > self.accuracy:
            return None
        tol = (self.accuracy - roundoff_dd) / (self.safety * CALIBRATION * per_tol) * (1 - 1e-9)
        tol = min(max(tol, MIN_TOL), MAX_TOLERANCE)
        if CALIBRATION * per_tol * tol + roundoff_dd > self.accuracy:
            return None
        return Taylor(tol=tol, precision=DOUBLE_DOUBLE), tol, roundoff_dd

    def _series(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, compiled: CompiledModel | None,
                start: float) -> Solution | None:
        """The first regime whose analytic series is predicted to meet the accuracy on this scene, or None."""
        if self.system is None or compiled is None or t_out[0] != 0.0 or compiled.built_in is None:
            return None  # the regimes' series describe the built-in torques only
        from gyrolab.contracts import registry
        from gyrolab.plugins.integrators.compiled_solvers import Taylor

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
                # A variant with a predicted error (a series order) comes from a regime whose series is built and
                # whose domain admits the scene: its start is cheap, so it goes first (most scenes miss the orbit,
                # and the domain check evaluates it again). Otherwise the domain check goes first: a refusal is
                # cheap where the orbit may not be (a shooting method).
                if not np.isfinite(estimate) and regime.check_domain(self.system):
                    continue  # outside the domain, or near its edge (warnings): no confidence in the series
                with np.errstate(all="ignore"):  # an orbit may evaluate to inf/nan: a miss
                    distance = float(np.max(np.abs(regime.initial_state(self.system)[:6] - y0[:6])))
                if not distance <= tolerance:
                    # Variants of one regime (series orders) approximate the same orbit, each predicted within
                    # accuracy/safety of it (series_candidates lists only those): the scene misses every one by
                    # at least distance − 2·accuracy/safety; MISS_MARGIN covers the prediction being an estimate.
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
            self.chosen = None  # an analytic series: more_accurate is the full model by a tight Taylor run
            self.choice = {"auto_method": f"regime {name}", "auto_predicted_error": predicted,
                           "auto_series_error_one_period": measured, "auto_check_nfev": truth.stats.nfev,
                           **regime.attributes()}
            return Solution(t_out, y, IntegratorStats(nfev=truth.stats.nfev, n_steps=0, n_rejected=0,
                                                      wall_time=time.perf_counter() - start))
        return None

    def _misses_orbits(self, base: Any, fun: RightHandSide, y0: np.ndarray, compiled: CompiledModel,
                       span: float) -> bool:
        """Whether the scene is certainly on none of the orbits ``base``'s variants describe, from the scene's own
        motion over one period: a necessary condition of the series check below, evaluated before any series
        is built (it would cost ~2 ms warm, ~0.4 s on a process's first call, on the many scenes that start on
        no regime's orbit).

        The check below takes a variant only when the scene starts within accuracy/(10·safety) of the variant's
        orbit (its start S(0)) and the variant stays within accuracy/safety of the scene's motion Φ over a window
        ending at its period T_S (all of the period once the span covers it); the variant is periodic,
        S(T_S) = S(0), hence |Φ(T_S) − y0| ≤ 1.1·accuracy/safety. The regime's ``period_spread`` bounds T_S to
        [T/spread, T·spread] around its cheap ``period`` T, and Φ is sampled on a grid there: T_S is within
        half a spacing h of a grid time, where Φ differs from Φ(T_S) by at most max|Φ'|·h/2. So a scene whose
        motion stays farther than 1.1·accuracy/safety + max|Φ'|·h/2 (+ the integration error) from y0 over
        the whole range cannot be taken, and the regime is skipped.
        """
        spread = getattr(base, "period_spread", None)
        if spread is None:
            return False
        from gyrolab.plugins.integrators.compiled_solvers import taylor_samples

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
               tau: float, previous: tuple[float, Solution] | None
               ) -> tuple[float, float, int, bool, tuple[float, Solution], tuple[float, Solution]]:
        """(raw predicted final error per unit tolerance, growth exponent q, evaluations, whether the pilot
        measured an error above round-off, the tight run and the loose run as (tolerance, solution)) from runs
        at τ and a tighter τ_t: the previous round's loose run when τ_t ≤ τ/10 (a re-centred or loosened round
        reuses it), else a new run at min(τ/100, accuracy/TIGHT_RATIO). The error at τ is then the runs' difference × τ/(τ − τ_t)."""
        loose = self._method(compiled, tau).integrate(fun, times, y0, None, compiled)
        if previous is not None and previous[0] <= tau / 10:
            tight_tol, tight = previous
            tight_nfev = 0
        else:
            # τ/100, or tighter where τ is held at MIN_TOLERANCE far above the final tolerance (~accuracy/1000): the
            # tight run must be at least as accurate as the final one to be its start
            tight_tol = min(tau * 1e-2, self.accuracy / TIGHT_RATIO)
            tight = self._method(compiled, tight_tol).integrate(fun, times, y0, None, compiled)
            tight_nfev = tight.stats.nfev
        final, slope = _fast(_error_growth, compiled)(loose.y, tight.y, times)
        # differences within a few hundred ulps are round-off, not a measurement of the truncation error
        measured = bool(final > 100 * EPS * max(1.0, *map(abs, y0)))
        # A non-symplectic method on a (near-)integrable motion drifts in energy linearly, hence in phase
        # quadratically: assume q = 2 unless the pilot shows faster growth (its early error is a plateau).
        growth = MIN_GROWTH if math.isnan(slope) else min(max(slope, MIN_GROWTH), MAX_GROWTH)
        per_tol = final / (tau - tight_tol) * (1.0 / self.pilot_fraction) ** growth
        self._pilot_steps = tight.stats.n_steps
        return per_tol, growth, loose.stats.nfev + tight_nfev, measured, (tight_tol, tight), (tau, loose)

    def attributes(self) -> dict[str, Any]:
        checked = {"auto_measured_error_before_recheck": list(self.measured_before)} if self.measured_before else {}
        return {"accuracy": self.accuracy, **self.choice, **checked}

    def tightened_for(self, measured_error: float) -> Auto | None:
        """Rule 11: when the measured error of the last run (``output.error_estimate``, on by default for auto)
        exceeds its recorded prediction, auto again with the method it ran made more accurate by the factor the
        measurement asks for (``RECHECK_MARGIN`` × measured / accuracy: at a fixed order the error is proportional
        to the tolerance), at most ``MAX_RECHECKS`` times, then one ConfigError sentence; else None. A measured
        error above the prediction but ``RECHECK_MARGIN`` times below the accuracy asked for keeps the run, and
        the recorded prediction is raised to ``RECHECK_MARGIN`` × the measurement. A regime's series whose
        measured error breaks its prediction is replaced by auto's integration.

        The prediction rests on the pilot (which sees only round-off when the pilot's stretch is shorter than a
        step: r0 = 32 over t = 0.25 at 1e-9 chose tol 1e-5 and predicted 2e-14 where the error was 5.7e-5) and on
        the amplification of one tangent run, whose growth on a chaotic scene scatters by up to e^±4 with any
        change of its steps (docs/performance.md); the measurement is the companion run's difference, within ~1 %
        of the error where truncation dominates. Over the extremes matrix and the reference scene at 1e-4 … 1e-13
        the measured error is at most 0.47× the prediction, so a scene that keeps its promise runs once."""
        predicted = self.choice.get("auto_predicted_error")
        if predicted is None or not measured_error > predicted:
            return None
        if RECHECK_MARGIN * measured_error <= self.accuracy:
            # the target is met by a margin, but not the recorded prediction: the measurement bounds the error now
            self.choice["auto_predicted_error"] = RECHECK_MARGIN * measured_error
            self.choice["auto_predicted_error_raised_by"] = "output.error_estimate: the measured error, times 3"
            return None
        method = self.chosen if self.chosen is not None else None
        factor = RECHECK_MARGIN * measured_error / self.accuracy
        finer = method.more_accurate(factor) if method is not None else None
        if finer is None and method is not None:
            finer = self._climb(method, factor)
        what = (f"the error estimate measures {measured_error:.2g} where auto predicted {predicted:.2g} "
                f"({self.choice.get('auto_method')})")
        if len(self.measured_before) >= MAX_RECHECKS or (method is not None and finer is None):
            reason = (f"after {MAX_RECHECKS} runs made more accurate {what}" if len(self.measured_before) >= MAX_RECHECKS
                      else f"{what}, and {method.name} cannot be made {factor:.2g}× more accurate")
            climb = "" if self.extended_precision else " or integrator.extended_precision=true"
            raise ConfigError(f"accuracy={self.accuracy:g} is not met on this scene: {reason}; ask for "
                              f"accuracy ≥ {RECHECK_MARGIN * measured_error:.1g} or a shorter time.end{climb}")
        again = type(self)(accuracy=self.accuracy, pilot_fraction=self.pilot_fraction, safety=self.safety,
                           extended_precision=self.extended_precision and (self.per_trajectory or None))
        again.measured_before = (*self.measured_before, measured_error)
        if finer is None:  # an analytic series: integrate instead
            again._no_series = True
        else:
            again._recheck = (finer[0], dict(self.choice))
        return again

    def _climb(self, method: Any, factor: float) -> tuple[Any, float, str] | None:
        """The next rung of the precision ladder for a recheck (``tightened_for``): a double Taylor run at its floor
        goes on in double-double (``extended_precision``, the default), ``factor`` times more accurate; else None."""
        from gyrolab.kernels.taylor_dd import MIN_TOL
        from gyrolab.plugins.integrators.compiled_solvers import DOUBLE, DOUBLE_DOUBLE, Taylor

        if not (self.extended_precision and isinstance(method, Taylor) and method.precision == DOUBLE):
            return None
        tol = max(method.tol / factor, MIN_TOL)
        return (Taylor(tol=tol, precision=DOUBLE_DOUBLE), 1.0,
                f"taylor double-double at tol {tol:.3g}: double precision's floor reached")

    def _run_recheck(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray, progress: ProgressCallback | None,
                     compiled: CompiledModel | None, start: float) -> Solution:
        """The earlier run's method made as much more accurate as its measured error asked (``tightened_for``)."""
        method, earlier = self._recheck
        solution = method.integrate(fun, t_out, y0, progress, compiled)
        self.chosen = method
        settings = {f"auto_{k.removeprefix('integrator_')}": v for k, v in method.attributes().items()}
        self.choice = {**earlier, **settings, "auto_method": method.name,
                       "auto_tolerance": settings.get("auto_tol", settings.get("auto_rtol", earlier.get("auto_tolerance"))),
                       # error ∝ tolerance at a fixed order: the earlier measurement scaled down, checked again by
                       # the measurement of this run
                       "auto_predicted_error": self.accuracy,
                       "auto_measured_error_before_recheck": list(self.measured_before)}
        self.choice.pop("auto_predicted_error_raised_by", None)
        stats = solution.stats
        return Solution(t_out, solution.y, IntegratorStats(
            nfev=stats.nfev, n_steps=stats.n_steps, n_rejected=stats.n_rejected,
            wall_time=time.perf_counter() - start, njev=stats.njev, nlu=stats.nlu))

    def more_accurate(self, factor: float):
        """Rule 9 for the method it ran (after ``integrate``): that method ``factor`` times more accurate; for an
        analytic series, the full model by the compiled Taylor method at tol 1e-15 (the series' check run)."""
        if not self.choice:
            return None
        if self.chosen is None:
            from gyrolab.plugins.integrators.compiled_solvers import Taylor

            return Taylor(tol=1e-15), 1.0, f"compiled Taylor at tol 1e-15 against auto's {self.choice['auto_method']}"
        finer = self.chosen.more_accurate(factor)
        if finer is None:
            return None
        return finer[0], finer[1], f"auto's choice, {finer[2]}"

    def choose_batch_method(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray,
                            params: np.ndarray) -> tuple[Integrator, dict[str, Any]]:
        """The method and tolerance for a batch: the single-run choice on a few trajectories, the tightest.

        The sample is the first trajectory, the one with the largest state and the one whose parameters
        lie farthest from the batch's mean (up to AUTO_SAMPLE distinct ones). Each runs the pilot and final
        run; the batch then runs the chosen method at the smallest tolerance chosen. A trajectory harder
        than every sampled one may miss the accuracy: sample it (pass it first) when you know it.
        """
        from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor
        from gyrolab.plugins.integrators.step_guard import compiled_rhs

        P = params
        spread = np.abs(P - P.mean(axis=0)).max(axis=1) if len(P) > 1 else np.zeros(1)
        sample = list(dict.fromkeys([0, int(np.argmax(np.abs(y0s).max(axis=1))), int(np.argmax(spread))]))[:AUTO_SAMPLE]
        choices = []
        for j in sample:
            single = type(self)(accuracy=self.accuracy, pilot_fraction=self.pilot_fraction, safety=self.safety,
                                extended_precision=False)  # the vectorised kernels run in double precision
            model = CompiledModel(compiled.model, P[j])
            single.integrate(compiled_rhs(model), times, y0s[j], None, model)
            choices.append(single.choice)
        choice = min(choices, key=lambda c: c["auto_tolerance"])
        tol = float(choice["auto_tolerance"])
        method = Taylor(order=choice["auto_order"], tol=tol) if choice["auto_method"] == Taylor.name \
            else DOP853Numba(rtol=tol, atol=tol)
        settings = {"accuracy": self.accuracy,
                    **{k: v.item() if isinstance(v, np.generic) else v for k, v in choice.items()},
                    "auto_sampled_trajectories": len(sample)}
        self.choice = {k: v for k, v in settings.items() if k != "accuracy"}
        return method, settings

    def integrate_batch(self, compiled: CompiledModel, times: np.ndarray, y0s: np.ndarray, params: np.ndarray,
                        failures: str) -> BatchSolution:
        """The batch's choice (``choose_batch_method``), then that method's kernel; the wall time includes the pilot."""
        start = time.perf_counter()
        method, settings = self.choose_batch_method(compiled, times, y0s, params)
        solution = method.integrate_batch(compiled, times, y0s, params, failures)
        solution.wall_time = time.perf_counter() - start
        solution.settings = settings
        return solution


def _amplified(per_tol: float, growth: float, factor: float, fraction: float, margin: float) -> float:
    """The pilot's predicted final error per unit tolerance, raised where the motion amplifies errors faster than
    the pilot's power law: an error E present at the pilot's end grows by up to ``factor`` (the tangent flow's
    growth after the pilot, ``amplification``), and the 1/fraction − 1 later stretches each commit as much again
    at most, so the final error is at most E · factor / fraction, against E · (1/fraction)^growth extrapolated.
    Beyond the pilot's largest power law (a chaotic scene) the factor carries ``margin``: it is measured along one
    numerical trajectory, which a chaotic flow lets scatter."""
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
