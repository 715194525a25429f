"""Is a monitored invariant really conserved? Its drift against what the integration error explains.

A scene monitors an invariant because its forces claim it (``Force`` rules 5 and 6); this is the check of the
run itself, made where the drifts are computed (``gyrolab.output.dataset``). An invariant ``I`` is flagged
*violated* when

    max_t |I(t) − I(0)|  >  S · max(FLOOR, E_tol, E_step, E_kin),      S = max(1, max_t |I(t)|)

with E_tol the adaptive method's tolerance summed over its steps, E_step a fixed-step method's global error and
E_kin ``EXPLAINED`` × the drift of the kinematic invariants, which every torque conserves (the yardstick, never
flagged themselves); each term and why: docs/plugins.md, "After the run". A run whose integrator gives none of
them is not judged.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

#: invariants every torque conserves (the kinematics of the frame): the measure of the integration error
KINEMATIC = ("gamma_norm", "frame_error")
FLOOR = 1e-6
EXPLAINED = 1e3
#: attributes that give an adaptive method's tolerance (the largest is used)
TOLERANCE_ATTRIBUTES = ("integrator_rtol", "integrator_atol", "integrator_tol", "auto_tolerance")


def explained_error(attrs: Mapping[str, Any], adaptive: bool, kinematic_drift: float | None,
                    span: float) -> float | None:
    """The relative error the integration explains (max of E_tol, E_step, E_kin, FLOOR), or None: not judged."""
    bounds = []
    if adaptive:
        tolerances = [float(attrs[k]) for k in TOLERANCE_ATTRIBUTES if k in attrs]
        if tolerances:
            bounds.append(EXPLAINED * max(tolerances) * max(1.0, float(attrs.get("integrator_n_steps", 1))))
    else:
        step, rate = attrs.get("integrator_step"), attrs.get("sampling_fastest_rate")
        if step is not None and rate is not None:
            order = float(attrs.get("integrator_order", 2))
            bounds.append((float(step) * float(rate)) ** order * max(1.0, float(rate) * span))
    if kinematic_drift is not None:
        bounds.append(EXPLAINED * kinematic_drift)
    return max(FLOOR, *bounds) if bounds else None


def violated_invariants(extremes: Mapping[str, tuple[float, float, float]], invariants: Iterable[str],
                        attrs: Mapping[str, Any], adaptive: bool, span: float) -> dict[str, tuple[float, float]]:
    """{name: (max drift, allowed drift)} of the monitored invariants whose drift the integration does not
    explain (module docstring); ``extremes`` holds each invariant's (first, largest, smallest) value."""
    invariants = list(invariants)
    kinematic = [max_drift(*extremes[k]) for k in KINEMATIC if k in invariants and k in extremes]
    error = explained_error(attrs, adaptive, max(kinematic) if kinematic else None, span)
    if error is None:
        return {}
    out = {}
    for name in invariants:
        if name in KINEMATIC or name not in extremes:
            continue
        allowed = error * max(1.0, extremes[name][1], -extremes[name][2])  # max |v|
        drift = max_drift(*extremes[name])
        if drift > allowed:
            out[name] = (drift, allowed)
    return out


def max_drift(first: float, high: float, low: float) -> float:
    """max |v − v0| from the first, largest and smallest value: subtracting v0 is monotone in floating point, so this
    is the value of np.max(np.abs(values - values[0])) without its two temporaries."""
    return max(high - first, first - low)


def violation_sentence(name: str, drift: float, allowed: float) -> str:
    return (f"invariant {name!r} drifts by {drift:.3g}, more than the {allowed:.3g} the integration error explains; "
            "a force's claim (its potential or preserves_area_integral) is likely false, so it is flagged "
            "violated in run.nc and not drawn as conserved")
