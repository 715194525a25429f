"""Slow spin about a fixed point (small r0/c): the perturbed physical pendulum — Ismail's (2021) "new domain", done right.

The pendulum swing at r0 = 0 (``gyrolab.physics.pendulum``), continued through its turning-point section
(``gyrolab.analysis.continuation``), as a numeric series in ε = r0/c fitted to exact orbits (``SlowSpinSeries``).
Method, domain and measured errors: docs/regimes.md, "large_parameter: slow spin, the perturbed physical pendulum".
``formula=printed`` evaluates the paper's printed (35) under its own reading μ = c/r0, which misses the motion by
O(1) (``docs/derivations/seed000_large_parameter.md`` §3); the run records the measured error.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from gyrolab.analysis.continuation import Section, _evaluate, shoot_section
from gyrolab.analysis.periodic import FixedPointModel
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.physics import pendulum
from gyrolab.physics.attitude import angles_from_states
from gyrolab.plugins.regimes import ismail2021 as paper
from gyrolab.plugins.regimes.base import FixedPointRegime, NondimensionalScene

MAX_SPIN = 0.2        # refused above: the series' radius of convergence is ≈ 0.29 (docs/regimes.md)
WARN_SPIN = 0.1
MIN_TILT, MAX_TILT = 0.05, 3.0
MIN_INDEX_GAP = 0.05  # |s0 − 2| below this: the swing is (nearly) degenerate out of plane
FIT_SPINS = (0.01, 0.02, 0.03, 0.04)
PRINTED_WARNING = ("regime.formula=printed evaluates Ismail's (2021) printed (35) under its own reading μ = c/r0: it is "
                   "not a solution of the equations of motion and misses the full model by O(1) (γ'' error 0.87-0.99 "
                   "at c/r0 = 4-64); the measured error is max_error_vs_full")


@dataclass
class SlowSpinSeries:
    """The numeric slow-spin series for one body and tilt (nondimensional: time 1/c, rates c):
    y(s T(ε); ε) = y_P(s T0) + ε Φ(s T0) ∂y0/∂ε + Σ_{j=2..7} ε^j y_j(s), T(ε) = T0 + T2 ε² + T4 ε⁴ + T6 ε⁶, the y_j
    fitted with their parity in ε to the exact orbits at ε = FIT_SPINS (docs/regimes.md, "Series (numeric)").
    """

    a: float
    b: float
    k: float
    theta0: float
    T0: float
    s0: float                  # out-of-plane stability index ρ + 1/ρ of the swing
    first: np.ndarray          # ∂y0/∂ε at ε = 0 (exact)
    periods: np.ndarray        # T2 … T5
    spectra: np.ndarray        # (4, HARMONICS, 6): rfft of y2 … y5 over the phase grid
    model: FixedPointModel
    section: Section

    @classmethod
    def build(cls, a: float, b: float, k: float, theta0: float) -> SlowSpinSeries:
        """Five shootings; use ``series_for`` (cached per (a, b, k, θ0))."""
        model = FixedPointModel(np.array([a, b, 1.0]), np.array([0.0, 0.0, 1.0]), k)
        section = Section("turning", float(np.cos(theta0)))
        T0 = pendulum.period(b, pendulum.kappa(a, k), theta0)
        swing = shoot_section(model, section, np.zeros(2), T0, 0.0)
        if abs(swing.period - T0) > 1e-9 * T0:
            raise IntegrationError(f"the r0 = 0 orbit has period {swing.period:.12g}, not the pendulum's {T0:.12g}")
        _, _, J, _, phi = _evaluate(model, section, np.array([0.0, 0.0, np.log(T0), 0.0]), 0.0)
        e_r = np.eye(6)[2]
        scale = max(1.0, float(np.max(np.abs(swing.y0))))
        dz = np.linalg.lstsq(J[:, :3], -(phi @ e_r - e_r) / scale, rcond=None)[0]
        first = section.derivative(np.zeros(2)) @ dz[:2] + e_r
        phases = np.arange(HARMONICS) / HARMONICS
        base = model.sample(swing.y0, T0 * phases, first)
        eps = np.array(FIT_SPINS)
        remainders, periods = [], []
        u = np.zeros(2)
        for e in eps:
            point = shoot_section(model, section, u + e * dz[:2], T0, float(e))
            u = np.array([point.y0[0], point.y0[4]]) - e * dz[:2]
            exact = model.sample(point.y0, point.period * phases)
            remainders.append(exact - base[0] - e * base[1])
            periods.append(point.period - T0)
        remainders = np.array(remainders)
        coefficients = np.zeros((len(POWERS), HARMONICS, 6))
        for parity, columns in ((0, EVEN), (1, ODD)):
            powers = [j for j in POWERS if j % 2 == parity]
            V = eps[:, None] ** np.array(powers)[None, :]
            fit = np.linalg.lstsq(V, remainders[:, :, columns].reshape(len(eps), -1), rcond=None)[0]
            for row, j in enumerate(powers):
                coefficients[POWERS.index(j)][:, columns] = fit[row].reshape(HARMONICS, len(columns))
        V = eps[:, None] ** np.array([j for j in POWERS if j % 2 == 0])[None, :]
        even_periods = np.linalg.lstsq(V, np.array(periods), rcond=None)[0]
        return cls(a, b, k, theta0, T0, swing.stability_index, first, even_periods,
                   np.fft.rfft(coefficients, axis=1), model, section)

    def period(self, eps: float) -> float:
        return float(self.T0 + np.sum(self.periods * eps ** np.array([j for j in POWERS if j % 2 == 0])))

    def initial_state(self, eps: float) -> np.ndarray:
        return self.state(np.array([0.0]), eps)[0]

    def state(self, t: np.ndarray, eps: float) -> np.ndarray:
        """The series at times t (phase s = t/T(ε) mod 1)."""
        phase = np.mod(np.asarray(t, dtype=float) / self.period(eps), 1.0)
        swing = self.model.sample(self.section.state(np.zeros(2), 0.0), self.T0 * phase, self.first)
        out = swing[0] + eps * swing[1]
        modes = np.arange(self.spectra.shape[1])
        weights = np.where((modes == 0) | (2 * modes == HARMONICS), 1.0, 2.0) / HARMONICS
        basis = np.exp(2j * np.pi * phase[:, None] * modes[None, :]) * weights
        for row, j in enumerate(POWERS):
            out = out + eps ** j * np.real(basis @ self.spectra[row])
        return out


HARMONICS = 256
POWERS = (2, 3, 4, 5, 6, 7)
EVEN, ODD = [1, 3, 5], [0, 2, 4]  # q, γ, γ'' even in ε at fixed phase; p, r, γ' odd (time reversal + mirror)


@cache   # building one takes 5 shootings
def series_for(a: float, b: float, k: float, theta0: float) -> SlowSpinSeries:
    return SlowSpinSeries.build(float(a), float(b), float(k), float(theta0))


class LargeParameter(FixedPointRegime):
    name = "large_parameter"
    parameter = "r0/c"
    parameter_long_name = "slow-spin parameter ε = r0/c (spin about the body z axis in units of c = √(Mgℓ/C))"
    order = {"pq": 8.0, "r": 9.0, "gamma": 8.0, "gamma3": 8.0, "period": 8.0}

    def parameter_value(self, system) -> float:
        return float(self.scene(system).r0)

    def series(self, s: NondimensionalScene) -> SlowSpinSeries:
        return series_for(s.a, s.b, s.k, s.theta0)

    def reseat_warnings(self, system) -> list[str]:
        given = np.concatenate([system.initial.omega, system.initial.gamma])
        y = self.initial_state(system)
        if np.max(np.abs(given[:2] - y[:2])) > 1e-12:
            return [f"the slow-spin orbit starts from its own p0={y[0]:.6g}, q0=0 at the swing's turning point (the "
                    f"scene gave p0={given[0]:.6g}, q0={given[1]:.6g}); r0 and θ0 are the scene's"]
        return []

    def check_domain(self, system) -> list[str]:
        s = self.scene(system)
        if self.formula == "printed":
            if not s.r0 > 0:
                raise ConfigError(f"regime large_parameter with formula=printed needs r0 > 0 (μ = c/r0), got "
                                  f"r0/c={s.r0:.4g}")
            frequency = paper.printed_frequency(printed_params(s))
            if frequency < 0:
                return [PRINTED_WARNING, f"the printed frequency 2π/(2π + α) is negative here (α = "
                        f"{paper.printed_period_correction(printed_params(s)):.4g} < −2π, Ω = {frequency:.4g}): "
                        f"the printed period is {2 * np.pi / (frequency * s.r0):.6g}/c; its magnitude sets the window"]
            return [PRINTED_WARNING]
        if abs(s.x0) > 1e-9 or abs(s.y0) > 1e-9 or s.z0 < 0:
            raise ConfigError(f"regime large_parameter (slow spin, a perturbed pendulum) is derived for a centre of "
                              f"mass on the body +z axis, got com_direction=({s.x0:.3g}, {s.y0:.3g}, {s.z0:.3g}); use "
                              "regime=small_parameter for fast spin or regime.formula=printed for the paper's formulas")
        gamma = system.initial.gamma
        if abs(gamma[1]) > 1e-9:
            raise ConfigError(f"regime large_parameter needs the z axis tilted about the body y axis (φ0 = ±π/2, "
                              f"γ'(0) = 0), got γ'(0)={gamma[1]:.3g}; set initial.phi0=1.5707963267948966")
        if not MIN_TILT <= s.theta0 <= MAX_TILT:
            raise ConfigError(f"regime large_parameter needs a swing amplitude {MIN_TILT:g} ≤ θ0 ≤ {MAX_TILT:g}, got "
                              f"θ0={s.theta0:.4g}")
        kap = pendulum.kappa(s.a, s.k)
        if not 1 + kap * np.cos(s.theta0) > 0 or not 1 + kap > 0:
            raise ConfigError(f"regime large_parameter needs a swing about the lowest position, 1 + κ cos θ > 0 with "
                              f"κ = k(a − 1) = {kap:.4g}, at θ0={s.theta0:.4g}")
        if not 0 < s.r0 <= MAX_SPIN:
            raise ConfigError(f"regime large_parameter needs slow spin, 0 < r0/c ≤ {MAX_SPIN:g}, got "
                              f"r0/c={s.r0:.4g}; use regime=small_parameter for r0/c ≥ 5")
        series = self.series(s)
        if abs(series.s0 - 2) < MIN_INDEX_GAP:
            raise ConfigError(f"regime large_parameter excludes swings with an out-of-plane Floquet multiplier near "
                              f"1: stability index s0 = {series.s0:.4g} (|s0 − 2| < {MIN_INDEX_GAP:g}) at "
                              f"θ0={s.theta0:.4g}, where the orbit family branches; change θ0 or the body")
        warnings = []
        if s.r0 > WARN_SPIN:
            warnings.append(f"r0/c = {s.r0:.3g} > {WARN_SPIN:g}: near the series' radius of convergence (≈ 0.29 for "
                            "the test body), errors up to ~1e-3 at r0/c = 0.2")
        if series.s0 > 2:
            warnings.append(f"the generating swing is unstable out of plane (ρ + 1/ρ = {series.s0:.4g}): the orbit "
                            "exists but a perturbed motion leaves it")
        return warnings + self.reseat_warnings(system)

    def _state(self, s, t):
        return printed_reading_state(t, s) if self.formula == "printed" else self.series(s).state(t, s.r0)

    def _period(self, s):
        if self.formula == "printed":
            # the printed frequency can be negative (check_domain says so): a period is a length of time
            return abs(2 * np.pi / (paper.printed_frequency(printed_params(s)) * s.r0))
        return self.series(s).period(s.r0)

    def _euler(self, s, t):
        if self.formula == "printed":
            return paper.printed_euler(t, printed_params(s))
        T = self._period(s)
        t = np.asarray(t, dtype=float)
        dense = np.linspace(0.0, max(float(t.max()), T), 1000 * int(np.ceil(max(float(t.max()), T) / T)) + 1)
        angles = angles_from_states(dense, self._state(s, dense), 0.0)
        return {k: np.interp(t, dense, v) for k, v in angles.items()}

    def initial_state(self, system) -> np.ndarray:
        if self.formula == "printed":
            return super().initial_state(system)
        s = self.scene(system)
        y = self.series(s).initial_state(s.r0)
        y[:3] *= s.c
        return y


def printed_params(s: NondimensionalScene) -> paper.Params:
    """The paper's parameters of scene ``s`` under its own reading μ = c/r0."""
    return paper.Params(a=s.a, b=s.b, x0=s.x0, y0=s.y0, z0=s.z0, k=s.k, mu=1.0 / s.r0, g0=s.gamma0pp)


def printed_reading_state(t: np.ndarray, s) -> np.ndarray:
    """Printed (35) under the paper's own reading μ = c/r0 (τ = r0 t, p = c p1, r = r0 r1).

    ``s`` is a ``NondimensionalScene``; returns (n, 6) in units of c at times t (1/c).
    """
    S = paper.printed_scaled(s.r0 * np.asarray(t, dtype=float), printed_params(s))
    return np.stack([S["p1"], S["q1"], s.r0 * S["r1"], S["g1"], S["g2"], S["g3"]], axis=-1)
