"""A measured error for the stored trajectory (``output.error_estimate``): a companion run on the same output times.

A tolerance is not an error, and a recorded prediction is only a prediction; what a user can check is a measurement.
The companion is the method that ran made more accurate by a known factor, as the method itself says
(``Integrator.more_accurate``, rule 9): ``TIGHTER`` times smaller tolerances, or half the step and Richardson's factor
(a fixed-step run is measured against the compiled Taylor method at its floor first, where that run bounds its own
error ``FLOOR_COMPANION_MARGIN`` times below the difference: ``_floor_companion``); an analytic series (``auto``) is
measured against the compiled Taylor method at tol 1e-15. At a method's floor the compiled Taylor method at tol 1e-16
stands in when the scene has a compiled model. A double Taylor run near that floor errs mostly by round-off, which
another double run shares: the rung above's tolerance at the run's order measures it (``climbed``), the Taylor
method with a double-double head (``HEAD_ORDERS``), or in double-double on a motion that amplifies perturbations more
than ``HEAD_COMPANION_GROWTH``; two double companions only for a model the rung above cannot run (``_double_pair``).
A run with a double-double head of its own measured its round-off and may stand on its own estimate (``_headed``). On
by default for the integrators that choose their method (``output.error_estimate: null``); ``true``/``false`` choose
it for any integrator. The audits behind these rules:
docs/integrators.md.

Stored as ``error_estimate_omega`` (ω's max-norm error at each output time, in ω's units) and
``error_estimate_attitude`` (the direction cosines') for systems whose state starts with ω; as ``error_estimate``
(the whole state's) for other systems.
"""

from __future__ import annotations

import functools
import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from gyrolab.accuracy.amplification import EPS, PILOT_FRACTION, growth_of
from gyrolab.accuracy.calibration import (CHAOS_MARGIN, DOUBLE_DOUBLE_BELOW,
                                         FLOOR_COMPANION_MARGIN, HEAD_COMPANION_GROWTH, HEAD_ORDERS, HEAD_WALK,
                                         ROUNDOFF_MARGIN, TIGHTER)
from gyrolab.kernels.model import rounding_moved
from gyrolab.contracts.integrator import (CHOOSES_METHOD, COMPILED_MODEL, PRECISIONS, PREFERS_COMPILED_MODEL,
                                          OwnEstimate)
from gyrolab.plugins.integrators.compiled_solvers import Taylor, TaylorDoubleDouble

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Companion:
    integrator: Any
    scale: float  # error of the stored run ≈ scale · |y − y_companion|
    how: str
    #: the integrator class whose model it borrows too (a double-double head: the rung above's series), whose refusal
    #: applies to it
    borrows: Any = None


def wanted(scene: Any) -> bool:
    """Whether the scene's run carries an error estimate: ``output.error_estimate`` true/false, or by default
    (null) for the integrators that choose their method for a target accuracy (CHOOSES_METHOD: ``auto``)."""
    choice = (scene.config.get("output") or {}).get("error_estimate")
    if choice is None:
        return scene.integrator.supports(CHOOSES_METHOD)
    return bool(choice)


def companion(method: Any, has_compiled: bool, round_off: bool = False, growth: float = math.inf) -> Companion | None:
    """The more accurate run that measures the run of ``method`` (its ``more_accurate``, rule 9 of the contract;
    else the compiled Taylor method at its floor when the scene has a compiled model; else, for a run that is itself
    the double-precision Taylor method near that floor, the method one rung up the precision ladder), or None.
    ``round_off``: the run's own estimate found its round-off not small (``one_pass``), which a double companion
    shares: a double Taylor run is then measured as near its floor (one rung up).
    ``growth``: how much the motion amplified perturbations over the run, as its own pass measured it (with the
    chaos margin): one rung up is the Taylor method with a double-double head (``HEAD_ORDERS``) up to
    ``HEAD_COMPANION_GROWTH``, the whole series in double-double beyond (the head's round-off, ~10⁻⁴ of a double
    run's, grows with the motion's amplification too: on the chaotic top over t = 200, amplified ~3·10¹⁰, the head
    companion ended ~10⁷ ulps off, benchmarks/companion_head.py)."""
    taylor = _double_taylor(method) if has_compiled else None
    finer = method.more_accurate(TIGHTER)
    if finer is not None and (taylor is None or (taylor.tol / TIGHTER >= DOUBLE_DOUBLE_BELOW and not round_off)):
        return Companion(*finer)
    if method.precision != PRECISIONS[0]:
        # above double precision a double stand-in would measure its own error, not the run's (docs/integrators.md:
        # the gyrostat audit's scene 25)
        return _tightest(method)
    if not has_compiled:
        return None
    if taylor is None:
        return Companion(Taylor(tol=Taylor.TOLERANCE_FLOOR), 1.0, f"compiled Taylor at tol {Taylor.TOLERANCE_FLOOR:g} "
                         f"({method.name} cannot be made {TIGHTER:g}× more accurate)")
    # a double Taylor run near the floor errs mostly by round-off, which another double run shares, also one at
    # another order with its rounded numbers moved (two such agreed within 6.8e-14 where both were 3e-13 from real128:
    # audit seed 13, scene 55; docs/integrators.md, "Double companions retired"): the rung above's tolerance, with only
    # the state and the series' first HEAD_ORDERS orders in double-double: its round-off that of the terms beyond,
    # thousands of times below a double run's, in ~1/6 of double-double's time (reference scene, tol 1e-18: within an
    # ulp of the state, 3.1 ms against 17.6); at the run's order, where the error is proportional to the tolerance (at
    # its own, higher, it measured seed 17's worst output time 0.54x and seed 13's 0.65x, at the run's 0.80x and
    # 0.92x, for ~25 % more time at ε = 1e-11 … 1e-13 on the reference scene)
    rung = taylor.climbed(TIGHTER)[0]
    up = Taylor(order=rung.order, tol=rung.tol, head=HEAD_ORDERS) if growth <= HEAD_COMPANION_GROWTH else rung
    how = (f"compiled Taylor at tol {up.tol:.3g}, same order, " +
           (f"its state and first {HEAD_ORDERS} orders in double-double" if up is not rung else "in double-double") +
           f" ({method.name} runs the Taylor method near double precision's floor)")
    return Companion(up, 1.0, how, borrows=type(rung))


@dataclass(frozen=True)
class Comparison:
    """A run against its companion: ``difference`` (the estimated error of every stored component at every output
    time, None when no companion could run) and the dataset attributes saying how (or why not). ``Scene.run``
    reads ``max_error`` before the dataset is assembled (rule 11) and passes ``variables`` to ``build_dataset``,
    which puts them in while assembling: inserting into a built dataset aligns and merges, ~0.4 ms each."""

    difference: np.ndarray | None
    attrs: dict[str, Any]  # error_estimate_method says how (or why not)
    #: the run's stored states (to tell whether a dataset's ω is their first three components)
    y: np.ndarray | None = None

    @property
    def max_error(self) -> float | None:
        """The largest estimated error over every component and output time (None: not measured)."""
        return None if self.difference is None else float(np.max(self.difference))

    def variables(self, stored: dict[str, xr.Variable]) -> tuple[dict[str, xr.Variable], dict[str, Any]]:
        """(variables, attributes) for the dataset whose trajectory variables are ``stored`` (read to tell whether
        the state starts with ω: ω's error and the attitude's are then stored apart)."""
        attrs = dict(self.attrs)
        if self.difference is None:
            return {}, attrs
        difference = self.difference
        omega = stored.get("omega")
        # (compared transposed: numpy then walks ω's columns, which a run dataset stores contiguous: 3× faster)
        if omega is not None and omega.shape == (len(difference), 3) and bool((omega.values.T == self.y[:, :3].T).all()):
            parts = {"omega": (difference[:, :3], omega.attrs.get("units", "1"), "angular velocity ω"),
                     "attitude": (difference[:, 3:], "1", "direction cosines (γ, and α where carried)")}
        else:  # a state whose layout this module does not know: one max-norm over all of it
            parts = {"": (difference, "1", "state (model units)")}
        variables = {}
        for part, (values, units, what) in parts.items():
            # the max-norm over the part's components, column by column: numpy reduces a short last axis row by
            # row (~0.1 ms for 3,001 × 3, 15× the time of two np.maximum over columns)
            series = functools.reduce(np.maximum, (values[:, k] for k in range(values.shape[1])))
            key = f"error_estimate_{part}" if part else "error_estimate"
            variables[key] = xr.Variable("time", series, {
                "units": units, "long_name": f"estimated max-norm error of the stored {what} at each output time",
                "comment": attrs["error_estimate_method"]}, fastpath=True)
            attrs[f"error_estimate_max_{part}" if part else "error_estimate_max"] = float(series.max())
        return variables, attrs


def compare(scene: Any, method: Any, y: np.ndarray, wall_time: float, check: Any = None,
            own: OwnEstimate | None = None) -> Comparison:
    """Run the companion of ``method``'s run of ``scene`` (stored states ``y``, integration time ``wall_time``; with
    ``check``, a run that is no integration, measured against ``check``) and compare: the measured error estimate,
    or why none is available. ``own``: the run's error estimated in the same pass (C8), taken instead of a companion
    where the run's round-off is ``ROUNDOFF_MARGIN`` times below it (``one_pass``)."""
    one = None
    if own is not None and own.error is not None:
        taylor = _double_taylor(method)
        # near double precision's floor round-off rivals the truncation error, erratically (audit seed 2026, scene 82
        # at 1e-10: r0 = 12, tol 1.6e-14, 6.1e-11 from real128 where the pass measured 3.8e-11 and its round-off
        # bound said 5.8e-12; at tol 1e-13 the pass measured 3.61e-10 of 3.62e-10): there the bound is not trusted, a
        # twin run measures the round-off (``one_pass``)
        near_floor = taylor is not None and taylor.tol / TIGHTER < DOUBLE_DOUBLE_BELOW
        twin = None if taylor is None or scene.compiled_model is None else lambda: taylor.integrate(
            scene.rhs, scene.times, scene.system.initial_state(), None, rounding_moved(scene.compiled_model))
        one = one_pass(own, y, scene.times, twin, near_floor, wall_time)
        if isinstance(one, Comparison):
            return one
    compiled_model = scene.compiled_model
    growth = math.inf if own is None else _growth(own, float(scene.times[-1] - scene.times[0]) or 1.0)
    if check is None:
        pick = companion(method, compiled_model is not None, isinstance(one, str), growth)
    else:
        pick = Companion(check, 1.0, f"{check.name} ({', '.join(f'{k} {v}' for k, v in check.attributes().items())}) "
                                     "against the analytic series")
    name = getattr(method, "name", type(method).__name__)
    if pick is None:
        return _unavailable(f"integrator {name!r} already runs at the compiled Taylor method's floor in double "
                            "precision (nothing more accurate to compare with)" if _double_taylor(method) else
                            f"integrator {name!r} cannot be made {LEAST_TIGHTER:g}× more accurate in {method.precision} "
                            "precision (nothing more accurate to compare with)" if method.precision != PRECISIONS[0]
                            else f"integrator {name!r} exposes no tolerance or step to tighten and the scene has no "
                            "compiled model for the Taylor method")
    companion_model, refusal = None, None
    if pick.integrator.supports(COMPILED_MODEL) or pick.integrator.supports(PREFERS_COMPILED_MODEL):
        # the companion's refusal hook prepares the model (a plugin torque's Taylor kernel compiled), or says when
        # it cannot run it
        companion_model = compiled_model
        refusal = None if compiled_model is None else pick.integrator.refusal(compiled_model, scene.system) or (
            pick.borrows.refusal(compiled_model, scene.system) if pick.borrows is not None else None)
        if refusal:
            taylor = _double_taylor(method)
            return _unavailable(f"the companion ({pick.how}) {refusal}") if taylor is None or check is not None \
                else _double_pair(scene, taylor, y, wall_time, f"the companion one rung up {refusal}"
                                  + ("" if one is None else f"; {one}"))
    if check is None and not getattr(method, "adaptive", True) and compiled_model is not None:
        floor = _floor_companion(scene, y, wall_time)
        if floor is not None:
            return floor
    start = time.perf_counter()
    y0 = scene.system.initial_state()
    y = np.asarray(y, dtype=float)
    how = pick.how
    other = pick.integrator.integrate(scene.rhs, scene.times, y0, None, companion_model).y
    spent = time.perf_counter() - start
    how = how if one is None else f"{how} ({one})"
    attrs = {"error_estimate_method": how, "error_estimate_cost_ratio": float(spent / max(wall_time, 1e-9))}
    return Comparison(pick.scale * np.abs(y - other), attrs, y)


def _double_pair(scene: Any, taylor: Taylor, y: np.ndarray, wall_time: float, refusal: str) -> Comparison:
    """A double Taylor run near the floor of a model without a double-double series (a plugin torque it cannot
    evaluate; ``refusal`` says why): two double companions at tol/``TIGHTER``, the second at another order with the
    model's rounded numbers moved (``rounding_moved``), measure it where their disagreement is ``ROUNDOFF_MARGIN``
    times below the error measured, else nothing does. The weaker measure, kept where the rung above cannot run: two
    such companions may share an error their disagreement does not show (audit seed 13, scene 55, with a built-in
    torque: they agreed within 6.8e-14 where both were 3e-13 from real128, and measured 0.48× the run's error at one
    output time)."""
    from gyrolab.kernels.taylor import MAX_ORDER

    tol = max(taylor.tol / TIGHTER, Taylor.TOLERANCE_FLOOR)
    if tol >= taylor.tol:  # a double companion no tighter than the run measures nothing of it
        return _unavailable(f"{refusal}, and a double companion cannot be tighter than the run (tol {taylor.tol:.3g})")
    start = time.perf_counter()
    other_order = taylor.order + 2 if taylor.order + 2 <= MAX_ORDER else taylor.order - 2
    y0, model = scene.system.initial_state(), scene.compiled_model
    first = Taylor(order=taylor.order, tol=tol).integrate(scene.rhs, scene.times, y0, None, model).y
    second = Taylor(order=other_order, tol=tol).integrate(scene.rhs, scene.times, y0, None, rounding_moved(model)).y
    difference = np.abs(np.asarray(y, dtype=float) - first)
    roundoff, measured = float(np.max(np.abs(first - second))), float(np.max(difference))
    if not ROUNDOFF_MARGIN * roundoff <= measured:
        return _unavailable(f"{refusal}, and two double companions at tol {tol:.3g} disagree by {roundoff:.2g}, "
                            f"round-off not small against {measured:.2g}")
    return Comparison(difference, {
        "error_estimate_method": f"compiled Taylor at tol {tol:.3g}, same order (near double precision's floor, "
                                 f"{refusal}: a second double companion at order {other_order} disagrees with it by "
                                 f"{roundoff:.2g}, ≥ {ROUNDOFF_MARGIN:g}× below the error measured)",
        "error_estimate_cost_ratio": float((time.perf_counter() - start) / max(wall_time, 1e-9))}, y)


def _floor_companion(scene: Any, y: np.ndarray, wall_time: float) -> Comparison | None:
    """A fixed-step run measured against the compiled Taylor method at its floor, its own error bounded in the same
    pass (the truncation it measures, and its round-off amplified by the growth it measures: with a double-double head
    where the model has that series, whose round-off it measures and which is thousands of times smaller, else a
    random walk of an ulp a step), where that bound is ``FLOOR_COMPANION_MARGIN`` times below their difference; else
    None (Richardson's half step measures). Richardson assumes the error ∝ h^p at every output time: a fast top at
    rk4's step 0.01 (ω·h = 0.2) was measured 0.3× its error at one time, and a lie_poisson run at step 0.002 whose
    round-off rivals its truncation 0.39× (audit seeds 7 and 11); the Taylor floor, far more accurate there, measures
    both, and costs less than the run again at half the step. None also where the model has no Taylor coefficients."""
    model = scene.compiled_model
    if Taylor.refusal(model, scene.system) is not None:
        return None
    start = time.perf_counter()
    headed = TaylorDoubleDouble.refusal(model) is None
    # (with a head, tol 1e-18: its round-off no longer the floor, the tolerance is; benchmarks/companion_head.py's)
    floor = Taylor(tol=1e-18, head=HEAD_ORDERS) if headed else Taylor(tol=Taylor.TOLERANCE_FLOOR)
    run = floor.integrate(scene.rhs, scene.times, scene.system.initial_state(), None, model, estimate=True)
    own = run.estimate
    scale = max(1.0, float(np.max(np.abs(run.y))))
    roundoff = HEAD_WALK * EPS * own.roundoff if headed else EPS * scale * math.sqrt(1.0 + own.steps)
    growth = _growth(own, float(scene.times[-1] - scene.times[0]) or 1.0)
    bound = max(float(np.max(np.abs(own.error))), roundoff * growth, 0.5 * EPS * scale)
    difference = np.abs(np.asarray(y, dtype=float) - run.y)
    if not FLOOR_COMPANION_MARGIN * bound <= float(np.max(difference)):
        return None
    head = f", its first {HEAD_ORDERS} orders in double-double" if headed else ""
    return Comparison(difference, {
        "error_estimate_method": f"compiled Taylor at tol {floor.tol:g}{head}, whose own error is bounded by "
                                 f"{bound:.2g}, ≥ {FLOOR_COMPANION_MARGIN:g}× below the difference (a fixed-step run: "
                                 "not Richardson's half step, which assumes the error ∝ h^p at every output time)",
        "error_estimate_cost_ratio": float((time.perf_counter() - start) / max(wall_time, 1e-9))}, y)


def _growth(own: OwnEstimate, span: float) -> float:
    """How much the motion amplified perturbations over a run, as the run's own pass measured it (e^{max ln|δ|}),
    times ``CHAOS_MARGIN`` where that growth is chaos (one numerical trajectory's growth scatters)."""
    chaos = CHAOS_MARGIN if growth_of(own, span).chaotic(PILOT_FRACTION) else 1.0
    return math.exp(min(float(own.log_growth[-1]), 700.0)) * chaos


def _unavailable(why: str) -> Comparison:
    reason = f"not available: {why}"
    log.warning("output.error_estimate: %s", reason)
    return Comparison(None, {"error_estimate_method": reason})


#: a companion this many times more accurate at least: its own error then adds at most 1/(k − 1) to the estimate
LEAST_TIGHTER = 4.0


def _tightest(method: Any) -> Companion | None:
    """The method made as much more accurate as it can be, ``TIGHTER`` times and then half as much at each try, last
    ``LEAST_TIGHTER``; its difference scaled by k/(k − 1) below ``TIGHTER`` (the companion's own error, 1/k of the
    run's, may cancel part of it). None when not even ``LEAST_TIGHTER`` times is possible: then nothing measures
    the run."""
    factor = TIGHTER
    while True:
        finer = method.more_accurate(factor)
        if finer is not None:
            integrator, scale, how = finer
            return Companion(integrator, scale * factor / (factor - 1.0) if factor < TIGHTER else scale, how)
        if factor == LEAST_TIGHTER:
            return None
        factor = max(factor / 2.0, LEAST_TIGHTER)


def _double_taylor(method: Any) -> Any:
    """``method`` when it is the double-precision Taylor method (a method with a rung above it, ``climbed``), whose
    error near its floor is mostly round-off; else None."""
    return method if method.precision == PRECISIONS[0] and method.climbed(1.0) is not None else None


def one_pass(own: OwnEstimate, y: np.ndarray, times: np.ndarray, twin: Any = None, near_floor: bool = False,
             wall_time: float = 0.0) -> Comparison | str:
    """The run's own estimate (C8) as the measured error, or why not (a companion measures instead). The linearised
    error equation has no sign for round-off, so the estimate stands only where the run's round-off is
    ``ROUNDOFF_MARGIN`` times below the largest error it measures, as a bound or a twin run says:

    * the bound, free: a random walk of one ulp of the state per step, amplified by the growth of perturbations the
      same pass measured (times ``CHAOS_MARGIN`` on a chaotic scene, as ``auto`` predicts it). (Amplified on regular
      scenes too: a slow top near its inverted rest, ``tests/helpers/accuracy.ROUND_OFF``, grows perturbations e^9
      without chaos and its round-off ended 2.7e-12 away where a walk unamplified said 3e-15.) Not trusted near the
      floor (``near_floor``: a companion tol below ``DOUBLE_DOUBLE_BELOW``), where it missed the round-off 4×;
    * else the twin (``twin()``: the same method on the model with its rounded numbers moved by an ulp,
      ``rounding_moved``, so the same truncation error and round-off of its own), whose distance from the run
      measures the round-off, run where the walk unamplified is ``ROUNDOFF_MARGIN`` times below the error (else it
      could not be trusted either) and the bound at most the error: one run where the companions near the floor are
      two, or double-double's ~20. The twin moves only the rounded numbers it can tell, alternately up and down, so it
      may see less of the model's rounding than there is: with the bound up to 3.3× above the error it passed one run
      that ended 2.1× its estimate away (benchmarks/roundoff_margin.py, seeds 5 and 11: 240 of 1,227 runs trusted, at
      every output time 0.57–2.8× the actual error against real128; the bound alone trusts ~113).

    Each output time's estimate then adds, in quadrature, the walk's typical size, unamplified: on the reference scene
    the bound is ~100× the round-off two double companions measure, and added it made early times' estimates 3×
    the actual error. A run with a double-double head measured its round-off itself (``_headed``)."""
    span = float(times[-1] - times[0]) or 1.0
    growth = _growth(own, span)
    scale = max(1.0, float(np.max(np.abs(y))))
    if own.roundoff is not None:
        return _headed(own, y, times, span, growth, scale)
    walk = (EPS * scale) * np.sqrt(1.0 + own.steps * ((times - times[0]) / span))
    bound = float(walk[-1] * growth)
    error = np.square(own.error)  # (in place below: np.hypot took ~0.13 ms for 3,001 × 9)
    measured = math.sqrt(float(np.max(error)))
    # (no error_estimate_cost_ratio for the bound: the estimate's work is inside the run's steps, not a run of its own)
    attrs = {"error_estimate_method": f"{own.how}, plus double precision's round-off in quadrature (a random walk "
                                      f"of one ulp a step: {float(walk[-1]):.2g} at the end; bounded by {bound:.2g})"}
    if near_floor or not ROUNDOFF_MARGIN * bound <= measured:
        why = (f"the one-pass estimate, {measured:.2g}, is not {ROUNDOFF_MARGIN:g}× above a bound on the run's "
               f"round-off, {bound:.2g}, which it does not see") if not near_floor else \
            "the run's tolerance is near double precision's floor, where round-off rivals truncation"
        if twin is None or not (ROUNDOFF_MARGIN * float(walk[-1]) <= measured and bound <= measured):
            return why
        start = time.perf_counter()
        roundoff = float(np.max(np.abs(twin().y - y)))
        if not ROUNDOFF_MARGIN * roundoff <= measured:
            return f"{why}; a twin run with the rounded numbers moved differs by {roundoff:.2g}, not small against it"
        attrs = {"error_estimate_method": f"{own.how}, plus double precision's round-off in quadrature (a random walk "
                                          f"of one ulp a step: {float(walk[-1]):.2g} at the end; a twin run with the "
                                          f"model's rounded numbers moved by an ulp differs by {roundoff:.2g}, "
                                          f"≥ {ROUNDOFF_MARGIN:g}× below the error measured)",
                 "error_estimate_cost_ratio": float((time.perf_counter() - start) / max(wall_time, 1e-9))}
    error += np.square(walk)[:, None]
    return Comparison(np.sqrt(error, out=error), attrs, y)


def _headed(own: OwnEstimate, y: np.ndarray, times: np.ndarray, span: float, growth: float,
            scale: float) -> Comparison | str:
    """``one_pass`` for a run with a double-double head (``Taylor(head=...)``), which measured its round-off: the ulps
    of each step's terms computed in double, added up (``OwnEstimate.roundoff``), at most ``HEAD_WALK`` times that,
    amplified by the growth of perturbations (and ``CHAOS_MARGIN`` on a chaotic scene), plus the outputs' own rounding
    (half an ulp of the state at each output, not carried, so not amplified). No twin: the model's numbers derived in
    double reach only those terms. The estimate stands where both are ``ROUNDOFF_MARGIN`` times below it; each output
    time adds, in quadrature, the round-off's share up to it (unamplified, without the margin: audit seed 2026, scene
    82, with the margin the estimate was 4.4× the actual error) and the output's rounding."""
    roundoff = EPS * own.roundoff
    walk = roundoff * ((times - times[0]) / span)
    stored = 0.5 * EPS * scale
    bound = max(HEAD_WALK * roundoff * growth, stored)
    error = np.square(own.error)
    measured = math.sqrt(float(np.max(error)))
    if not ROUNDOFF_MARGIN * bound <= measured:
        return (f"the one-pass estimate, {measured:.2g}, is not {ROUNDOFF_MARGIN:g}× above a bound on the run's "
                f"round-off, {bound:.2g} (its double-double head's measured round-off amplified, or its outputs' "
                f"rounding)")
    error += (np.square(walk) + stored * stored)[:, None]
    return Comparison(np.sqrt(error, out=error), {"error_estimate_method": (
        f"{own.how}, plus the round-off in quadrature (a double-double head: the ulps of each step's terms computed "
        f"in double, added up, {float(walk[-1]):.2g} at the end; bounded by {bound:.2g})")}, y)


def headed(method: Any, compiled: Any) -> Any:
    """``method`` with a double-double head (``HEAD_ORDERS``) where it is the double-precision Taylor method near its
    floor (a companion tol below ``DOUBLE_DOUBLE_BELOW``) and the model has a double-double series: there a tighter
    tolerance gains nothing against the round-off that dominates (audit seed 2026, scene 82 at 1e-11: double runs at
    tol 7e-15 … 1e-16 measured 7.2e-11, 1.9e-11, 1.2e-11 and the target was refused; with the head, one rerun
    measured 5.8e-13, 5.77e-13 from double-double). Else ``method``."""
    taylor = _double_taylor(method)
    if taylor is None or taylor.head or taylor.tol / TIGHTER >= DOUBLE_DOUBLE_BELOW or compiled is None or \
            TaylorDoubleDouble.refusal(compiled) is not None:
        return method
    return Taylor(order=taylor.order, tol=taylor.tol, head=HEAD_ORDERS)
