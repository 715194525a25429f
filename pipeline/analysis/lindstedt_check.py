"""The Lindstedt series of ``gyrolab.physics.lindstedt`` against exact periodic orbits (Newton shooting on the
full model): the error of a series order at a parameter, and the ladder of errors that measures the order."""

from __future__ import annotations

import numpy as np

from gyrolab.analysis.periodic import FixedPointModel, shoot
from gyrolab.physics.lindstedt import Body, LindstedtSeries


def _model(body: Body) -> FixedPointModel:
    """The full model in the body's nondimensional units (c = 1: inertia (a, b, 1), U = (x0', y0', z0'), N = k)."""
    return FixedPointModel(np.array([body.a, body.b, 1.0]), np.array([body.x0, body.y0, body.z0]), float(body.k))


def exact_orbit(body: Body, eps: float, tilt: float, guess: LindstedtSeries | None = None):
    """The exact periodic orbit through r1 = 1, γ' = 0, γ'' = tilt at ε (Newton shooting on the full model).

    Shot in the body's nondimensional units (``_model``), from the series' initial state and period when ``guess``
    is given. Returns the ``PeriodicOrbit`` (its state in c units, r = r1/ε, period in 1/c: T = ε T_τ).
    """
    if guess is not None:
        y0 = guess.scaled(eps, np.array([0.0]))[0]
        period = 2 * np.pi / guess.frequency(eps)
    else:
        y0, period = np.zeros(6), 2 * np.pi
    y0 = np.array([y0[0], y0[1], 1.0 / eps, np.sqrt(1 - tilt**2), 0.0, tilt])
    return shoot(_model(body), y0, eps * period)


def series_error(sol: LindstedtSeries, orbit, eps: float, order: int, samples: int = 64) -> dict[str, float]:
    """Max error of the order-``order`` series against an exact orbit over one period, in the scaled variables.

    ``state``: max over (p1, q1, r1, γ, γ', γ'') at the orbit's own times; ``period``: |T_τ − T_τ,exact|/T_τ,exact.
    """
    t = np.linspace(0.0, orbit.period, samples + 1)
    exact = _model(sol.body).sample(orbit.y0, t)
    exact[:, 2] *= eps  # r1 = ε r
    approx = sol.scaled(eps, t / eps, order)
    t_series = 2 * np.pi / sol.frequency(eps, order)
    return {"state": float(np.max(np.abs(approx - exact))),
            "period": abs(t_series - orbit.period / eps) / (orbit.period / eps)}


def error_ladder(sol: LindstedtSeries, order: int, tilt: float, *, target: float = 1e-8, points: int = 4,
                 step: float = 2**-0.5) -> dict[str, np.ndarray | float]:
    """The order-``order`` series against exact orbits at ``points`` values of ε, and the fitted error slope.

    The largest ε is where the predicted error (``error_estimate``) is ``target`` (capped at a third of the
    radius of convergence), the others a factor ``step`` apart: the errors then lie between round-off (~1e-13)
    and the pre-asymptotic range, where the fitted slope is the order's.
    """
    lo, hi = 1e-6, sol.radius_of_convergence() / 3
    if sol.error_estimate(hi, order) > target:
        for _ in range(60):
            mid = np.sqrt(lo * hi)
            lo, hi = (mid, hi) if sol.error_estimate(mid, order) < target else (lo, mid)
    eps = hi * step ** np.arange(points)
    errors = [series_error(sol, exact_orbit(sol.body, float(e), tilt, sol), float(e), order) for e in eps]
    state, period = (np.array([err[key] for err in errors]) for key in ("state", "period"))
    slope = float(np.polyfit(np.log(eps), np.log(state), 1)[0])
    return {"eps": eps, "state": state, "period": period, "slope": slope}
