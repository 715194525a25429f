"""Find regular precessions numerically: solve R(t) ≡ 0 for (n, m, θ0, ψ0) and chosen free parameters.

The existence conditions are that the vector residual of the ``orbiting_gyrostat`` equations
vanishes at every time along ψ = nt + ψ0, θ = θ0, φ = mt. The finder samples R at ``samples``
times over ``orbits`` orbits and minimises Σ|R|² by Levenberg–Marquardt-type least squares
(scipy ``least_squares``) from a quasi-random set of starts in the search window; converged
points (max residual < ``accept``) are polished and de-duplicated by the motion they describe
(same body-frame state at the sample times, so θ0 ∈ {0, π} solutions that differ only in how
n + m is split count once). Each solution carries the dimension of the solution family through
it (the null space of the residual's Jacobian): 0 = isolated, d > 0 = a d-parameter family.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import qmc

from gyrolab.errors import ConfigError
from gyrolab.physics.precession.motion import Precession, build_system, states, vector_residual
from gyrolab.plugins.systems.gyrostat_euler import GyrostatParameters

MOTION = ("n", "m", "theta0", "psi0")


@dataclass
class Solution:
    motion: Precession
    params: GyrostatParameters
    values: dict[str, float]
    residual: float
    family_dimension: int
    checks: dict[str, float] = field(default_factory=dict)


def _split(x: np.ndarray, names: list[str], fixed: dict[str, float], params: GyrostatParameters):
    values = {**fixed, **dict(zip(names, map(float, x)))}
    motion = Precession(values["n"], values["m"], values["psi0"], values["theta0"])
    free = {k: v for k, v in values.items() if k not in MOTION}
    return motion, (params.replace(**free) if free else params), values


def find_precessions(params: GyrostatParameters, window: dict[str, tuple[float, float]],
                     fixed: dict[str, float] | None = None, *, starts: int = 64, samples: int = 48,
                     orbits: float = 2.0, accept: float = 1e-9, seed: int = 0) -> list[Solution]:
    """Every precession found with the unknowns of ``window`` (name → (low, high)) in their window.

    Unknowns are motion parameters (n, m, theta0, psi0) and body/field parameters (A, B, C, k1..k3,
    mu1..mu3, h1..h3); motion parameters not in ``window`` must be in ``fixed``.
    """
    fixed = dict(fixed or {})
    names = list(window)
    missing = [k for k in MOTION if k not in window and k not in fixed]
    if missing:
        raise ConfigError(f"finder: motion parameter {missing[0]} is neither searched nor fixed; give a window "
                          f"or a value for each of {', '.join(MOTION)}")
    low = np.array([window[k][0] for k in names], dtype=float)
    high = np.array([window[k][1] for k in names], dtype=float)
    if not np.all(high > low):
        raise ConfigError(f"finder: every window must have low < high, got {window}")
    t = np.linspace(0.0, orbits * 2 * np.pi / params.Omega, samples)
    scale = np.max(np.abs(params.I))

    def residual(x: np.ndarray) -> np.ndarray:
        motion, p, _ = _split(x, names, fixed, params)
        system = build_system(p, motion)
        y, y_dot = states(system, motion, t)
        defect = y_dot - system.derivative(y)
        defect[:, 0:3] *= system.inertia
        return defect.ravel() / scale

    points = qmc.scale(qmc.Sobol(len(names), seed=seed).random(starts), low, high)
    found: list[Solution] = []
    signatures: list[np.ndarray] = []
    for x0 in points:
        fit = least_squares(residual, x0, bounds=(low, high), xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200)
        if np.max(np.abs(fit.fun)) * scale > accept:
            continue
        motion, p, values = _split(fit.x, names, fixed, params)
        system = build_system(p, motion)
        signature = np.concatenate([states(system, motion, t[:4])[0].ravel(), [values[k] for k in names
                                                                              if k not in MOTION]])
        if any(np.max(np.abs(signature - s)) < 1e-6 for s in signatures):
            continue
        singular = np.linalg.svd(fit.jac, compute_uv=False)
        dimension = int(np.sum(singular < 1e-6 * max(singular.max(), 1.0)))
        signatures.append(signature)
        found.append(Solution(motion, p, values, vector_residual(system, motion, t), dimension))
    return found
