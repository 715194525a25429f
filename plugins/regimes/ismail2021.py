"""The fast-spin periodic solution of Ismail (2021), printed and corrected.

A. I. Ismail, "The periodic rotary motions of a rigid body in a new domain of
angular velocity", J. Egypt. Math. Soc. 29:2 (2021). Verification report:
``docs/derivations/seed000_large_parameter.md`` (cited below as "report §n").

Scaling (the only one consistent with the paper's eqs. (1)-(2), report §3;
the paper's eq. (4) prints μ = c/r0, which contradicts them):

    μ = r0/c (≫ 1: FAST spin),  ε = 1/μ = c/r0,  τ = r0 t,
    p1 = p/c, q1 = q/c, r1 = r/r0,  γ0'' = Γ/μ (eq. 28),  k = N/c².

Notation: a = A/C, b = B/C, A1 = (1−b)/a, B1 = (a−1)/b, C1 = b−a,
ω² = −A1B1 (eq. 5); (x0', y0', z0') = unit centre-of-mass direction.
All functions are plain numpy on floats; times in units of 1/c, rates in c
(multiply by c, divide by c for another unit system).

Validity (report §5, §9): generic ω away from 1, 2, 3 (denominators 1−ω²,
4−ω², 9−ω²), M1 = M2 = 0, μ ≫ 1 and Γ = μγ0'' = O(1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gyrolab.plugins.regimes.notation import BodyRatios


@dataclass(frozen=True)
class Params(BodyRatios):
    """Body and orbit in the paper's nondimensional form (time unit 1/c)."""

    k: float  # N/c²
    mu: float  # r0/c
    g0: float  # γ0'' = cos θ0

    @property
    def omega2(self) -> float:
        """ω² = −A1B1 = (C−A)(C−B)/(AB) (eq. 5)."""
        return -self.A1 * self.B1

    @property
    def chi1(self) -> float:
        """χ1 = (1−ω²)⁻¹[−z0'(a⁻¹ − A1b⁻¹) + kγ0''(A1 − ω²)] (eq. 10)."""
        return (-self.z0 * (1 / self.a - self.A1 / self.b) + self.k * self.g0 * (self.A1 - self.omega2)) / (1 - self.omega2)

    @property
    def chi2(self) -> float:
        """χ2 = χ1 + z0'a⁻¹ − kA1γ0'' (eq. 10)."""
        return self.chi1 + self.z0 / self.a - self.k * self.A1 * self.g0


# -- corrected (report §5.1, derived independently by Lindstedt–Poincaré) -----------------------------
def frequency(P: Params) -> float:
    """Ω = 2π/T_τ = 1 − μ⁻²(x0' + kC1/4 − z0'γ0'') + O(μ⁻⁴) (corrected (36), report §5.2)."""
    return 1 - (P.x0 + 0.25 * P.k * P.C1 - P.z0 * P.g0) / P.mu**2


def period_correction(P: Params, n: int = 1) -> float:
    """α = T_τ − 2πn (corrected (36)): 2πnμ⁻²(x0' − z0'γ0'' + kC1/4) + O(μ⁻⁴)."""
    return 2 * np.pi * n * (P.x0 - P.z0 * P.g0 + 0.25 * P.k * P.C1) / P.mu**2


def scaled(tau: np.ndarray, P: Params) -> dict[str, np.ndarray]:
    """Corrected (35) in strained time s = Ωτ: p1, q1 O(μ⁻³), r1, γ's O(μ⁻⁴) (report §5.3)."""
    e, g0, C1, x, y, z, a, b = 1 / P.mu, P.g0, P.C1, P.x0, P.y0, P.z0, P.a, P.b
    kc = P.k * C1
    s = frequency(P) * np.asarray(tau, dtype=float)
    cs, ss, c2, s2, c3, s3 = np.cos(s), np.sin(s), np.cos(2 * s), np.sin(2 * s), np.cos(3 * s), np.sin(3 * s)
    p1 = e * (x * g0 / (1 - a) + P.chi1 * cs)
    q1 = e * (y * g0 / (1 - b) + P.chi2 / P.A1 * ss)
    r1 = 1 - e**2 * (x * (1 - cs) + y * ss + 0.25 * kc * (1 - c2))
    g1 = (1 - 0.5 * g0**2) * cs + e**2 * (kc / 16 * (c3 - cs) - 0.5 * x * (1 - c2) + y * (ss - 0.5 * s2))
    g2 = -(1 - 0.5 * g0**2) * ss + e**2 * (-kc / 16 * (ss + s3) - 0.5 * x * s2 + y * (cs - 0.5 - 0.5 * c2)
                                           - g0 * z * C1 / (a + b - 1) * ss)
    g3 = g0 + e**2 * (-z * C1 / (a + b - 1) * ss**2
                      + g0 * (x / (1 - a) * (1 - cs) + y / (1 - b) * ss - 0.25 * kc * (1 - c2)))
    return dict(p1=p1, q1=q1, r1=r1, g1=g1, g2=g2, g3=g3, s=s)


def euler(t: np.ndarray, P: Params) -> dict[str, np.ndarray]:
    """Corrected (38)-(39), t in 1/c, ψ(0) = 0, φ(0) = π/2 (report §6): θ, ψ O(μ⁻⁴), φ O(μ⁻³·⁵)."""
    e, g0, C1, A1, x, y, z, a, b, k = 1 / P.mu, P.g0, P.C1, P.A1, P.x0, P.y0, P.z0, P.a, P.b, P.k
    r0 = P.mu
    t = np.asarray(t, dtype=float)
    s = frequency(P) * r0 * t
    th0 = np.arccos(g0)

    def th2(u):
        return (y * g0 / (1 - b) * np.sin(u) - x * g0 / (1 - a) * np.cos(u)
                + 0.5 * C1 * (z / (a + b - 1) + 0.5 * k * g0) * np.cos(2 * u))

    def ps1(u):
        return (0.25 * (P.chi1 + P.chi2 / A1) * np.sin(2 * u) + y * g0 / (1 - b) * np.cos(u)
                + x * g0 / (1 - a) * np.sin(u))

    theta = th0 - e**2 / np.sin(th0) * (th2(s) - th2(0.0))
    psi = 0.5 / r0 * (P.chi1 - P.chi2 / A1) * t + e**2 * (ps1(s) - ps1(0.0))
    phi = np.pi / 2 + s + e**2 * (x * np.sin(s) + y * (np.cos(s) - 1) + k * C1 / 8 * np.sin(2 * s))
    return dict(theta=theta, psi=psi, phi=phi)


# -- as printed (all three extractions agree unless noted; report §5.2, §6) --------------------------
def printed_period_correction(P: Params, n: int = 1) -> float:
    """α of (36) as printed (003/004; M3 = 1): C1 coefficient 1/16 and a spurious B1γ0''(1−γ0'') term."""
    return 2 * np.pi * n / P.mu**2 * (P.x0 - P.z0 * P.g0 - 0.5 * P.k * (
        P.g0**2 * (P.b * P.B1 - P.a * P.A1) + P.B1 * P.g0 * (1 - P.g0) - 0.125 * P.C1))


def printed_frequency(P: Params) -> float:
    """Ω = 2π/(2π + α) with the printed α (used for the printed period only)."""
    return 2 * np.pi / (2 * np.pi + printed_period_correction(P))


def printed_scaled(tau: np.ndarray, P: Params) -> dict[str, np.ndarray]:
    """(35) as printed (M3 = 1), evaluated at the unstrained τ as the paper does."""
    e, g0, C1, x, y, z, a, b, k = 1 / P.mu, P.g0, P.C1, P.x0, P.y0, P.z0, P.a, P.b, P.k
    tau = np.asarray(tau, dtype=float)
    ct, st = np.cos(tau), np.sin(tau)
    Gam = g0 * P.mu
    p1 = e * (x * g0 / (1 - a) + P.chi1 * ct)
    q1 = e * (y * g0 / (1 - b) + P.chi2 / P.A1 * st)
    r1 = 1 - 0.25 * e**2 * (k * C1 + 4 * x * (1 - ct) + y * st - k * C1 * np.cos(2 * tau))
    g1 = ct - 0.5 * e**2 * Gam**2 * ct
    g2 = -st + 0.5 * e**2 * Gam**2 * st
    g3 = g0 + e**2 * (x * g0 / (1 - a) - 0.5 * C1 * (z / (a + b - 1) + 0.5 * k * g0)
                      - x * g0 / (1 - a) * ct + y * g0 / (1 - b) * st
                      + 0.25 * C1 * (2 * z / (a + b - 1) + k * g0) * np.cos(2 * tau))
    return dict(p1=p1, q1=q1, r1=r1, g1=g1, g2=g2, g3=g3, s=tau)


def printed_euler(t: np.ndarray, P: Params) -> dict[str, np.ndarray]:
    """(38)-(39) exactly as printed (r0⁻¹t arguments, '+ sin 2r0⁻¹t', prefactor μ⁻¹c, θ sign +, −0.667k)."""
    e, g0, C1, A1, x, y, z, a, b, k = 1 / P.mu, P.g0, P.C1, P.A1, P.x0, P.y0, P.z0, P.a, P.b, P.k
    r0 = P.mu
    w = 1 / r0
    th0 = np.arccos(g0)
    t = np.asarray(t, dtype=float)

    def th2(u):
        return (y * g0 / (1 - b) * np.sin(w * u) - x * g0 / (1 - a) * np.cos(w * u)
                + 0.5 * C1 * (z / (a + b - 1) - 0.667 * k * g0) * np.cos(2 * w * u))

    def ps1(u):
        return (0.25 * (P.chi1 + P.chi2 / A1) + np.sin(2 * w * u) + y * g0 / (1 - b) * np.cos(w * u)
                + x * g0 / (1 - a) * np.sin(w * u))

    theta = th0 + e**2 / np.sin(th0) * (th2(t) - th2(0.0))
    psi = 0.5 / r0 * (P.chi1 - P.chi2 / A1) * t + e * (ps1(t) - ps1(0.0))
    phi = np.pi / 2 + (w - 0.5 / r0 * g0 * (P.chi1 - P.chi2 / A1)) * t
    return dict(theta=theta, psi=psi, phi=phi)


def scaled_to_model(S: dict[str, np.ndarray], P: Params) -> np.ndarray:
    """(p, q, r, γ, γ', γ'') in units of c from the scaled solution: p = c p1, r = r0 r1 (report §3)."""
    return np.stack([S["p1"], S["q1"], P.mu * S["r1"], S["g1"], S["g2"], S["g3"]], axis=-1)


# -- reduced quasilinear system (000 eq. 1: the scaled equations integrated in τ) ---------------------
def scaled_rhs(tau: float, Y: np.ndarray, P: Params) -> np.ndarray:
    """The paper's eq. (1) in τ = r0 t, Y = (p1, q1, r1, γ, γ', γ''); exact (it is the full model rescaled)."""
    return euler_poisson_scaled(Y, 1 / P.mu, P)


def euler_poisson_scaled(Y: np.ndarray, e: float, P: BodyRatios) -> np.ndarray:
    """The Euler–Poisson equations of both papers' scalings: d/dτ of Y = (p1, q1, r1, γ, γ', γ'') with small
    parameter ``e`` and the body, centre-of-mass direction and k of ``P`` (its fields a, b, x0, y0, z0, k)."""
    a, b, x, y, z, k, A1, B1, C1 = P.a, P.b, P.x0, P.y0, P.z0, P.k, P.A1, P.B1, P.C1
    p, q, r, g1, g2, g3 = Y
    return np.array([
        -A1 * q * r + e / a * (g3 * y - g2 * z + k * a * A1 * g2 * g3),
        -B1 * p * r + e / b * (g1 * z - g3 * x + k * b * B1 * g3 * g1),
        e**2 * (-C1 * p * q + g2 * x - g1 * y + k * C1 * g1 * g2),
        r * g2 - e * q * g3,
        e * p * g3 - r * g1,
        e * (q * g1 - p * g2)])


# -- the reduction (7), (9)-(14) term by term (errata 000-2, 000-3; report §4) ------------------------
# Every function below is plain numpy and accepts a complex μ (so that tests can take Taylor coefficients
# in ε = 1/μ by Cauchy integrals). The right-hand side ``scaled_rhs`` is quadratic in the state, so
# its Jacobian applied to v is exactly (f(Y + v) − f(Y − v))/2.
def flow_derivative(Y: np.ndarray, P: Params) -> tuple[np.ndarray, np.ndarray]:
    """(Ẏ, Ÿ) of the paper's eq. (1) at Y (d/dτ): Ÿ = J(Y)Ẏ, exact because (1) is quadratic."""
    f = scaled_rhs(0.0, Y, P)
    return f, 0.5 * (scaled_rhs(0.0, Y + f, P) - scaled_rhs(0.0, Y - f, P))


def state_from_integrals(p1, q1, g1, g2, s2, s3, P: Params, iterations: int = 60) -> np.ndarray:
    """Y = (p1, q1, r1, γ, γ', γ'') with r1, γ'' from the integrals (2)-(3) for given s2, s3 (eq. 6).

    r1² = 1 + μ⁻²s1, s1 = s3 − 2z0'(γ0'' − γ'') + k(γ0''² − γ''²); r1γ'' = γ0'' + μ⁻¹s2 (fixed point).
    """
    e, g0, z, k = 1 / P.mu, P.g0, P.z0, P.k
    r1, g3 = 1.0 + 0j * e, g0 + 0j * e
    for _ in range(iterations):
        s1 = s3 - 2 * z * (g0 - g3) + k * (g0**2 - g3**2)
        r1 = np.sqrt(1 + e**2 * s1)
        g3 = (g0 + e * s2) / r1
    return np.array([p1, q1, r1, g1, g2, g3])


def eq7_gamma_mu2(p1, q1, g1, g2, s2, s3, P: Params, printed: bool = False):
    """μ⁻² coefficient of γ̈ + γ in eq. (7) (the γ-equation), at the state of ``state_from_integrals``.

    −γ[s3 + y0'γ' + z0'b⁻¹γ0'' + q1² ∓ k(C1γ'² − B1γ0''²)] + p1[(1+B1)s2 + (1−C1)q1γ'] + x0'(b⁻¹γ0''² + γ'²).
    Printed: "+k(C1γ'² − B1γ0''²)" inside the bracket; corrected "−k(…)" (erratum 000-2).
    """
    g0, x, y, z, k, b, B1, C1 = P.g0, P.x0, P.y0, P.z0, P.k, P.b, P.B1, P.C1
    sign = 1.0 if printed else -1.0
    return (p1 * ((1 + B1) * s2 + (1 - C1) * q1 * g2)
            - g1 * (s3 + y * g2 + z * g0 / b + q1**2 + sign * k * (C1 * g2**2 - B1 * g0**2))
            + x * (g0**2 / b + g2**2))


def eq12_s11_s21(Z: np.ndarray, Z0: np.ndarray, P: Params) -> tuple:
    """s11, s21 of eq. (12) for Z = (p2, ṗ2, γ2, γ̇2) and the initial Z0 (the leading parts of s1, s2)."""
    a, b, x, y, k, A1 = P.a, P.b, P.x0, P.y0, P.k, P.A1
    Pn, Pd, G, Gd = Z[0], Z[1], Z[2], Z[3]
    P0, Pd0, G0, Gd0 = Z0[0], Z0[1], Z0[2], Z0[3]
    s11 = (a * (P0**2 - Pn**2) + b * (Pd0**2 - Pd**2) / A1**2 - 2 * (x * (G0 - G) + y * (Gd0 - Gd))
           + k * (a * (G0**2 - G**2) + b * (Gd0**2 - Gd**2)))
    s21 = a * (P0 * G0 - Pn * G) - b / A1 * (Pd0 * Gd0 - Pd * Gd)
    return s11, s21


def eq12_s12_s22(Z: np.ndarray, Z0: np.ndarray, P: Params) -> tuple:
    """s12, s22 of eq. (12): s1 = s11 + 2μ⁻¹s12 + …, s2 = s21 + μ⁻¹s22 + … (correct as printed, y0' reading)."""
    a, b, x, y, z, k, g0, A1, chi1, chi2 = P.a, P.b, P.x0, P.y0, P.z0, P.k, P.g0, P.A1, P.chi1, P.chi2
    Pn, Pd, G, Gd = Z[0], Z[1], Z[2], Z[3]
    P0, Pd0, G0, Gd0 = Z0[0], Z0[1], Z0[2], Z0[3]
    _, s21 = eq12_s11_s21(Z, Z0, P)
    xa = x / (1 - a)
    dPG, dPdGd = P0 * G0 - Pn * G, Pd0 * Gd0 - Pd * Gd
    s12 = (a * (xa * g0 * (P0 - Pn) + chi1 * dPG) - b / A1**2 * (y / a * g0 * (Pd0 - Pd) - chi2 * dPdGd)
           - a * x * g0 * (P0 - Pn) + y * b / A1 * g0 * (Pd0 - Pd) + (z - k * g0) * s21
           + k * g0 * (a**2 * dPG - b**2 / A1 * dPdGd))
    s22 = (a * (a * g0 * (P0**2 - Pn**2) + xa * g0 * (G0 - G) + chi1 * (G0**2 - G**2))
           + b / A1 * (b / A1 * g0 * (Pd0**2 - Pd**2) + y / a * g0 * (Gd0 - Gd) - chi2 * (Gd0**2 - Gd**2)))
    return s12, s22


def _eq14_f2_phi2(Z: np.ndarray, Z0: np.ndarray, P: Params, printed: bool = False) -> tuple:
    """f2, φ2 of eq. (14) (F2, Φ2 before the χ1, γ0'' terms of the change of variables (9))."""
    a, b, x, y, z, k, g0, A1, B1, C1, w2 = P.a, P.b, P.x0, P.y0, P.z0, P.k, P.g0, P.A1, P.B1, P.C1, P.omega2
    Pn, Pd, G, Gd = Z[0], Z[1], Z[2], Z[3]
    s11, s21 = eq12_s11_s21(Z, Z0, P)
    f2 = (x * (A1 / b * s21 + Pd * Gd) + Pd / A1 * (C1 * Pn * Pd - y * (2 * A1 + b / a) * G)
          - Pn * (w2 * s11 + y / a * Gd + z / a * g0)
          - k * (G * ((1 - C1) * Pd * Gd + A1 * (1 + B1) * s21) - A1 * Pn * (g0**2 - Gd**2)))
    phi2 = ((1 + B1) * Pn * s21 + x * (Gd**2 + (g0 if printed else g0**2) / b)
            - Pd / A1 * (G * Pd / A1 + (1 - C1) * Pn * Gd)
            - G * (s11 + z / b * g0 + y * Gd - k * (C1 * Gd**2 - B1 * g0**2)))
    return f2, phi2


def eq14_F2_Phi2(Z: np.ndarray, Z0: np.ndarray, P: Params, printed: bool = False) -> tuple:
    """F2, Φ2 of eq. (14): p̈2 + ω²p2 = μ⁻²F2 + O(μ⁻³), γ̈2 + γ2 = μ⁻²Φ2 + O(μ⁻³).

    F2 is correct as printed. Φ2 printed has x0'(γ̇2² + b⁻¹γ0''); corrected x0'(γ̇2² + b⁻¹γ0''²) (erratum 000-3).
    """
    a, g0, w2, chi1 = P.a, P.g0, P.omega2, P.chi1
    Pn, G = Z[0], Z[2]
    f2, phi2 = _eq14_f2_phi2(Z, Z0, P, printed)
    F2 = f2 - a * g0 * chi1 * (1 - w2) * Pn
    Phi2 = phi2 + a * g0 * (1 - w2) * (chi1 * G + g0 * P.x0 / (1 - a))
    return F2, Phi2


def eq14_F3_Phi3(Z: np.ndarray, Z0: np.ndarray, P: Params, printed: bool = False) -> tuple:
    """F3, Φ3 of eq. (14): p̈2 + ω²p2 = μ⁻²F2 + μ⁻³F3 + O(μ⁻⁴), γ̈2 + γ2 = μ⁻²Φ2 + μ⁻³Φ3 + O(μ⁻⁴).

    F3 = f3 − χ1Φ2, Φ3 = φ3 + aγ0''[aγ0''χ1(1−ω²)p2 − f2] as printed; f3, φ3 in the 000/004 reading
    (003 is corrupted there). Corrected = the ε³ Taylor coefficient of the full model in the variables (9),
    derived exactly in docs/derivations/scripts/seed000/derive_f3_phi3.py (erratum 000-4). With
    u = χ1γ2 + γ0''x0'/(1−a) (the μ⁻¹ shift of p1 in (9)), the printed → corrected terms are:

    F3 (f3 and the Φ2 it contains):
      (F-a) Φ2 inside F3: the erratum 000-3 typo b⁻¹γ0'' → b⁻¹γ0''², propagated by −χ1Φ2;
      (F-b) C1A1⁻¹ṗ2[ṗ2u + 2p2ṗ2(χ2γ̇2 − y0'a⁻¹γ0'')] → […+ 2p2(χ2γ̇2 − y0'a⁻¹γ0'')] (spurious ṗ2);
      (F-c) x0'-line −γ0''γ̇2(y0'a⁻¹ − χ2γ̇2) → −γ̇2(y0'a⁻¹γ0'' − χ2γ̇2) (γ0'' belongs to y0'a⁻¹ only);
      (F-d) y0'-line −y0'a⁻¹γ0''[γ̇2(χ1γ2 + x0'/(1−a)) − bA1⁻¹p2ṗ2]
            → −y0'a⁻¹[γ̇2 u − bA1⁻¹γ0''p2ṗ2] (no γ0'' on χ1γ2γ̇2; this is the y0'γ2γ̇2 term and, through
            the kγ0'' part of χ1, the only k-term that was wrong);
      (F-e) z0'-line −γ0''(χ1γ2 + x0'/(1−a)) → −γ0''u (x0'/(1−a) lost its γ0'').
    Φ3 (φ3):
      (Φ-a) (1−C1)A1⁻¹[… + p2γ̇2(y0'a⁻¹ − χ2γ̇2)] → p2γ̇2(y0'a⁻¹γ0'' − χ2γ̇2) (the slip of F-c);
      (Φ-b) the constant b⁻¹γ0''²x0' inside (1−C1)A1⁻¹[…] is spurious (removed).
    Everything else, including all other k-terms, s12, s22 and f2, is correct as printed.
    """
    a, b, x, y, z, k, g0, A1, B1, C1, w2, chi1, chi2 = (P.a, P.b, P.x0, P.y0, P.z0, P.k, P.g0, P.A1, P.B1,
                                                        P.C1, P.omega2, P.chi1, P.chi2)
    Pn, Pd, G, Gd = Z[0], Z[1], Z[2], Z[3]
    s11, s21 = eq12_s11_s21(Z, Z0, P)
    s12, s22 = eq12_s12_s22(Z, Z0, P)
    f2, _ = _eq14_f2_phi2(Z, Z0, P, printed)
    _, Phi2 = eq14_F2_Phi2(Z, Z0, P, printed)
    xa = x / (1 - a)
    u = chi1 * G + xa * g0
    ya = y / a
    if printed:
        c_line = 2 * Pn * Pd * (chi2 * Gd - ya * g0)
        x_line = g0 * Gd * (ya - chi2 * Gd)
        y_line = ya * g0 * (Gd * (chi1 * G + xa) - b / A1 * Pn * Pd)
        z_line = g0 * (chi1 * G + xa)
        p_line = Pn * Gd * (ya - chi2 * Gd) + x * g0**2 / b
    else:
        c_line = 2 * Pn * (chi2 * Gd - ya * g0)
        x_line = Gd * (ya * g0 - chi2 * Gd)
        y_line = ya * (Gd * u - b / A1 * g0 * Pn * Pd)
        z_line = g0 * u
        p_line = Pn * Gd * (ya * g0 - chi2 * Gd)
    f3 = (-w2 * (s11 * u + 2 * Pn * s12)
          + C1 / A1 * Pd * (Pd * u + c_line)
          + x * (A1 / b * s22 - b / A1 * g0 * Pd**2 - x_line)
          - y_line
          + z / a * (0.5 / b * (2 * b - 1) * s11 * G - z_line - Pn * s21)
          + y * (2 - b) / (1 - b) * (G * (ya * g0 - chi2 * Gd) - a * g0 * Pn * Pd)
          + k * ((1 - C1) * ((ya * g0 - chi2 * Gd) * G * Gd - a * g0 * Pn * Pd * Gd + b / A1 * g0 * G * Pd**2)
                 + Pn * g0 * (2 * b * Pd * Gd - a * A1 * (1 + B1) * s21 + 2 * A1 * s21)
                 + A1 * (u * (g0**2 - Gd**2) - (1 + B1) * G * s22)))
    phi3 = (-2 * s12 * G - a * g0 * Pn * s11 + (1 + B1) * (Pn * s22 + u * s21)
            + 2 * x * g0 * (s21 / b - b / A1 * Pd * Gd) - z / b * (a * g0**2 * Pn + s21 * G)
            + (1 - C1) / A1 * (b / A1 * g0 * Pn * Pd**2 - u * Pd * Gd + p_line)
            - y * g0 * (a * Pn * Gd - b / A1 * G * Pd)
            + (2 * Pd * (ya * g0 - chi2 * Gd) * G - a * g0 * Pn * Pd**2) / A1**2
            + k * g0 * (a * Pn * (C1 * Gd**2 - B1 * g0**2) - 2 * G * (b / A1 * C1 * Pd * Gd + B1 * s21)))
    F3 = f3 - chi1 * Phi2
    Phi3 = phi3 + a * g0 * (a * g0 * chi1 * (1 - w2) * Pn - f2)
    return F3, Phi3


def reduced_from_scaled(Y: np.ndarray, P: Params) -> np.ndarray:
    """Z = (p2, ṗ2, γ2, γ̇2) from the scaled state Y by the exact change of variables (9).

    p1 = p2 + μ⁻¹(χ1γ2 + x0'γ0''/(1−a)), γ = γ2 + μ⁻¹aγ0''p2; the dots are d/dτ along eq. (1).
    """
    e, a, g0, chi1, xa = 1 / P.mu, P.a, P.g0, P.chi1, P.x0 / (1 - P.a)
    f = scaled_rhs(0.0, Y, P)
    det = 1 - e**2 * chi1 * a * g0
    p2 = (Y[0] - e * xa * g0 - e * chi1 * Y[3]) / det
    p2d = (f[0] - e * chi1 * f[3]) / det
    return np.array([p2, p2d, Y[3] - e * a * g0 * p2, f[3] - e * a * g0 * p2d])


def scaled_from_reduced(Z: np.ndarray, P: Params, Y0: np.ndarray | None = None, iterations: int = 60) -> np.ndarray:
    """Inverse of ``reduced_from_scaled``: Y = (p1, q1, r1, γ, γ', γ'') (eqs. 9, 10, 13, without truncation).

    q1, γ' from eq. (1) (p- and γ-rows), r1, γ'' from the integrals (2) relative to the orbit's initial state
    Y0 (r1 = 1, γ'' = γ0'' there; ``Y0=None`` means Z is that initial state). Fixed-point iteration in μ⁻¹.
    """
    e, a, y, z, k, g0, A1, chi1 = 1 / P.mu, P.a, P.y0, P.z0, P.k, P.g0, P.A1, P.chi1
    Pn, Pd, G, Gd = Z
    p1 = Pn + e * (chi1 * G + P.x0 * g0 / (1 - a))
    g1 = G + e * a * g0 * Pn
    p1d = Pd + e * chi1 * Gd
    g1d = Gd + e * a * g0 * Pd
    q1, g2, r1, g3 = -p1d / A1, g1d, 1.0 + 0 * e, g0 + 0 * e
    for _ in range(iterations):
        q1_new = (-p1d + e * ((y * g3 - z * g2) / a + k * A1 * g2 * g3)) / (A1 * r1)
        g2_new = (g1d + e * q1 * g3) / r1
        if Y0 is not None:
            s1, s2 = _s1_s2([p1, q1, r1, g1, g2, g3], Y0, P)
            r1 = np.sqrt(1 + e**2 * s1)
            g3 = (g0 + e * s2) / r1
        q1, g2 = q1_new, g2_new
    return np.array([p1, q1, r1, g1, g2, g3])


def _s1_s2(Y, Y0, P: Params):
    """s1, s2 of eq. (3) from the energy and area integrals of (1), relative to the initial state Y0."""
    a, b, x, y, z, k = P.a, P.b, P.x0, P.y0, P.z0, P.k
    p, q, _, g1, g2, g3 = Y
    p0, q0, _, g10, g20, g30 = Y0
    s3 = (a * (p0**2 - p**2) + b * (q0**2 - q**2) - 2 * (x * (g10 - g1) + y * (g20 - g2))
          + k * (a * (g10**2 - g1**2) + b * (g20**2 - g2**2)))
    s1 = s3 - 2 * z * (g30 - g3) + k * (g30**2 - g3**2)
    s2 = a * (p0 * g10 - p * g1) + b * (q0 * g20 - q * g2)
    return s1, s2


def reduced_rhs(tau: float, Z: np.ndarray, P: Params, Z0: np.ndarray, printed: bool = False,
                order: int = 3) -> np.ndarray:
    """The reduced quasilinear system (14) through the μ⁻³ terms: d/dτ (p2, ṗ2, γ2, γ̇2).

        p̈2 + ω²p2 = μ⁻²F2 + μ⁻³F3,   γ̈2 + γ2 = μ⁻²Φ2 + μ⁻³Φ3      (``order=2`` drops the μ⁻³ terms)

    Z0 is the initial state (it enters through s11, s12, s21, s22 of (12)); ``printed`` uses the printed Φ2, F3, Φ3
    (errata 000-3, 000-4). Errors against the full model: docs/regimes.md, "Reduced systems".
    """
    if order not in (2, 3):
        raise ValueError(f"order={order!r}: the reduced system (14) is available through μ⁻² or μ⁻³ (order 2 or 3)")
    F2, Phi2 = eq14_F2_Phi2(Z, Z0, P, printed=printed)
    e = 1 / P.mu
    F, Phi = e**2 * F2, e**2 * Phi2
    if order >= 3:
        F3, Phi3 = eq14_F3_Phi3(Z, Z0, P, printed=printed)
        F, Phi = F + e**3 * F3, Phi + e**3 * Phi3
    return np.array([Z[1], -P.omega2 * Z[0] + F, Z[3], -Z[2] + Phi])
