"""The heavy body about a fixed point at r0 = 0: an exact planar physical pendulum.

Nondimensional form of the papers (time in 1/c, c² = Mgℓ/C, inertia diag(a, b, 1)): with the centre of mass on
the body z axis, r_c = (0, 0, 1), and the body released from rest with z tilted by θa about the body y axis,
γ = (sin θ, 0, cos θ), ω = (0, q, 0) stays so for all time: (Iω) × ω = 0 for ω along a principal axis, and both
r_c × γ and k γ × Iγ = k (a − 1) γx γz e_y (uniform gravity and the Newtonian term) point along e_y. The
remaining equations are θ̇ = −q and

    b θ̈ = −sin θ − κ sin θ cos θ,        κ = k (a − 1),

with the energy ½ b θ̇² − cos θ − ½ κ cos² θ. The swing (libration about θ = 0, which needs 1 + κ > 0) from the
turning point θ(0) = θa has, with m = sin²(θa/2), θ = 2 arcsin(√m sin s):

    T0 = 4 √b ∫₀^{π/2} ds / [√(1 − m sin² s) √(1 + ½ κ (cos θ + cos θa))]     (= 4 √b K(m) for κ = 0),

a smooth integrand (Gauss–Legendre converges exponentially). For κ = 0 the swing is in Jacobi elliptic functions:
sin(θ/2) = √m sn(t/√b + K(m), m), θ̇ = −(2√m/√b) cn(·) … (q = −θ̇), θ(0) = θa.
"""

from __future__ import annotations

import numpy as np
from scipy.special import ellipj, ellipk

from gyrolab.errors import ConfigError

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(64)


def kappa(a: float, k: float) -> float:
    """κ = k (a − 1): the Newtonian term's share of the restoring torque.

    Parameters
    ----------
    a : float
        A/C, the body's first principal moment over its third.
    k : float
        N/c², the Newtonian field's strength over the squared gravity frequency.

    Returns
    -------
    float
        κ; the swing's restoring torque is ∝ sin θ (1 + κ cos θ).
    """
    return float(k) * (float(a) - 1.0)


def check_libration(b: float, kap: float, theta_a: float) -> None:
    """Refuse a pendulum swing that is not a libration about the lowest position.

    Parameters
    ----------
    b : float
        B/C, which must be positive.
    kap : float
        κ = k (a − 1) (see `kappa`).
    theta_a : float
        The swing's amplitude θa, in (0, π).

    Raises
    ------
    gyrolab.errors.ConfigError
        When θa is outside (0, π), when 1 + κ cos θ is not positive over the swing, or when b ≤ 0.
    """
    if not 0.0 < theta_a < np.pi:
        raise ConfigError(f"the pendulum swing needs an amplitude 0 < θ0 < π, got θ0={theta_a:.6g}")
    if not 1.0 + kap * np.cos(theta_a) > 0 or not 1.0 + kap > 0:
        raise ConfigError(f"the pendulum swing about the lowest position needs 1 + κ cos θ > 0 on the swing "
                          f"(κ = k(a − 1) = {kap:.4g}, θ0 = {theta_a:.4g})")
    if b <= 0:
        raise ConfigError(f"the pendulum needs b = B/C > 0, got b={b:g}")


def period(b: float, kap: float, theta_a: float) -> float:
    """Period T0 of the plane swing (pendulum libration) of amplitude θa.

    Parameters
    ----------
    b : float
        B/C, positive.
    kap : float
        κ = k (a − 1) (see `kappa`).
    theta_a : float
        The amplitude θa, in (0, π).

    Returns
    -------
    float
        T0 by 64-point Gauss–Legendre quadrature of the energy integral; 4√b K(m), m = sin²(θa/2), when κ = 0.

    Raises
    ------
    gyrolab.errors.ConfigError
        When the swing is not a libration about the lowest position (`check_libration`).
    """
    check_libration(b, kap, theta_a)
    m = np.sin(theta_a / 2) ** 2
    s = 0.25 * np.pi * (_NODES + 1.0)
    theta = 2 * np.arcsin(np.sqrt(m) * np.sin(s))
    integrand = 1.0 / (np.sqrt(1 - m * np.sin(s) ** 2) * np.sqrt(1 + 0.5 * kap * (np.cos(theta) + np.cos(theta_a))))
    return float(4 * np.sqrt(b) * 0.25 * np.pi * np.sum(_WEIGHTS * integrand))


def swing(t: np.ndarray, b: float, theta_a: float) -> np.ndarray:
    """The κ = 0 swing released from rest at θ(0) = θa, in closed form (Jacobi elliptic functions).

    Parameters
    ----------
    t : numpy.ndarray
        Times, shape (n,).
    b : float
        B/C, positive.
    theta_a : float
        The amplitude θa, in (0, π).

    Returns
    -------
    numpy.ndarray
        (p, q, r, γ, γ', γ'') at ``t``, shape (n, 6).

    Raises
    ------
    gyrolab.errors.ConfigError
        When the swing is not a libration about the lowest position (`check_libration`).
    """
    check_libration(b, 0.0, theta_a)
    m = np.sin(theta_a / 2) ** 2
    K = ellipk(m)
    sn, cn, dn, _ = ellipj(np.asarray(t, dtype=float) / np.sqrt(b) + K, m)
    half = np.sqrt(m) * sn                       # sin(θ/2)
    cos_half = dn                                # cos(θ/2) = √(1 − m sn²) = dn
    theta_dot = 2 * np.sqrt(m) * cn / np.sqrt(b)  # d/dt [2 arcsin(√m sn)] = 2√m cn dn/(√b cos(θ/2))
    zeros = np.zeros_like(half)
    return np.stack([zeros, -theta_dot, zeros, 2 * half * cos_half, zeros, 1 - 2 * half ** 2], axis=-1)
