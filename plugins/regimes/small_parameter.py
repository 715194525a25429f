"""Fast spin about a fixed point: Poincaré's small-parameter periodic solution, ε = c/r0 ≪ 1 (Ismail (2021), corrected).

Ismail's (2021) "large-parameter" method is consistent only with μ = r0/c (report §3 of
``docs/derivations/seed000_large_parameter.md``): it is the classical fast-top expansion in ε = 1/μ. This plugin is
that expansion with the corrected (35), (36), (38)-(39) (``gyrolab.plugins.regimes.ismail2021``; ``formula=printed``:
the printed ones), with the finite-tilt frequency (``finite_tilt_frequency``); ``order=N`` replaces the closed forms
by the numeric Poincaré–Lindstedt series through ε^N (``gyrolab.physics.lindstedt``). Domain, refusal bands at the
resonances ω = 1, 2, 3 and the measured orders: docs/regimes.md.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np
from gyrolab.errors import ConfigError
from gyrolab.analysis import lindstedt_check
from gyrolab.physics import lindstedt
from gyrolab.plugins.regimes import ismail2021 as paper
from gyrolab.plugins.regimes.base import FixedPointRegime, NondimensionalScene

RESONANCES = (1.0, 2.0, 3.0)
WARN_DISTANCE = 0.1
# Refusal band around a resonance, |n² − ω²| < divisor_threshold(n, ε), where the error against the exact orbit
# reaches ~1e-2: ε³/|n² − ω²| ≤ 1/580 near ω = 2, 3 (one small divisor in the ε³ terms), ∝ ε^(4/3) near ω = 1 (the
# fold of a weakly nonlinear oscillator); measured by regime_validity's resonance sweep (docs/regimes.md, "across
# the resonances").
REFUSE_CUBIC = 580.0
REFUSE_ONE_TO_ONE = 2.28


def divisor_threshold(n: float, eps: float) -> float:
    """|n² − ω²| below which small_parameter refuses the scene (ε = c/r0).

    Capped at |ω − n| = WARN_DISTANCE: farther out the error is the generic O(ε³) one (within 2–3× of its value
    far from every resonance), which the slow-spin warning (c/r0 > 0.2) covers, not a small divisor.
    """
    rule = REFUSE_ONE_TO_ONE * eps ** (4 / 3) if n == 1.0 else REFUSE_CUBIC * eps**3
    return min(rule, n * n - (n - WARN_DISTANCE) ** 2)


# The series is computed at least through this order: the order above the one used gives its error estimate, and
# the radius of convergence is estimated from the upper half of the coefficients (docs/regimes.md, "Radius").
RADIUS_ORDER = 32
MAX_ORDER = 60
CANDIDATES = 3  # orders offered to integrator=auto (it measures each, lowest first, and takes the first that meets)


@lru_cache(maxsize=32)
def _series(body: lindstedt.Body, order: int, tilt: float) -> lindstedt.LindstedtSeries:
    return lindstedt.series(body, order, tilt=tilt)


def series_body(s: NondimensionalScene) -> lindstedt.Body:
    return lindstedt.Body(a=s.a, b=s.b, x0=s.x0, y0=s.y0, z0=s.z0, k=s.k)


def finite_tilt_frequency(P: paper.Params) -> float:
    """Ω = 2π/T_τ through ε³ at a fixed tilt γ0'' (the ε³ term vanishes by symmetry).

    The ε² coefficient is −[x0'√(1 − γ0''²) − z0'γ0'' + (k/4)(b − a − γ0''²(a + 3b − 4))]: (36) with the finite
    tilt kept — its O(γ0''²) terms are O(ε⁴) in Ismail's (2021) scaling γ0'' = Γε, so (36) agrees with it there.
    Found from the numeric series' ε² coefficient (exact in γ0'') and checked against exact orbits'
    periods (tests/plugins/regimes/test_small_parameter.py).
    """
    g = P.g0
    return 1 - (P.x0 * np.sqrt(1 - g * g) - P.z0 * g
                + 0.25 * P.k * (P.b - P.a - g * g * (P.a + 3 * P.b - 4))) / P.mu**2


def refusal_distance(n: float, eps: float) -> float:
    """The widest |ω − n| that is refused at ε (the side below the resonance)."""
    return float(n - np.sqrt(max(n * n - divisor_threshold(n, eps), 0.0)))


class SmallParameter(FixedPointRegime):
    name = "small_parameter"
    parameter = "c/r0"
    parameter_long_name = "Poincaré's small parameter ε = c/r0 = √(Mgℓ/C)/r0 (Ismail's (2021) 1/μ)"
    order = {"pq": 3.0, "r": 4.0, "gamma": 4.0, "gamma3": 4.0, "period": 4.0}
    # the closed forms' period is exact through ε³; every listed order's differs from it from ε⁴ on, far below the
    # period where an order is listed (ε below half the radius of convergence): a factor 2 either way is generous
    period_spread = 2.0

    def __init__(self, *, formula: str = "corrected", periods: int = 3, samples_per_period: int = 200,
                 order: int | None = None) -> None:
        super().__init__(formula=formula, periods=periods, samples_per_period=samples_per_period)
        if order is not None and (isinstance(order, bool) or not isinstance(order, int) or not 1 <= order <= MAX_ORDER):
            raise ConfigError(f"regime.order={order!r} must be an integer from 1 to {MAX_ORDER} (or null: the "
                              "paper's closed forms)")
        if order is not None and formula == "printed":
            raise ConfigError("regime.order selects the numeric series, which has no printed form; "
                              "use regime.formula=corrected with regime.order, or drop regime.order")
        self.series_order = order
        if order is not None:
            # fixed tilt: p, q carry the odd powers of ε, r and the γ's the even ones, Ω is even
            odd, even = (order + 1 if (order + 1) % 2 else order + 2), (order + 1 if order % 2 else order + 2)
            self.order = {"pq": float(odd), "r": float(even), "gamma": float(even), "gamma3": float(even),
                          "period": float(even)}

    def series(self, system) -> lindstedt.LindstedtSeries:
        """The numeric Lindstedt series of the scene's orbit, through max(order + 1, RADIUS_ORDER)."""
        s = self.scene(system)
        self.check_series_domain(s)
        return _series(series_body(s), max((self.series_order or 3) + 1, RADIUS_ORDER), float(s.gamma0pp))

    def check_series_domain(self, s: NondimensionalScene) -> None:
        if not abs(s.gamma0pp) < 1:
            raise ConfigError(f"regime small_parameter needs a tilted axis, 0 < θ0 < π, got θ0={s.theta0:.4g}")

    def with_order(self, order: int) -> SmallParameter:
        return SmallParameter(formula=self.formula, periods=self.periods, samples_per_period=self.samples_per_period,
                              order=order)

    def series_candidates(self, system, accuracy: float) -> list[tuple[SmallParameter, float]]:
        """(regime at order N, its predicted max error in model units: the first omitted term), the lowest
        ``CANDIDATES`` orders predicted to meet ``accuracy``, after the closed forms (auto measures them) when the
        regime has no order of its own; none beyond half the radius of convergence, where the estimate is not
        trustworthy.
        """
        s = self.scene(system)
        out = [(self, float("nan"))] if self.series_order is None else []  # the closed forms, measured by auto
        if not s.r0 > 1 or not abs(s.gamma0pp) < 1:
            return out
        eps = 1.0 / s.r0
        sol = self.series(system)
        if not eps < 0.5 * sol.radius_of_convergence():
            return out
        for n in range(1, sol.max_order):
            estimate = sol.error_estimate(eps, n, (s.c, s.c, s.c / eps, 1.0, 1.0, 1.0))
            if estimate <= accuracy:
                out.append((self.with_order(n), estimate))
            if len(out) == CANDIDATES + (self.series_order is None):
                break
        return out

    def attributes(self) -> dict[str, Any]:
        order = "paper (closed forms)" if self.series_order is None else int(self.series_order)
        return {**super().attributes(), "regime_order": order}

    def diagnostics(self, system) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
        """Series coefficients, radius of convergence, small divisors and the measured order-N error slope."""
        return ({}, {}, {}) if self.series_order is None else series_diagnostics(self, system)

    def params(self, s: NondimensionalScene) -> paper.Params:
        return paper.Params(a=s.a, b=s.b, x0=s.x0, y0=s.y0, z0=s.z0, k=s.k, mu=s.r0, g0=s.gamma0pp)

    def parameter_value(self, system) -> float:
        s = self.scene(system)
        return 1.0 / s.r0 if s.r0 != 0 else np.inf

    def check_domain(self, system) -> list[str]:
        s = self.scene(system)
        eps = 1.0 / s.r0 if s.r0 > 0 else np.inf
        if not 0 < eps < 1:
            raise ConfigError(f"regime small_parameter needs fast spin, 0 < c/r0 < 1, but initial.r0 gives "
                              f"c/r0={eps:.4g}; choose r0 > c (r0 ≥ 5c for errors below ~1e-3)")
        warnings = _resonance_warnings(s.omega2, eps)
        if eps > 0.2 and self.series_order is None:  # the order-N series warns at half its radius instead
            warnings.append(f"c/r0 = {eps:.3g} > 0.2: near the edge of the fast-spin domain, expect errors of "
                            f"order (c/r0)² ≈ {eps**2:.2g}")
        if self.series_order is not None:
            return warnings + self._series_warnings(system, eps) + self.reseat_warnings(system)
        gamma = s.gamma0pp / eps
        if abs(gamma) > 3:
            warnings.append(f"Γ = cos θ0 · r0/c = {gamma:.3g}: the closed forms assume cos θ0 = O(c/r0) "
                            "(a nearly horizontal axis, Ismail (2021) eq. 28); expect errors of order cos⁴θ0 in the γ's "
                            "(the period keeps the finite tilt); regime.order=N gives the finite-tilt series")
        if abs(s.a + s.b - 1) < 0.05:
            warnings.append(f"a + b − 1 = {s.a + s.b - 1:.3g}: the z0'/(a + b − 1) terms of (35) are large")
        return warnings + self.reseat_warnings(system)

    def _series_warnings(self, system, eps: float) -> list[str]:
        """The order-N series' domain: ConfigError beyond its radius of convergence, a warning beyond half of it."""
        R = self.series(system).radius_of_convergence()  # (``series`` checks the tilt first)
        if not eps < R:
            raise ConfigError(f"regime small_parameter with order={self.series_order} needs c/r0 below the "
                              f"series' radius of convergence {R:.3g} (estimated from its coefficients), but "
                              f"c/r0={eps:.4g}; choose r0/c > {1 / R:.3g}")
        if eps > 0.5 * R:
            return [f"c/r0 = {eps:.3g} is beyond half the series' radius of convergence {R:.3g}: "
                    f"the error falls only like ({eps / R:.2f})^(N+1) with the order N"]
        return []

    def reduced_rhs(self, system):
        """The reduced quasilinear system (000 eq. 14 through the μ⁻³ terms) for this scene: ``(rhs, Z0, to_model)``,
        ``rhs(τ, Z)`` = d/dτ of Z = (p2, ṗ2, γ2, γ̇2) (τ = r0 t), Z0 the orbit's τ = 0 state, ``to_model`` mapping a
        (4, n) solution to (n, 6) model-unit states (errors, the printed variant: docs/regimes.md, "Reduced systems").
        """
        s = self.scene(system)
        P = self.params(s)
        S = paper.scaled(np.array([0.0]), P)
        Y0 = np.array([S[k][0] for k in ("p1", "q1", "r1", "g1", "g2", "g3")])
        Y0[3] = np.sqrt(1 - Y0[4] ** 2 - Y0[5] ** 2)
        Z0 = paper.reduced_from_scaled(Y0, P)
        printed = self.formula == "printed"

        def rhs(tau, Z):
            return paper.reduced_rhs(tau, Z, P, Z0, printed)

        def to_model(Z):
            Z = np.asarray(Z, dtype=float).reshape(4, -1)
            Y = np.array([paper.scaled_from_reduced(Z[:, i], P, Y0) for i in range(Z.shape[1])])
            y = paper.scaled_to_model({k: Y[:, i] for i, k in enumerate(("p1", "q1", "r1", "g1", "g2", "g3"))}, P)
            y[:, :3] *= s.c
            return y

        return rhs, Z0, to_model

    def _state(self, s, t):
        P = self.params(s)
        tau = s.r0 * t
        if self.series_order is not None:
            sol = _series(series_body(s), max(self.series_order + 1, RADIUS_ORDER), float(s.gamma0pp))
            y = sol.scaled(1.0 / s.r0, tau, self.series_order)
            y[:, 2] *= s.r0
            return y
        if self.formula == "printed":
            return paper.scaled_to_model(paper.printed_scaled(tau, P), P)
        # the closed forms in the finite-tilt strained time s = Ωτ (they evaluate s = frequency(P)·τ)
        return paper.scaled_to_model(paper.scaled(tau * finite_tilt_frequency(P) / paper.frequency(P), P), P)

    def _omega(self, s) -> float:
        P = self.params(s)
        if self.series_order is not None:
            sol = _series(series_body(s), max(self.series_order + 1, RADIUS_ORDER), float(s.gamma0pp))
            return float(sol.frequency(1.0 / s.r0, self.series_order))
        return paper.printed_frequency(P) if self.formula == "printed" else finite_tilt_frequency(P)

    def _period(self, s):
        return 2 * np.pi / (self._omega(s) * s.r0)

    def _euler(self, s, t):
        P = self.params(s)
        if self.series_order is not None:
            return self._series_euler(s, t)
        if self.formula == "printed":
            return paper.printed_euler(t, P)
        return paper.euler(t * finite_tilt_frequency(P) / paper.frequency(P), P)

    def _series_euler(self, s, t):
        """θ = arccos γ'', φ = π/2 + s + a periodic part, ψ from ψ̇ = (pγ + qγ')/(1 − γ''²) integrated exactly
        (spectrally in s: its mean gives the precession rate, its harmonics the periodic part)."""
        sol = _series(series_body(s), max(self.series_order + 1, RADIUS_ORDER), float(s.gamma0pp))
        eps, omega = 1.0 / s.r0, self._omega(s)
        M = sol.fourier.shape[2]
        grid = 2 * np.pi * np.arange(M) / M
        Yg = sol.scaled(eps, grid / omega, self.series_order)
        dpsi_ds = (Yg[:, 0] * Yg[:, 3] + Yg[:, 1] * Yg[:, 4]) / (1 - Yg[:, 5] ** 2) / (omega * s.r0)
        spec = np.fft.fft(dpsi_ds) / M
        n = np.fft.fftfreq(M, 1.0 / M)
        u = omega * s.r0 * np.asarray(t, dtype=float)
        periodic = np.zeros_like(u)
        for m in np.nonzero(n)[0]:
            periodic += np.real(spec[m] / (1j * n[m]) * (np.exp(1j * n[m] * u) - 1))
        Y = sol.scaled(eps, s.r0 * np.asarray(t, dtype=float), self.series_order)
        phi = np.pi / 2 + u + np.angle((Y[:, 4] + 1j * Y[:, 3]) * np.exp(-1j * (np.pi / 2 + u)))
        return {"theta": np.arccos(np.clip(Y[:, 5], -1, 1)), "psi": np.real(spec[0]) * u + periodic, "phi": phi}


def series_diagnostics(regime: SmallParameter, system) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Dataset variables and attributes of an order-N run: coefficients' sizes, Ω_k, radius, small divisors,
    and the order-N error against exact orbits at four ε (chosen where it is measurable) with its fitted slope."""
    s = regime.scene(system)
    sol = regime.series(system)
    N = regime.series_order
    radius = sol.radius()
    R = sol.radius_of_convergence()
    ladder = lindstedt_check.error_ladder(sol, N, float(s.gamma0pp))
    k = np.arange(sol.max_order + 1)
    data = {
        "series_coefficient_norm": ("series_order", sol.norms(), {
            "units": "1", "long_name": "max-norm of the ε^k coefficient Y_k of (p/c, q/c, r/r0, γ, γ', γ'') "
                                       "(sum of |Fourier coefficients|)"}),
        "series_frequency_coefficient": ("series_order", sol.omega, {
            "units": "1", "long_name": "ε^k coefficient Ω_k of the τ-frequency Ω = 2π/T_τ (τ = r0 t)"}),
        "series_consistency_residual": ("series_order", sol.consistency, {
            "units": "1", "long_name": "residual of the solvability conditions the first integrals satisfy "
                                       "(round-off when the series is right)"}),
        "series_ladder_eps": ("ladder", ladder["eps"], {
            "units": "1", "long_name": "c/r0 of the exact orbits the order-N series is checked against"}),
        "series_ladder_error": ("ladder", ladder["state"], {
            "units": "1", "long_name": "max error of the order-N series over one period against the exact orbit "
                                       "(p/c, q/c, r/r0, γ's)"}),
    }
    coords = {"series_order": ("series_order", k, {"units": "1", "long_name": "power k of ε = c/r0"}),
              "ladder": ("ladder", np.arange(len(ladder["eps"])), {"units": "1", "long_name": "ladder point"})}
    divisors = sol.small_divisors
    attrs = {
        "series_order": int(N),
        "series_expected_error_slope": float(regime.order["pq"] if N % 2 == 0 else regime.order["gamma"]),
        "series_error_slope": float(ladder["slope"]),
        "series_radius_of_convergence": float(R),
        "series_radius_root_test": float(radius["root"]),
        "series_radius_domb_sykes_norm": float(radius["domb_sykes_norm"]),
        "series_radius_pade": float(radius["pade"]),
        "series_min_r0_over_c": float(1 / R),
        "series_scene_eps_over_radius": float((1 / s.r0) / R),
        "series_small_divisors": [float(divisors[n]) for n in sorted(divisors)],
        "series_small_divisors_long_name": "n² − ω² for n = 0, 1, …: the p-mode divisors of the coefficients",
        "series_consistency_max": float(np.max(sol.consistency)),
    }
    return data, coords, attrs


def _resonance_warnings(w2: float, eps: float) -> list[str]:
    """ConfigError at a resonance ω = n the series excludes; warnings near one, and for ω² ≤ 0."""
    w = np.sqrt(w2) if w2 > 0 else 0.0
    for n in RESONANCES:
        if w2 > 0 and abs(n * n - w2) < divisor_threshold(n, eps):
            raise ConfigError(f"regime small_parameter excludes the resonance ω = {n:g}: the body has "
                              f"ω = {w:.5g} (ω² = (C−A)(C−B)/(AB)), |{n:g}² − ω²| = {abs(n * n - w2):.3g} < "
                              f"{divisor_threshold(n, eps):.3g} at c/r0 = {eps:.3g}; choose a, b with |ω − {n:g}| ≥ "
                              f"{refusal_distance(n, eps):.3g} or spin faster"
                              + (" (or regime=resonant_omega3)" if n == 3 else ""))
    warnings = [f"ω = {w:.4g} is within {WARN_DISTANCE:g} of the excluded resonance ω = {n:g}: terms ∝ "
                f"1/({n:g}² − ω²) = {1 / (n * n - w2):.3g} amplify the error"
                for n in RESONANCES if w2 > 0 and abs(w - n) < WARN_DISTANCE]
    if w2 <= 0:
        warnings.append(f"ω² = {w2:.4g} ≤ 0 (A, B on both sides of C): the generating p-mode is not an "
                        "oscillation; the expansion is untested there")
    return warnings
