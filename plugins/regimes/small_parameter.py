"""Fast spin about a fixed point: Poincaré's small-parameter periodic solution, ε = c/r0 ≪ 1 (seed 000, corrected).

Seed 000 (Ismail 2021) calls this a "large-parameter" method for small r0,
but its equations (1)-(2) are consistent only with μ = r0/c (report §3 of
``docs/derivations/seed000_large_parameter.md``): it is the classical fast-top
expansion in ε = 1/μ = c/r0 = √(Mgℓ/C)/r0. This plugin is that expansion,
with the corrected (35), (36), (38)-(39) (``gyrolab.plugins.regimes.ismail2021``);
``formula=printed`` evaluates the paper's printed formulas in the same
consistent scaling.

Domain: ε < 1 (warning above 0.2), ω away from the resonances 1, 2, 3 of
the generating system (refused where |n² − ω²| < ``divisor_threshold(n, ε)``, a band that
narrows as the spin grows: ε^(4/3) at ω = 1, ε³ at ω = 2, 3), and γ0'' = cos θ0 = O(ε) (the derivation sets
γ0'' = Γ/μ; warning when Γ = γ0''/ε > 3). Theory error orders in ε:
p, q 3; r, γ, γ', γ'' 4; period 4 (corrected) — the printed r, γ, γ' are 2.
"""

from __future__ import annotations

import numpy as np

from gyrolab.errors import ConfigError
from gyrolab.plugins.regimes import ismail2021 as paper
from gyrolab.plugins.regimes.base import FixedPointRegime, NondimensionalScene

RESONANCES = (1.0, 2.0, 3.0)
WARN_DISTANCE = 0.1
# Refusal band around a resonance, |n² − ω²| < divisor_threshold(n, ε), where the error against the exact orbit
# reaches ~1e-2 (measured by regime_validity's resonance sweep, body I, c/r0 = 0.1, 0.05, 0.025; docs/regimes.md):
# near ω = 2 the error is 5.7 ε^2.96 / |4 − ω²|^0.95 (the ε³ terms carry one small divisor), hence ε³/|n² − ω²|
# ≤ 1/580; near ω = 1 (1:1 with the γ-mode) it blows up at |1 − ω²| ≈ 0.11, 0.042, 0.017, i.e. ∝ ε^(4/3): the
# detuning at which a weakly nonlinear oscillator with forcing ε and frequency shift ε²A² folds.
REFUSE_CUBIC = 580.0
REFUSE_ONE_TO_ONE = 2.28


def divisor_threshold(n: float, eps: float) -> float:
    """|n² − ω²| below which small_parameter refuses the scene (ε = c/r0).

    Capped at |ω − n| = WARN_DISTANCE: farther out the error is the generic O(ε³) one (within 2–3× of its value
    far from every resonance), which the slow-spin warning (c/r0 > 0.2) covers, not a small divisor.
    """
    rule = REFUSE_ONE_TO_ONE * eps ** (4 / 3) if n == 1.0 else REFUSE_CUBIC * eps**3
    return min(rule, n * n - (n - WARN_DISTANCE) ** 2)


def refusal_distance(n: float, eps: float) -> float:
    """The widest |ω − n| that is refused at ε (the side below the resonance)."""
    return float(n - np.sqrt(max(n * n - divisor_threshold(n, eps), 0.0)))


class SmallParameter(FixedPointRegime):
    name = "small_parameter"
    parameter = "c/r0"
    parameter_long_name = "Poincaré's small parameter ε = c/r0 = √(Mgℓ/C)/r0 (seed 000's 1/μ)"
    order = {"pq": 3.0, "r": 4.0, "gamma": 4.0, "gamma3": 4.0, "period": 4.0}
    printed_order = {"pq": 3.0, "r": 2.0, "gamma": 2.0, "gamma3": 4.0, "period": 2.0}

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
        w2 = s.omega2
        w = np.sqrt(w2) if w2 > 0 else 0.0
        for n in RESONANCES:
            if w2 > 0 and abs(n * n - w2) < divisor_threshold(n, eps):
                raise ConfigError(f"regime small_parameter excludes the resonance ω = {n:g}: the body has "
                                  f"ω = {w:.5g} (ω² = (C−A)(C−B)/(AB)), |{n:g}² − ω²| = {abs(n * n - w2):.3g} < "
                                  f"{divisor_threshold(n, eps):.3g} at c/r0 = {eps:.3g}; choose a, b with |ω − {n:g}| ≥ "
                                  f"{refusal_distance(n, eps):.3g} or spin faster"
                                  + (" (or regime=resonant_omega3)" if n == 3 else ""))
        warnings = []
        for n in RESONANCES:
            if w2 > 0 and abs(w - n) < WARN_DISTANCE:
                warnings.append(f"ω = {w:.4g} is within {WARN_DISTANCE:g} of the excluded resonance ω = {n:g}: "
                                f"terms ∝ 1/({n:g}² − ω²) = {1 / (n * n - w2):.3g} amplify the error")
        if w2 <= 0:
            warnings.append(f"ω² = {w2:.4g} ≤ 0 (A, B on both sides of C): the generating p-mode is not an "
                            "oscillation; the expansion is untested there")
        if eps > 0.2:
            warnings.append(f"c/r0 = {eps:.3g} > 0.2: near the edge of the fast-spin domain, expect errors of "
                            f"order (c/r0)² ≈ {eps**2:.2g}")
        gamma = s.gamma0pp / eps
        if abs(gamma) > 3:
            warnings.append(f"Γ = cos θ0 · r0/c = {gamma:.3g}: the expansion assumes cos θ0 = O(c/r0) "
                            "(a nearly horizontal axis, seed 000 eq. 28); expect larger errors")
        if abs(s.a + s.b - 1) < 0.05:
            warnings.append(f"a + b − 1 = {s.a + s.b - 1:.3g}: the z0'/(a + b − 1) terms of (35) are large")
        return warnings + self.reseat_warnings(system)

    def reduced_rhs(self, system):
        """The reduced quasilinear system (000 eq. 14 through the μ⁻³ terms, corrected F3, Φ3) for this scene.

        Returns ``(rhs, Z0, to_model)``: ``rhs(τ, Z)`` gives d/dτ of Z = (p2, ṗ2, γ2, γ̇2) (τ = r0 t, any
        integrator); Z0 is the orbit's τ = 0 state (that of ``initial_state`` with r = r0, γ'' = γ0'');
        ``to_model(Z, Z0)`` maps a (4, n) solution back to (n, 6) model-unit states (p, q, r, γ, γ', γ'')
        at t = τ/(c r0). ``formula=printed`` uses the printed Φ2, F3, Φ3 (errata 000-3, 000-4). Error against the
        full model over a period: O(μ⁻⁴) from a generic state, p, q O(μ⁻⁵) on the periodic orbit
        (tests/test_erratum_000_4.py).
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
        S = paper.printed_scaled(tau, P) if self.formula == "printed" else paper.scaled(tau, P)
        return paper.scaled_to_model(S, P)

    def _period(self, s):
        P = self.params(s)
        omega = paper.printed_frequency(P) if self.formula == "printed" else paper.frequency(P)
        return 2 * np.pi / (omega * s.r0)

    def _euler(self, s, t):
        P = self.params(s)
        return paper.printed_euler(t, P) if self.formula == "printed" else paper.euler(t, P)
