"""Euler angles (z-x-z: precession ψ, nutation θ, proper rotation φ) and direction cosines.

Convention of the papers (Leimanis, and the three papers): the unit vector of the fixed
vertical Z in body axes is γ = (sin θ sin φ, sin θ cos φ, cos θ). With α and
β the body components of the fixed X and Y axes (β = γ × α), ψ is read from
α_z = sin ψ sin θ and β_z = −cos ψ sin θ.

All angles come from atan2 of well-conditioned combinations, never from
arccos: near θ = 0 the combination ψ + φ = atan2(β_x − α_y, α_x + β_y) keeps
full relative accuracy (both arguments carry the factor 1 + cos θ), near θ = π
ψ − φ = atan2(β_x + α_y, α_x − β_y) does. At θ exactly 0 or π only that sum
or difference is defined; φ is then taken from γ (zero) and ψ carries it.
"""

from __future__ import annotations

import numpy as np

from gyrolab.physics.vectors import cross


def gamma_from_angles(theta: float, phi: float) -> np.ndarray:
    """Body components of the fixed vertical: γ = (sin θ sin φ, sin θ cos φ, cos θ).

    Parameters
    ----------
    theta : float
        Nutation θ (rad).
    phi : float
        Proper rotation φ (rad).

    Returns
    -------
    numpy.ndarray
        γ, shape (3,), a unit vector.
    """
    return np.array([np.sin(theta) * np.sin(phi), np.sin(theta) * np.cos(phi), np.cos(theta)])


def frame_from_angles(psi: float, theta: float, phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body components (α, β, γ) of the fixed axes X, Y, Z for Euler angles (ψ, θ, φ) (z-x-z convention).

    Parameters
    ----------
    psi, theta, phi : float
        Precession ψ, nutation θ and proper rotation φ (rad).

    Returns
    -------
    tuple of numpy.ndarray
        α, β, γ, each of shape (3,): the rows of a proper rotation matrix.
    """
    sp, cp = np.sin(psi), np.cos(psi)
    st, ct = np.sin(theta), np.cos(theta)
    sf, cf = np.sin(phi), np.cos(phi)
    alpha = np.array([cp * cf - sp * ct * sf, -cp * sf - sp * ct * cf, sp * st])
    beta = np.array([sp * cf + cp * ct * sf, -sp * sf + cp * ct * cf, -cp * st])
    gamma = np.array([st * sf, st * cf, ct])
    return alpha, beta, gamma


def nutation_and_spin(gamma: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """θ and φ from γ alone.

    Parameters
    ----------
    gamma : numpy.ndarray
        Body components of the fixed vertical, shape (..., 3).

    Returns
    -------
    theta, phi : numpy.ndarray
        Nutation θ in [0, π] and proper rotation φ wrapped to (−π, π], shape (...).
    """
    horizontal = np.hypot(gamma[..., 0], gamma[..., 1])
    theta = np.arctan2(horizontal, gamma[..., 2])
    phi = np.arctan2(gamma[..., 0], gamma[..., 1])
    return theta, phi


def unwrap(angle: np.ndarray) -> np.ndarray:
    """``np.unwrap(angle)`` (period 2π, along a 1-d series), bit for bit, in half its time: the corrections are
    computed at the jumps only (|step| ≥ π, rare in a series that resolves its motion), where numpy's works on every
    step (~30 µs of a 3,001-sample run's dataset)."""
    step = np.diff(angle)
    jumps = np.flatnonzero(np.abs(step) >= np.pi)
    out = np.array(angle, dtype=float)
    if jumps.size:
        at = step[jumps]
        wrapped = np.mod(at + np.pi, 2.0 * np.pi) - np.pi
        wrapped[(wrapped == -np.pi) & (at > 0)] = np.pi  # numpy's choice at the boundary
        correction = np.zeros_like(step)
        correction[jumps] = wrapped - at
        out[1:] += np.cumsum(correction)
    return out


def euler_angles(alpha: np.ndarray, gamma: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unwrapped Euler angles (ψ, θ, φ) along a trajectory.

    Parameters
    ----------
    alpha : numpy.ndarray
        Body components of the fixed X axis, shape (n, 3).
    gamma : numpy.ndarray
        Body components of the fixed Z axis (the vertical), shape (n, 3).

    Returns
    -------
    psi, theta, phi : numpy.ndarray
        Each of shape (n,); ψ and φ unwrapped (continuous through the poles θ = 0 and θ = π).
    """
    alpha = np.atleast_2d(alpha)
    gamma = np.atleast_2d(gamma)
    beta = cross(gamma, alpha)
    theta, phi = nutation_and_spin(gamma)
    upper = gamma[:, 2] >= 0.0  # θ ≤ π/2: use ψ + φ; otherwise ψ − φ
    psi_plus_phi = np.arctan2(beta[:, 0] - alpha[:, 1], alpha[:, 0] + beta[:, 1])
    psi_minus_phi = np.arctan2(beta[:, 0] + alpha[:, 1], alpha[:, 0] - beta[:, 1])
    psi = np.where(upper, psi_plus_phi - phi, psi_minus_phi + phi)  # in (−2π, 2π]: two angles of (−π, π]
    # wrapped to (−π, π] before unwrapping by ±2π, exact there (Sterbenz: |ψ| ≥ π lies within a factor 2 of 2π);
    # np.angle(np.exp(1j ψ)) rounded, in 9× the time
    psi = np.where(psi > np.pi, psi - 2.0 * np.pi, np.where(psi <= -np.pi, psi + 2.0 * np.pi, psi))
    phi = unwrap(phi)
    return unwrap_with_pole_combination(psi, phi, upper), theta, phi


def unwrap_with_pole_combination(psi: np.ndarray, phi: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """ψ unwrapped so that the combination defined at the nearer pole stays continuous: ψ + φ where ``upper``
    (θ ≤ π/2), ψ − φ elsewhere; ``phi`` is already unwrapped.

    Passing near a pole, φ and ψ each turn by about π between two samples, in opposite senses, and only their
    sum (θ = 0) or difference (θ = π) is defined. Unwrapping ψ and φ separately picks each 2π branch on its own,
    so a jump of slightly more than π in one and slightly less in the other makes the defined combination jump
    by 2π. Here ψ's branch at each sample is the one that keeps that combination's step smallest (below π);
    away from the poles φ moves little between samples and this is ``np.unwrap(psi)``.
    """
    if psi.size < 2:
        return psi
    sign = np.where(upper[1:], 1.0, -1.0)
    step = np.diff(psi) + sign * np.diff(phi)  # the combination's step with ψ's raw (wrapped) branch
    turns = -np.round(step / (2.0 * np.pi))
    return psi + 2.0 * np.pi * np.concatenate(([0.0], np.cumsum(turns)))


def angles_from_states(t: np.ndarray, y: np.ndarray, psi0: float) -> dict[str, np.ndarray]:
    """Euler angles of sampled (ω, γ) states: θ and φ from γ, ψ by quadrature of ψ̇ = (pγ + qγ')/(1 − γ''²)
    (Shaker et al. eq. 29) with a cubic spline through the samples (error ~ h⁴: 7e-11 rad at 200 samples per
    period against ψ from α, tests/experiments/test_regime_experiments.py) — for states that come without the fixed axis α."""
    from scipy.interpolate import CubicSpline  # scipy.interpolate: imported when used, not with attitude

    theta, phi = nutation_and_spin(y[:, 3:6])
    rate = (y[:, 0] * y[:, 3] + y[:, 1] * y[:, 4]) / (1.0 - y[:, 5] ** 2)
    psi = psi0 + CubicSpline(t, rate).antiderivative()(t)
    return {"psi": psi, "theta": theta, "phi": unwrap(phi)}
