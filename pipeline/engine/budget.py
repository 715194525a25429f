"""Requests gyrolab refuses before anything runs: tolerances outside (0, 1), and plainly infeasible work
(the budget: docs/configs.md, "Your own configs"; ``allow_large=true`` lifts it).
"""

from __future__ import annotations

import math
from typing import Any

from hydra.core.override_parser.types import ChoiceSweep, RangeSweep

from gyrolab.engine.scene import AUTO, AUTO_MAX_SAMPLES
from gyrolab.engine.schemas import keys_with
from gyrolab.errors import ConfigError

MAX_STATE_BYTES = 2 * 1024**3
MAX_STEPS = 1_000_000_000
#: an optimistic cost of one step (fast compiled kernels), used to say how long a request would take
SECONDS_PER_STEP = 1e-6
RADIANS_PER_STEP = 2.0
#: tolerance-like parameters, relative to the state's scale: each must lie in (0, 1) (the schemas' TOLERANCE fields)
TOLERANCES = keys_with("tolerance")
ESCAPE = "set allow_large=true to run it anyway"


def check_tolerances(plain: dict[str, Any]) -> None:
    """ConfigError for a tolerance (integrator.rtol, atol, tol, accuracy; top-level accuracy) outside (0, 1)."""
    items = [(f"integrator.{k}", v) for k, v in (plain.get("integrator") or {}).items() if k in TOLERANCES]
    items.append(("accuracy", plain.get("accuracy")))
    for where, value in items:
        if value is None or isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if not 0 < value < 1:
            raise ConfigError(f"{where}={value:g} is outside (0, 1); a tolerance must be positive and below 1, "
                              "e.g. 1e-10")


def check_budget(plain: dict[str, Any], state_size: int) -> None:
    """ConfigError when the output arrays or the step count of one run are beyond the budget."""
    if plain.get("allow_large") is True:
        return
    time = plain["time"]
    n = _n_output(time)
    size = float(n) * state_size * 8
    if size > MAX_STATE_BYTES:
        raise ConfigError(f"time.n_output={n} needs at least {_bytes(size)} for the state alone ({n:.3g} samples × "
                          f"{state_size} values × 8 bytes), beyond the budget of {_bytes(MAX_STATE_BYTES)}; "
                          f"store fewer samples or {ESCAPE}")
    steps, why = estimated_steps(plain)
    if steps > MAX_STEPS:
        raise ConfigError(f"{why} needs at least {steps:.2g} integrator steps, {_duration(steps * SECONDS_PER_STEP)} "
                          f"even at {SECONDS_PER_STEP * 1e6:g} µs a step, beyond the budget of {MAX_STEPS:.0e} steps; "
                          f"shorten the span, enlarge the step or {ESCAPE}")


def estimated_steps(plain: dict[str, Any]) -> tuple[float, str]:
    """A lower bound on the steps of one run, and the settings it comes from (for the message)."""
    time = plain["time"]
    span = float(time["end"]) - float(time["start"])
    integrator = plain.get("integrator") or {}
    candidates = [(float(_n_output(time)) - 1, f"time.n_output={time['n_output']}")]
    for key in ("step", "max_step"):
        step = integrator.get(key)
        if isinstance(step, (int, float)) and not isinstance(step, bool) and step > 0:
            candidates.append((span / step, f"integrator.{key}={step:g} over time.start={time['start']:g} to "
                                            f"time.end={time['end']:g}"))
    initial = plain.get("initial") or {}
    rates = [initial.get(k) for k in ("p0", "q0", "r0")]
    if all(isinstance(r, (int, float)) and not isinstance(r, bool) for r in rates):
        rate = math.sqrt(sum(float(r) ** 2 for r in rates))
        candidates.append((rate * span / RADIANS_PER_STEP, f"time.end={time['end']:g} (|ω0| = {rate:.3g} rad per time "
                           f"unit over a span of {span:.3g}, one step per {RADIANS_PER_STEP:g} rad at most)"))
    return max(candidates, key=lambda c: c[0])


def _n_output(time: dict[str, Any]) -> int:
    """The stored samples, or for ``auto`` their cap (the count itself needs the built scene)."""
    return AUTO_MAX_SAMPLES if time.get("n_output", AUTO) == AUTO else int(time["n_output"])


def _bytes(n: float) -> str:
    if not math.isfinite(n):
        return "more bytes than a float can count"
    for unit, scale in (("TiB", 1024**4), ("GiB", 1024**3), ("MiB", 1024**2)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n:.0f} bytes"


def _duration(seconds: float) -> str:
    for unit, scale in (("years", 3.156e7), ("days", 86400.0), ("hours", 3600.0), ("minutes", 60.0)):
        if seconds >= scale:
            return f"{seconds / scale:.3g} {unit}"
    return f"{seconds:.3g} s"


#: points of one batch, a stability map or a sweep: beyond it even 1 ms a point is more than a day of CPU time
MAX_POINTS = 100_000_000


def check_points(n: float, why: str, *, allow_large: bool = False) -> None:
    """ConfigError when ``n`` points (a grid, a batch) exceed :data:`MAX_POINTS`; ``why`` names the settings."""
    if not (allow_large or n <= MAX_POINTS):
        raise ConfigError(f"{why} makes {n:.3g} points, beyond the budget of {MAX_POINTS:.0e} points "
                          f"({_duration(n * 1e-3)} even at 1 ms a point); use fewer points or {ESCAPE}")


def sweep_points(overrides: Any) -> tuple[float, str]:
    """(the number of points the sweeps of ``overrides`` (Hydra ``Override`` objects) make, the sweeps' text),
    counted without expanding them: ``range(0,1e12,1)`` is 1e12 points, not a list of them."""
    total, named = 1.0, []
    for o in overrides:
        if not o.is_sweep_override():
            continue
        total *= _sweep_length(o)
        named.append(o.input_line)
    return total, " ".join(named)


def _sweep_length(o: Any) -> float:
    value = o.value()
    if isinstance(value, RangeSweep):
        start, stop, step = (float(v) if v is not None else None for v in (value.start, value.stop, value.step))
        step = 1.0 if step is None else step
        if step == 0:
            raise ConfigError(f"{o.input_line!r}: a range's step must not be 0, e.g. range(0,1,0.1)")
        if not all(math.isfinite(v) for v in (start, stop, step)):
            raise ConfigError(f"{o.input_line!r}: a range's start, stop and step must be finite numbers")
        return max(0.0, math.ceil((stop - start) / step))
    if isinstance(value, ChoiceSweep):
        return float(len(value.list))
    return 1.0


def check_sweep_size(overrides: Any) -> None:
    """ConfigError before any expansion when the sweeps of the command line make more than MAX_POINTS points
    (unless the command line says ``allow_large=true``)."""
    allow_large = any(o.key_or_group == "allow_large" and not o.is_sweep_override() and o.value() is True
                      for o in overrides)
    n, named = sweep_points(overrides)
    check_points(n, named, allow_large=allow_large)
