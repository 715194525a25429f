"""Find regular precessions numerically: solve R(t) ≡ 0 for (n, m, θ0, ψ0) and chosen free parameters, least squares
from quasi-random starts, solutions de-duplicated by the body-frame motion and each with the dimension of its family
(docs/gyrostat.md, "Finder").
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, least_squares, minimize_scalar
from scipy.stats import qmc

from gyrolab.analysis.precession.motion import Precession, build_system, defect, states, vector_residual
from gyrolab.errors import ConfigError
from gyrolab.physics.gyrostat_euler import GyrostatParameters

MOTION = ("n", "m", "theta0", "psi0")


@dataclass
class Solution:
    motion: Precession
    params: GyrostatParameters
    values: dict[str, float]
    residual: float
    family_dimension: int


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
        return defect(build_system(p, motion), motion, t).ravel() / scale

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


def _rest_torque(params: GyrostatParameters, theta0: float, chi: float) -> np.ndarray:
    """I(ω̇ − f_ω) of the system's own right-hand side for the body at rest in the orbital frame at (χ, θ0)."""
    motion = Precession(0.0, 0.0, chi, theta0)
    return defect(build_system(params, motion), motion, np.zeros(1))[0, 0:3]


def find_normal_rests(params: GyrostatParameters, theta0: float, *, grid: int = 720,
                      accept: float = 1e-12) -> list[Solution]:
    """Every rest in the orbital frame with the body z axis on the orbit normal (θ0 = 0 or π, n ± m = 0): the zeros in
    χ of the residual's γ-component (which does not contain k), then k1, k2 from the components ⊥ γ; a γ-component
    zero for every χ is a family, one representative χ = 0 with ``family_dimension`` 1 (docs/gyrostat.md).
    """
    sigma = 1.0 if np.cos(theta0) > 0 else -1.0
    theta0 = 0.0 if sigma > 0 else np.pi
    chis = np.linspace(0.0, 2 * np.pi, grid + 1)
    g = np.array([sigma * _rest_torque(params, theta0, x)[2] for x in chis])
    scale = max(float(np.max(np.abs(params.I))) * params.Omega ** 2, 1e-300)
    if np.max(np.abs(g)) < accept * scale:
        roots, dimension = [0.0], 1
    else:
        roots, dimension = _torque_zeros(lambda x: sigma * _rest_torque(params, theta0, x)[2], chis, g,
                                         accept * scale), 0
    found = []
    for chi in roots:
        base = _rest_torque(params.replace(k1=0.0, k2=0.0), theta0, chi)
        columns = [_rest_torque(params.replace(k1=float(e1), k2=float(e2)), theta0, chi) - base
                   for e1, e2 in ((1.0, 0.0), (0.0, 1.0))]
        k12 = np.linalg.solve(np.array(columns).T[0:2], -base[0:2])
        p = params.replace(k1=float(k12[0]), k2=float(k12[1]))
        motion = Precession(0.0, 0.0, float(chi), theta0)
        system = build_system(p, motion)
        residual = vector_residual(system, motion, np.linspace(0.0, 4 * np.pi / params.Omega, 64))
        if residual < 1e-9:
            found.append(Solution(motion, p, {"n": 0.0, "m": 0.0, "psi0": float(chi), "theta0": theta0,
                                              "k1": float(k12[0]), "k2": float(k12[1])}, residual, dimension))
    return found


def _torque_zeros(gamma_torque: Callable[[float], float], chis: np.ndarray, g: np.ndarray,
                  tolerance: float) -> list[float]:
    """The distinct zeros in [0, 2π) of ``gamma_torque``, sampled as ``g`` on the grid ``chis``: sign changes
    (Brent), and grazing minima polished to within ``tolerance``."""
    roots = []
    for i in range(len(chis) - 1):
        a, b = chis[i], chis[i + 1]
        if g[i] == 0.0:
            roots.append(a)
        elif g[i] * g[i + 1] < 0:
            roots.append(brentq(gamma_torque, a, b, xtol=1e-15, rtol=1e-15))
        elif 0 < i and abs(g[i]) < abs(g[i - 1]) and abs(g[i]) < abs(g[i + 1]):
            polish = minimize_scalar(lambda x: abs(gamma_torque(x)), bounds=(chis[i - 1], b), method="bounded",
                                     options={"xatol": 1e-14})
            if abs(polish.fun) < tolerance:
                roots.append(float(polish.x))
    roots = [r % (2 * np.pi) for r in roots]
    roots = [r for j, r in enumerate(roots) if all(abs(np.angle(np.exp(1j * (r - q)))) > 1e-9 for q in roots[:j])]
    return roots
