"""The resonant case ω = 3 of Shaker, El-Barki & Ismail: the branches (i)-(iv) of eq. (23), printed and corrected.

M. O. Shaker, F. A. El-Barki, A. I. Ismail, "Singular value of the natural
frequency for the motion of rigid body". Verification report:
``docs/derivations/seed001_resonant_omega3.md`` (cited as "report §n").

Units: I = diag(a, b, 1), time in 1/c (c² = Mgℓ/C), rates in c, k_gt = N/c².
Paper's scaled quantities (eqs. 5, 7):

    γ0'' = cos θ0,  M3 = tan θ0,  μ = c√γ0''/r0 (≪ 1: fast spin),  k = k_gt γ0'',
    τ = r0 t,  p = c√γ0'' p1,  q = c√γ0'' q1,  r = r0 r1,  γ = γ0'' γ1.

ω² = −A1B1 = (1−a)(1−b)/(ab) = 9 requires b = (1−a)/(1+8a) and hence
A + B < C: no real body has ω = 3 (ω² − 1 = C(C−A−B)/(AB), report §3).
Normalisation: r(0) = r0, γ''(0) = γ0'', γ'(0) = 0 (φ(0) = π/2), ψ(0) = 0.
Measured accuracy of the corrected series (report §6): p, q O(μ³) relative to
c√γ0''; r/r0, γ/γ0'' O(μ⁴); period O(μ⁴); Euler angles O(μ⁴).

Branches of (23) (the generating p-mode p2 = M1 cos 3τ + M2 sin 3τ, E² = M1² + M2²): (i) M1 = M2 = 0, the full
series above; (iii) the case-(i) series with the p-mode amplitude μℓ1 replaced by M1 = ±√(a2/a1); (ii) and (iv)
only as printed, the generating solution (16) (erratum 001-6). Their orders: docs/regimes.md, "resonant_omega3".
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gyrolab.plugins.regimes.ismail2021 import euler_poisson_scaled
from gyrolab.plugins.regimes.notation import BodyRatios


def omega3_b(a: float) -> float:
    """b = B/C that makes ω = 3 for a = A/C (report §2)."""
    return (1.0 - a) / (1.0 + 8.0 * a)


@dataclass(frozen=True)
class Constants(BodyRatios):
    """Constants of the ω = 3 series (eqs. 7, 21, 26, 28); ``printed`` says which a2, L310, α."""

    k_gt: float
    theta0: float
    printed: bool = False
    M1: float = 0.0  # generating p-mode amplitudes of (16)/(23): zero for branch (i)
    M2: float = 0.0

    @property
    def g0(self) -> float:
        return float(np.cos(self.theta0))

    @property
    def M(self) -> float:
        """M3 = tan θ0 (eq. 31)."""
        return float(np.tan(self.theta0))

    @property
    def k(self) -> float:
        """The paper's k = N γ0''/c² (eq. 7), not k_gt."""
        return self.k_gt * self.g0

    @property
    def e(self) -> float:
        return self.x0 * self.A1 / (9.0 * self.b)

    @property
    def e1(self) -> float:
        return (self.k * (9.0 - self.A1) + self.z0 * (1.0 / self.a - self.A1 / self.b)) / 8.0

    @property
    def e2(self) -> float:
        return self.e1 + self.z0 / self.a - self.k * self.A1

    @property
    def nu(self) -> float:
        return -(1.0 + self.B1) / 8.0

    @property
    def a1(self) -> float:
        return (self.a - 1.0) * (self.a + self.b - 2.0) / (2.0 * self.b)

    @property
    def a2(self) -> float:
        """(21)/(24). Corrected: 18k[1−(a+b)+¼(a+b)M3²]; printed: 18k[1−(a+b)+½bM3²] (erratum 001-1)."""
        a, b, M, k, z = self.a, self.b, self.M, self.k, self.z0
        tail = 0.5 * b * M**2 if self.printed else 0.25 * (a + b) * M**2
        return z / (a * b) * (3.0 * (a + b) - 2.0 * (2.0 * a * b + 1.0)) + 18.0 * k * (1.0 - (a + b) + tail)

    @property
    def L310(self) -> float:
        """Resonant forcing (21). Corrected: k z0' C1 (4b−1)/(16ab) (erratum 001-2)."""
        a, b, k, z, e1, e2, A1, C1 = self.a, self.b, self.k, self.z0, self.e1, self.e2, self.A1, self.C1
        if self.printed:
            return 0.25 * k * (8.0 * e1 * (a - b) - 0.5 * z * (1.0 / a - A1 / b) * (a - b)
                               + e2 * (1.0 - C1) + e1 * A1 + (A1 - 9.0) * (a * e1 + b * e2 / A1))
        return k * z * C1 * (4.0 * b - 1.0) / (16.0 * a * b)

    @property
    def l1(self) -> float:
        """ℓ1 = M3³ L310 / a2 (26)."""
        return self.M**3 * self.L310 / self.a2

    @property
    def alpha2(self) -> float:
        """α/μ² of (28). Corrected: π[2M3x0' − 8νe1 − z0'/b + k(½M3²(b−a) − B1)] (erratum 001-4)."""
        half = 1.0 if self.printed else 0.5
        return np.pi * (2.0 * self.M * self.x0 - 8.0 * self.nu * self.e1 - self.z0 / self.b
                        + self.k * (half * self.M**2 * (self.b - self.a) - self.B1))

    @property
    def E(self) -> float:
        """Amplitude of the p-mode on branches (ii)-(iv): E² = M1² + M2² = a2/a1 (23); NaN if a2/a1 < 0."""
        ratio = self.a2 / self.a1
        return float(np.sqrt(ratio)) if ratio > 0 else float("nan")

    def as_printed(self) -> Constants:
        return replace(self, printed=True)

    def on_branch(self, branch: str, sign: float = 1.0, phase: float = np.pi / 4) -> Constants:
        """These constants on branch (i)-(iv) of (23): M1 = M2 = 0; M2 = ±E; M1 = ±E; (M1, M2) = ±E(cos ε, sin ε)."""
        E = self.E
        M1, M2 = {"i": (0.0, 0.0), "ii": (0.0, sign * E), "iii": (sign * E, 0.0),
                  "iv": (sign * E * np.cos(phase), sign * E * np.sin(phase))}[branch]
        return replace(self, M1=float(M1), M2=float(M2))

    @property
    def branch_i(self) -> bool:
        return self.M1 == 0.0 and self.M2 == 0.0

    def pmode(self, mu: float) -> tuple[float, float]:
        """Coefficients (L, K) of μ cos 3τ and μ sin 3τ in p1: (ℓ1, 0) on branch (i), (M1/μ, M2/μ) otherwise."""
        return (self.l1, 0.0) if self.branch_i else (self.M1 / mu, self.M2 / mu)

    def gamma_l1(self, mu: float) -> float:
        """The p-mode coefficient in the γ and Euler-angle terms (linear in it): ℓ1 on branch (i); M1/μ on the
        corrected branch (iii); 0 for the printed branches, which are the generating solution (16) there."""
        if self.branch_i:
            return self.l1
        if self.printed:
            return 0.0
        if self.M2 != 0.0:
            raise ValueError("branches (ii), (iv) are not periodic solutions (erratum 001-6); printed reading only")
        return self.M1 / mu


def mu_of(r0: float, theta0: float) -> float:
    """μ = c√γ0''/r0 with r0 in units of c (eq. 5)."""
    return float(np.sqrt(np.cos(theta0)) / r0)


def scaled_rhs(tau: float, Y: np.ndarray, mu: float, C: Constants) -> np.ndarray:
    """The paper's scaled system (eq. 1 with the variables of eq. 5; report §1), d/dτ of
    Y = (p1, q1, r1, γ1, γ1', γ1'') with τ = r0 t, p = c√γ0'' p1, r = r0 r1, γ = γ0'' γ1 and k = k_gt γ0'':

        ṗ1 + A1q1r1 = μa⁻¹(y0'γ1'' − z0'γ1' + kaA1γ1'γ1''),  q̇1 + B1p1r1 = μb⁻¹(z0'γ1 − x0'γ1'' + kbB1γ1''γ1),
        ṙ1 = μ²(−C1p1q1 + x0'γ1' − y0'γ1 + kC1γ1γ1'),
        γ̇1 = r1γ1' − μq1γ1'',  γ̇1' = μp1γ1'' − r1γ1,  γ̇1'' = μ(q1γ1 − p1γ1').

    Exact: it is the full model rescaled (tests/plugins/regimes/test_resonant_omega3.py).
    """
    return euler_poisson_scaled(Y, mu, C)


def period(r0: float, C: Constants) -> float:
    """T = (2π + α)/r0 in units of 1/c (28)."""
    return (2.0 * np.pi + C.alpha2 * mu_of(r0, C.theta0) ** 2) / r0


def state(t: np.ndarray, r0: float, C: Constants) -> np.ndarray:
    """(p, q, r, γ, γ', γ'') in units of c at times t (1/c), shape (n, 6): solution (27).

    Corrected: phase th = Ωr0t with Ω = 1 − α/(2π), and the O(μ²) terms G2, H2 of γ, γ' (report §4).
    Printed: τ = r0 t, only the O(1) terms of γ, γ' (the paper's V_i, W_i are not printed),
    and its γ'' bracket (27) with the printed ℓ1.
    """
    mu = mu_of(r0, C.theta0)
    M, e, e1, e2, A1, C1, k = C.M, C.e, C.e1, C.e2, C.A1, C.C1, C.k
    a, b, x, y = C.a, C.b, C.x0, C.y0
    L, K = C.pmode(mu)
    l1 = C.gamma_l1(mu)
    t = np.asarray(t, dtype=float)
    th = r0 * t if C.printed else (1.0 - C.alpha2 * mu**2 / (2 * np.pi)) * r0 * t
    cs, sn = np.cos, np.sin
    p1 = mu * (e + e1 * M * cs(th) + L * cs(3 * th) + K * sn(3 * th))
    q1 = mu / A1 * (y / a + e2 * M * sn(th) + 3.0 * (L * sn(3 * th) - K * cs(3 * th)))
    r1 = 1.0 - mu**2 * M * (x * (1 - cs(th)) + y * sn(th) + 0.25 * k * C1 * M * (1 - cs(2 * th)))
    if C.printed:
        g1, g1p = M * cs(th), -M * sn(th)
        br = (0.5 * M * (e1 * a + b * e2 / A1) + a * e + x + 0.25 * k * C1 * M + a * l1
              - (x + a * e) * cs(th) + y * (1 + b / (a * A1)) * sn(th)
              + 0.5 * (3 * b * l1 / A1 - a * l1 - 0.5 * k * C1 * M - e1 * a * M - e2 * b * M / A1) * cs(2 * th)
              - 0.5 * l1 * (a + 3 * b / A1) * cs(4 * th))
        g1pp = 1 + mu**2 * M * br
    else:
        yA = y / (a * A1)
        g3 = a * l1 + C1 * k * M**3 / 16.0
        G2 = ((e - 0.5 * M**2 * x) - (e + g3) * cs(th) + (y * M**2 - yA) * sn(th)
              + 0.5 * M**2 * x * cs(2 * th) - 0.5 * M**2 * y * sn(2 * th) + g3 * cs(3 * th))
        h1 = e + a * l1 - C1 * k * M**3 / 16.0 + C1 * M * (C.z0 / (a * b) - 4.0 * k) / 8.0
        H2 = ((yA - 0.5 * y * M**2) + (y * M**2 - yA) * cs(th) + h1 * sn(th) - 0.5 * M**2 * y * cs(2 * th)
              - 0.5 * M**2 * x * sn(2 * th) + (3.0 * b / A1 * l1 - C1 * k * M**3 / 16.0) * sn(3 * th))
        K2 = M * (e * (1 - cs(th)) + yA * sn(th)
                  + 0.25 * ((e1 + e2 / A1) * M + l1 * (3.0 / A1 - 1.0)) * (1 - cs(2 * th))
                  + 0.125 * l1 * (1.0 + 3.0 / A1) * (1 - cs(4 * th)))
        g1, g1p, g1pp = M * cs(th) + mu**2 * G2, -M * sn(th) + mu**2 * H2, 1.0 + mu**2 * K2
    s = np.sqrt(C.g0)
    return np.stack([s * p1, s * q1, r0 * r1, C.g0 * g1, C.g0 * g1p, C.g0 * g1pp], axis=-1)


def euler(t: np.ndarray, r0: float, C: Constants, *, printed_phi2: bool | None = None) -> dict[str, np.ndarray]:
    """θ, ψ, φ of (29)-(33), t0 = 0, ψ0 = 0, φ0 = π/2; printed keeps (33)'s φ2 garbles (erratum 001-5).

    ``printed_phi2`` overrides whether φ2 is the printed one (default: ``C.printed``), to isolate that erratum.
    """
    printed_phi2 = C.printed if printed_phi2 is None else printed_phi2
    mu = mu_of(r0, C.theta0)
    t = np.asarray(t, dtype=float)
    th0, M, e, e1, e2, A1, C1, k = C.theta0, C.M, C.e, C.e1, C.e2, C.A1, C.C1, C.k
    x, y, a = C.x0, C.y0, C.a
    l1 = C.gamma_l1(mu)
    s = r0 * t if C.printed else (1.0 - C.alpha2 * mu**2 / (2 * np.pi)) * r0 * t
    yA = y / (a * A1)
    tn, ct = np.tan(th0), 1.0 / np.tan(th0)

    def th2(u):
        return (-e * np.cos(u) + yA * np.sin(u) - 0.25 * ((e1 + e2 / A1) * M + l1 * (3.0 / A1 - 1.0)) * np.cos(2 * u)
                - 0.125 * l1 * (1.0 + 3.0 / A1) * np.cos(4 * u))

    def ps2(u):
        return (e * np.sin(u) + yA * np.cos(u) + 0.25 * ((e1 + e2 / A1) * tn + l1 * (1.0 - 3.0 / A1)) * np.sin(2 * u)
                + 0.125 * l1 * (1.0 + 3.0 / A1) * np.sin(4 * u))

    f = 1.0 / r0 if printed_phi2 else 0.5

    def ph2(u):
        out = ((x * tn - e * ct) * np.sin(u) + y * (tn - ct / (a * A1)) * np.cos(u)
               + 0.25 * (f * k * C1 * tn**2 - e1 - e2 / A1 - l1 * ct + 3.0 * l1 * ct / A1) * np.sin(2 * u)
               - 0.125 * (1.0 + 3.0 / A1) * l1 * ct * np.sin(4 * u))
        if printed_phi2:
            out = out - 0.25 * (1 + 3 / A1) / r0 * np.cos(4 * u)
        return out

    theta = th0 - mu**2 * (th2(s) - th2(0.0))
    psi = 0.5 / r0 * (e1 - e2 / A1) * t + mu**2 / np.sin(th0) * (ps2(s) - ps2(0.0))
    rate = r0 - (1.0 / r0) * (0.5 * np.cos(th0) * (e1 - e2 / A1) + np.sin(th0) * (x + 0.25 * k * C1 * tn))
    phi = 0.5 * np.pi + rate * t + mu**2 * (ph2(s) - ph2(0.0))
    return dict(theta=theta, psi=psi, phi=phi)
