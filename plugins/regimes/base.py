"""What the fixed-point regimes share: the scene in the papers' nondimensional form, and the unit mapping.

The papers work with time in 1/c and rates in c (c² = Mgℓ/C), a = A/C, b = B/C,
the unit centre-of-mass direction (x0', y0', z0') and k = N/c². A scene in SI
units is mapped there and back: t' = c t, ω' = ω/c.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.physics.attitude import frame_from_angles
from gyrolab.contracts.regime import Regime
from gyrolab.contracts.system import System
from gyrolab.errors import ConfigError
from gyrolab.plugins.regimes.notation import BodyRatios

SUPPORTED_FORCES = ("uniform_gravity", "newtonian", "magnetic")


@dataclass(frozen=True)
class NondimensionalScene(BodyRatios):
    k: float  # N/c²
    c: float  # √(Mgℓ/C) in model rate units (1 for a nondimensional body)
    r0: float  # initial spin in units of c
    theta0: float
    psi0: float
    nonphysical: bool

    @property
    def omega2(self) -> float:
        """ω² = −A1B1 = (C−A)(C−B)/(AB) (Ismail (2021) eq. 5, Shaker et al. §2)."""
        return (1 - self.a) * (1 - self.b) / (self.a * self.b)

    @property
    def gamma0pp(self) -> float:
        return float(np.cos(self.theta0))


#: each system's nondimensional form, once computed: a system's body, forces and initial state are fixed when it is
#: built, and ``integrator=auto``'s series check asks every regime for it (~40 µs each)
_SCENES: weakref.WeakKeyDictionary[System, NondimensionalScene] = weakref.WeakKeyDictionary()


def nondimensional_scene(system: System, regime: str) -> NondimensionalScene:
    """The scene's body, forces and initial spin/tilt in the papers' form; ConfigError for other forces."""
    known = _SCENES.get(system)
    if known is None:
        known = _SCENES[system] = _nondimensional_scene(system, regime)
    return known


def _nondimensional_scene(system: System, regime: str) -> NondimensionalScene:
    names = [f.name for f in system.forces]
    foreign = [n for n in names if n not in SUPPORTED_FORCES]
    if foreign or not {"uniform_gravity", "magnetic"} & set(names):
        raise ConfigError(f"regime {regime} is derived for force=[uniform_gravity] or [uniform_gravity,newtonian] "
                          f"(a vertical magnetic field may add to or replace gravity), got force={names}")
    body = system.body
    nd = _with_magnetic_moment(system, regime, body.nondimensional(), names)
    c2 = nd.get("c2", 1.0)
    if c2 <= 0:
        raise ConfigError(f"regime {regime} needs a heavy body (c² = |U|/C > 0 with U = Mg r_c [+ m·B]), got c²={c2:g}")
    c = float(np.sqrt(c2))
    k = 0.0
    for force in system.forces:
        if force.name == "newtonian":
            k = float(force.N) / c2
    omega0, gamma0 = system.initial.omega, system.initial.gamma
    theta0 = float(np.arctan2(np.hypot(gamma0[0], gamma0[1]), gamma0[2]))
    alpha0 = system.initial.alpha
    # −(γ × α)_z written out: np.cross on 3-vectors costs ~0.4 ms, a noticeable part of auto's series check
    cross_z = gamma0[0] * alpha0[1] - gamma0[1] * alpha0[0]
    psi0 = float(np.arctan2(alpha0[2], -cross_z)) if np.sin(theta0) > 1e-12 else 0.0
    x0, y0, z0 = nd["com_direction"]
    return NondimensionalScene(a=nd["a"], b=nd["b"], x0=x0, y0=y0, z0=z0, k=k, c=c, r0=float(omega0[2]) / c,
                               theta0=theta0, psi0=psi0, nonphysical=bool(body.nonphysical))


def _with_magnetic_moment(system: System, regime: str, nd: dict, names: list[str]) -> dict:
    """The body's nondimensional data with c² and the centre-of-mass direction of the torque U × γ: the weight's
    moment plus m·B of a vertical uniform field (the same form, Ismail (2021) eq. 1)."""
    body = system.body
    U = np.array(body.weight_moment, dtype=float) if "uniform_gravity" in names else np.zeros(3)
    for force in system.forces:
        if force.name == "magnetic":
            if np.any(force.direction[:2] != 0):
                raise ConfigError(f"regime {regime} needs a vertical magnetic field, force.magnetic.direction="
                                  f"[0,0,±1], got {force.direction.tolist()}")
            U = U + force.field * force.direction[2] * force.moment
    if np.linalg.norm(U - np.asarray(body.weight_moment)) > 0:
        moment = float(np.linalg.norm(U))
        nd = {**nd, "c2": moment / float(body.inertia[2]),
              "com_direction": (U / moment).tolist() if moment > 0 else [0.0, 0.0, 0.0]}
    return nd


def with_alpha(regime: Regime, system: System, y6: np.ndarray) -> np.ndarray:
    """A 6-state (ω, γ) in the system's layout: α appended from the regime's ψ0 and the state's θ, φ when carried."""
    if system.state_size == 6:
        return y6
    psi0 = float(regime.euler_angles(system, np.array([0.0]))["psi"][0])
    alpha, _, _ = frame_from_angles(psi0, float(np.arccos(np.clip(y6[5], -1, 1))), float(np.arctan2(y6[3], y6[4])))
    return np.concatenate([y6, alpha])


class FixedPointRegime(Regime):
    """Base of the built-in regimes: nondimensional formulas, mapped to the scene's model units.

    ``periods`` and ``samples_per_period`` set the window of a regime run. Subclasses implement the nondimensional
    solution (time in 1/c, rates in c) of a ``NondimensionalScene`` s: ``_state(s, t)`` (n, 6), ``_period(s)`` and
    ``_euler(s, t)`` (ψ from ψ0 = 0).
    """

    #: the contract's ``period_spread`` (``gyrolab.contracts.regime``, item 11); None: no cheap screen for auto
    period_spread: float | None = None

    def __init__(self, *, formula: str = "corrected", periods: int = 3, samples_per_period: int = 200) -> None:
        super().__init__(formula=formula)
        for key, value in (("periods", periods), ("samples_per_period", samples_per_period)):
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ConfigError(f"regime.{key}={value!r} must be a positive integer")
        self.periods, self.samples_per_period = periods, samples_per_period

    def scene(self, system: System) -> NondimensionalScene:
        return nondimensional_scene(system, self.name)

    def initial_state(self, system: System) -> np.ndarray:
        return self.solution(system, np.array([0.0]))[0]

    def period(self, system: System) -> float:
        s = self.scene(system)
        return self._period(s) / s.c

    def solution(self, system: System, t: np.ndarray) -> np.ndarray:
        s = self.scene(system)
        y = self._state(s, s.c * np.asarray(t, dtype=float))
        y[:, :3] *= s.c
        return y

    def euler_angles(self, system: System, t: np.ndarray) -> dict[str, np.ndarray]:
        s = self.scene(system)
        angles = self._euler(s, s.c * np.asarray(t, dtype=float))
        angles["psi"] = angles["psi"] + s.psi0
        return angles

    def full_initial_state(self, system: System) -> np.ndarray:
        """The orbit's t = 0 state in the system's layout (α appended from ψ0, θ(0), φ(0) when carried)."""
        y = self.initial_state(system)
        y[3:6] /= np.linalg.norm(y[3:6])  # the series satisfies |γ| = 1 to its order only
        return with_alpha(self, system, y)

    def reseat_warnings(self, system: System) -> list[str]:
        """Warnings naming the scene's initial values the orbit replaces (p0, q0, φ0)."""
        y = self.initial_state(system)
        given = np.concatenate([system.initial.omega, system.initial.gamma])
        if not (np.max(np.abs(given[:2] - y[:2])) > 1e-12 or abs(given[4]) > 1e-12):
            return []
        return [f"the analytic orbit starts from its own p0={y[0]:.6g}, q0={y[1]:.6g}, φ0=π/2 (the scene gave "
                f"p0={given[0]:.6g}, q0={given[1]:.6g}, γ'0={given[4]:.3g}); r0 and θ0 are the scene's"]

    def attributes(self) -> dict[str, Any]:
        return {**super().attributes(), "regime_parameter_long_name": self.parameter_long_name}
