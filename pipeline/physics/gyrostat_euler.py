"""Lagrange equations of the orbiting satellite-gyrostat in Euler angles (Yehia & El-kenani (2021), eqs. 5–7 re-derived).

Euler angles (ψ, θ, φ), z-x-z, of the body relative to the orbital frame (α radial,
β along-track, γ orbit normal): α, β, γ in body axes are eq. (1) of Yehia & El-kenani
(2021) = ``gyrolab.physics.attitude.frame_from_angles``; ω′ = J(θ, φ) q̇ and ω = ω′ + Ωγ.
From L = ½ω·Iω + ω·k − V with V = ½N α·Iα + μ·(h1 α + h2 β + h3 γ) (N = 3Ω², the
paper has h2 = 0 and the sign +μ·H), E_q = d/dt ∂L/∂q̇ − ∂L/∂q is

    E(q, q̇, q̈) = M(q) q̈ + g(q, q̇) + ∂V/∂q,

derived with sympy in ``docs/derivations/scripts/seed002/derive_euler_lagrange.py``
(notation there: D = A − B, a = A sin²φ + B cos²φ, P = ψ̇ + Ω, κc = k1 sin φ + k2 cos φ,
κs = k1 cos φ − k2 sin φ). On any motion E = Jᵀ R, with R the residual of the vector
Euler equations (tests/analysis/test_precession.py checks this on random states); det J = −sin θ,
so at θ ∈ {0, π} the Euler-angle form loses one direction of R.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gyrolab.physics.attitude import frame_from_angles


@dataclass(frozen=True)
class GyrostatParameters:
    """The paper's parameters: inertia (A, B, C), k, Ω, μ, h = (h1, h2, h3) with V ∋ +μ·(h1α + h2β + h3γ).

    ``N`` is the gravity-gradient coefficient, 3Ω² on a circular orbit (None: that value).
    """

    inertia: tuple[float, float, float]
    k: tuple[float, float, float] = (0.0, 0.0, 0.0)
    mu: tuple[float, float, float] = (0.0, 0.0, 0.0)
    h: tuple[float, float, float] = (0.0, 0.0, 0.0)
    Omega: float = 1.0
    N: float | None = field(default=None)

    @property
    def I(self) -> np.ndarray:  # noqa: E743 (the paper's name)
        return np.asarray(self.inertia, dtype=float)

    @property
    def gradient(self) -> float:
        return 3.0 * self.Omega**2 if self.N is None else float(self.N)

    def replace(self, **changes: float) -> GyrostatParameters:
        """A copy with some scalar parameters changed: A, B, C, k1..k3, mu1..mu3, h1..h3, Omega."""
        inertia, k, mu, h = list(self.inertia), list(self.k), list(self.mu), list(self.h)
        omega = self.Omega
        for name, value in changes.items():
            value = float(value)
            if name in ("A", "B", "C"):
                inertia["ABC".index(name)] = value
            elif name[:-1] in ("k", "mu", "h") and name[-1] in "123":
                {"k": k, "mu": mu, "h": h}[name[:-1]][int(name[-1]) - 1] = value
            elif name == "Omega":
                omega = value
            else:
                raise KeyError(name)
        return GyrostatParameters(tuple(inertia), tuple(k), tuple(mu), tuple(h), omega, self.N)


def kinematic_matrix(theta: float, phi: float) -> np.ndarray:
    """J with ω′ = J (ψ̇, θ̇, φ̇) (eq. 1)."""
    st, ct, sf, cf = np.sin(theta), np.cos(theta), np.sin(phi), np.cos(phi)
    return np.array([[st * sf, cf, 0.0], [st * cf, -sf, 0.0], [ct, 0.0, 1.0]])


def mass_matrix(q: np.ndarray, p: GyrostatParameters) -> np.ndarray:
    """The kinetic energy's matrix M(q) in the Euler-angle rates: T = ½ q̇ᵀ M(q) q̇ + (lower order).

    Parameters
    ----------
    q : numpy.ndarray
        The Euler angles (ψ, θ, φ), shape (3,).
    p : GyrostatParameters
        The gyrostat (its principal moments ``I`` = (A, B, C)).

    Returns
    -------
    numpy.ndarray
        The symmetric 3 × 3 matrix Jᵀ diag(A, B, C) J with J the `kinematic_matrix`.
    """
    A, B, C = p.I
    _, th, ph = q
    st, ct = np.sin(th), np.cos(th)
    a = A * np.sin(ph) ** 2 + B * np.cos(ph) ** 2
    b = A * np.cos(ph) ** 2 + B * np.sin(ph) ** 2
    m12 = 0.5 * (A - B) * np.sin(2 * ph) * st
    return np.array([[a * st**2 + C * ct**2, m12, C * ct], [m12, b, 0.0], [C * ct, 0.0, C]])


def gyroscopic_terms(q: np.ndarray, qd: np.ndarray, p: GyrostatParameters) -> np.ndarray:
    """Velocity-dependent part of E (quadratic, Ω-Coriolis/centrifugal and rotor terms)."""
    A, B, C = p.I
    k1, k2, k3 = p.k
    W = p.Omega
    _, th, ph = q
    dps, dth, dph = qd
    st, ct, sf, cf = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    s2p, c2p, s2t = np.sin(2 * ph), np.cos(2 * ph), np.sin(2 * th)
    D = A - B
    a = A * sf**2 + B * cf**2
    P = dps + W
    kc = k1 * sf + k2 * cf
    ks = k1 * cf - k2 * sf
    e_psi = (0.5 * D * s2p * ct * dth**2
             + dth * ((D * c2p - C) * st * dph + (a - C) * s2t * P + ct * kc - k3 * st)
             + dph * st * (D * s2p * st * P + ks))
    e_th = (-(a - C) * st * ct * P**2 + P * ((D * c2p + C) * st * dph - ct * kc + k3 * st)
            - D * s2p * dph * dth - kc * dph)
    e_ph = (0.5 * D * s2p * dth**2 + dth * (-(D * c2p + C) * st * P + kc)
            - 0.5 * D * s2p * st**2 * P**2 - st * ks * P)
    return np.array([e_psi, e_th, e_ph])


def potential_gradient(q: np.ndarray, p: GyrostatParameters) -> np.ndarray:
    """∂V/∂(ψ, θ, φ) from the partial derivatives of eq. (1)."""
    psi, th, ph = q
    alpha, beta, gamma = frame_from_angles(psi, th, ph)
    mu = np.asarray(p.mu, dtype=float)
    h1, h2, h3 = p.h
    va = p.gradient * p.I * alpha + h1 * mu  # ∂V/∂α
    vb = h2 * mu
    vg = h3 * mu
    dgamma_dth = np.array([np.cos(th) * np.sin(ph), np.cos(th) * np.cos(ph), -np.sin(th)])
    rot = lambda e: np.array([e[1], -e[0], 0.0])  # noqa: E731  ∂e/∂φ
    v_psi = -va @ beta + vb @ alpha
    v_th = np.sin(psi) * (va @ gamma) - np.cos(psi) * (vb @ gamma) + vg @ dgamma_dth
    v_ph = va @ rot(alpha) + vb @ rot(beta) + vg @ rot(gamma)
    return np.array([v_psi, v_th, v_ph])


def lagrange_equations(q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, p: GyrostatParameters) -> np.ndarray:
    """E(q, q̇, q̈) = M q̈ + g + ∂V/∂q (zero on motions)."""
    q, qd, qdd = (np.asarray(x, dtype=float) for x in (q, qd, qdd))
    return mass_matrix(q, p) @ qdd + gyroscopic_terms(q, qd, p) + potential_gradient(q, p)


def rhs_euler_angles(t: float, x: np.ndarray, p: GyrostatParameters) -> np.ndarray:
    """First-order form, x = (ψ, θ, φ, ψ̇, θ̇, φ̇); singular at sin θ = 0."""
    q, qd = x[:3], x[3:]
    qdd = np.linalg.solve(mass_matrix(q, p), -(gyroscopic_terms(q, qd, p) + potential_gradient(q, p)))
    return np.concatenate([qd, qdd])
