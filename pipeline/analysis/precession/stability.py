"""Linear stability of a regular precession: Floquet multipliers of the full vector equations over the body-frame
period, Df by complex steps of the system's own right-hand side, with a stability tolerance tied to the integration
accuracy (trivial multipliers 1 sit in Jordan blocks: docs/gyrostat.md, "Regular precession"). Spectral stability is
necessary, not sufficient, for stability.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from scipy.integrate import solve_ivp

from gyrolab.analysis.precession.motion import Precession, states
from gyrolab.plugins.systems.orbiting_gyrostat import OrbitingGyrostat

TOLERANCE_FACTOR = 10.0  # tolerance = TOLERANCE_FACTOR · max(√rtol, δ)
STEP = 1e-30


@dataclass(frozen=True)
class Floquet:
    kind: str  # "periodic", "equilibrium" or "quasi-periodic" (not analysed)
    period: float
    multipliers: np.ndarray
    tolerance: float = float("nan")  # |ρ| ≤ 1 + tolerance counts as |ρ| = 1
    uncertainty: float = float("nan")  # δ: change of the sorted |ρ| between rtol and 100·rtol

    @property
    def max_modulus(self) -> float:
        return float(np.max(np.abs(self.multipliers))) if self.multipliers.size else float("nan")

    @property
    def stable(self) -> bool | None:
        return None if not self.multipliers.size else bool(self.max_modulus <= 1.0 + self.tolerance)


def jacobian(system: OrbitingGyrostat, y: np.ndarray) -> np.ndarray:
    """Df(y) (9 × 9) by complex steps of the system's right-hand side."""
    size = len(y)
    probes = np.tile(y.astype(complex), (size, 1)) + 1j * STEP * np.eye(size)
    return (system.derivative(probes).imag / STEP).T


def body_frame_period(motion: Precession, Omega: float, max_denominator: int = 12) -> tuple[str, float]:
    n, m = motion.n, motion.m
    if abs(np.sin(motion.theta0)) < 1e-12:
        rate = n + m if np.cos(motion.theta0) > 0 else m - n
        return ("equilibrium", 2 * np.pi / Omega) if abs(rate) < 1e-12 else ("periodic", 2 * np.pi / abs(rate))
    if abs(n) < 1e-12 and abs(m) < 1e-12:
        return "equilibrium", 2 * np.pi / Omega
    if abs(n) < 1e-12 or abs(m) < 1e-12:
        return "periodic", 2 * np.pi / abs(m if abs(n) < 1e-12 else n)
    ratio = Fraction(n / m).limit_denominator(max_denominator)
    if abs(float(ratio) - n / m) > 1e-12:
        return "quasi-periodic", float("nan")
    return "periodic", 2 * np.pi * ratio.denominator / abs(m)


def floquet(system: OrbitingGyrostat, motion: Precession, rtol: float = 1e-11) -> Floquet:
    """Floquet multipliers over the body-frame period, with a stability tolerance from the integration accuracy."""
    kind, period = body_frame_period(motion, system.Omega)
    if kind == "quasi-periodic":
        return Floquet(kind, period, np.array([]))
    floor = TOLERANCE_FACTOR * np.sqrt(rtol)
    if kind == "equilibrium":
        y = states(system, motion, np.zeros(1))[0][0]
        return Floquet(kind, period, np.exp(np.linalg.eigvals(jacobian(system, y)) * period), floor, 0.0)
    multipliers = monodromy_multipliers(system, motion, period, rtol)
    coarse = monodromy_multipliers(system, motion, period, 100 * rtol)
    spread = float(np.max(np.abs(np.sort(np.abs(multipliers)) - np.sort(np.abs(coarse)))))
    return Floquet(kind, period, multipliers, max(floor, TOLERANCE_FACTOR * spread), spread)


def monodromy_multipliers(system: OrbitingGyrostat, motion: Precession, period: float, rtol: float,
                          periods: int = 1) -> np.ndarray:
    """Eigenvalues of Φ(periods·T) from the variational equations along the exact motion (DOP853, rtol = atol)."""
    size = system.state_size

    def variational(t: float, z: np.ndarray) -> np.ndarray:
        y = states(system, motion, np.array([t]))[0][0]  # the exact motion (its residual is checked separately)
        return (jacobian(system, y) @ z.reshape(size, size)).ravel()

    solution = solve_ivp(variational, (0.0, periods * period), np.eye(size).ravel(), method="DOP853", rtol=rtol,
                         atol=rtol)
    return np.linalg.eigvals(solution.y[:, -1].reshape(size, size))
