"""Shared set-up of the regime tests: the research's test bodies, error fits against exact orbits, and Taylor
coefficients in ε by the Cauchy integral.

Every expected number comes from the papers, from physics (the exact periodic orbit of the full model, found by
shooting) or from the independent verification reports in docs/derivations/, never from the regime code under test.
"""

import numpy as np

from gyrolab.engine.config import compose_config
from gyrolab.experiments.regime_run import compute, prepare

# Seed 000 report, body I: a = 2, b = 1.5, r_c = (0.5, 0.3, 0.8124), k = 0.3, Γ = μγ0'' = 0.5.
BODY_000 = ["body.a=2.0", "body.b=1.5", f"body.com_direction=[0.5,0.3,{float(np.sqrt(1 - 0.34))!r}]",
            "force.newtonian.k=0.3", "initial.phi0=1.5707963267948966", "initial.psi0=0.0"]
GAMMA_000 = 0.5
# Seed 001 report, B1 (figure body) and B2, both on the ω = 3 curve (non-physical).
B1 = dict(a=0.4, b=1 / 7, rc=(0.48, 0.36, 0.8), k=1.0, theta0=float(np.arctan(0.75)))
B2 = dict(a=0.6, b=(1 - 0.6) / (1 + 8 * 0.6), rc=(-0.3, 0.5, float(np.sqrt(1 - 0.34))), k=2.5, theta0=np.pi / 3)


def overrides_000(mu, formula="corrected"):
    return ["regime=small_parameter", f"regime.formula={formula}", "regime.periods=1", *BODY_000,
            f"initial.r0={mu!r}", f"initial.theta0={float(np.arccos(GAMMA_000 / mu))!r}"]


def overrides_001(body, mu, formula="corrected", periods=1):
    r0 = np.sqrt(np.cos(body["theta0"])) / mu
    rc = ",".join(repr(float(v)) for v in body["rc"])
    return ["regime=resonant_omega3", f"regime.formula={formula}", f"regime.periods={periods}",
            f"body.a={body['a']!r}", f"body.b={body['b']!r}", "body.allow_nonphysical=true",
            f"body.com_direction=[{rc}]", f"force.newtonian.k={body['k']!r}", f"initial.r0={float(r0)!r}",
            f"initial.theta0={float(body['theta0'])!r}", "initial.phi0=1.5707963267948966", "initial.psi0=0.0"]


def run_case(overrides, samples=240, full=False):
    scene, regime, _ = prepare(compose_config(overrides))
    T = regime.period(scene.system)
    t = np.linspace(0, regime.periods * T, regime.periods * samples + 1)
    return scene, regime, t, compute(scene, regime, t, full=full)


def slope(x, y):
    return float(np.polyfit(np.log(x), np.log(y), 1)[0])


def taylor_coefficients(f, count, radius=0.05, points=32, real=False):
    """Taylor coefficients 0..count−1 in ε of an analytic f(ε) (an array of any shape) by the Cauchy integral on
    |ε| = radius (trapezoid rule); their real parts when ``real``."""
    theta = 2 * np.pi * np.arange(points) / points
    values = np.array([f(radius * np.exp(1j * t)) for t in theta])
    along = (-1,) + (1,) * (values.ndim - 1)   # the weights along the points, broadcast over f's shape
    coefficients = [np.mean(values * np.exp(-1j * k * theta).reshape(along), axis=0) / radius**k for k in range(count)]
    return [c.real for c in coefficients] if real else coefficients
