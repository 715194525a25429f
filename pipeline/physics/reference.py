"""Reference trajectories of known accuracy: a Taylor series method in extended precision.

Independent of the compiled kernels (plain numpy on ``np.longdouble``, which is
the x87 80-bit format on x86-64: 64-bit mantissa, eps ≈ 1.1e-19), it integrates
the fixed-point Euler–Poisson equations, whose right-hand side is quadratic,
with Taylor coefficients from Cauchy products and a step chosen so that the
first neglected term is below ``tol``. Used to measure errors of the double
precision integrators down to ~1e-13 and below (benchmarks, accuracy tests).
"""

from __future__ import annotations

import numpy as np

from gyrolab.errors import ConfigError

EXTENDED = np.longdouble


def _cauchy_cross(a: np.ndarray, b: np.ndarray, k: int) -> np.ndarray:
    """k-th Taylor coefficient of a(t) × b(t) from coefficient rows a[0..k], b[0..k]."""
    return np.cross(a[: k + 1], b[k::-1]).sum(axis=0)


def fixed_point_reference(inertia, weight_moment, newtonian_n, y0, t_out, *, order: int = 28,
                          tol: float = 1e-21) -> np.ndarray:
    """State (ω, γ) at the times t_out for I ω̇ = Iω×ω + w×γ + N γ×Iγ, γ̇ = γ×ω, in extended precision; given a
    9-component ``y0``, (ω, γ, α) with α̇ = α×ω (the body components of the fixed X axis: no torque reads them)."""
    if np.finfo(EXTENDED).eps > 1e-18:
        raise ConfigError("this platform's numpy.longdouble is plain double precision; no extended reference")
    inertia = np.asarray(inertia, dtype=EXTENDED)
    w = np.asarray(weight_moment, dtype=EXTENDED)
    n_grad = EXTENDED(newtonian_n)
    y = np.asarray(y0, dtype=EXTENDED).copy()
    t_out = np.asarray(t_out, dtype=EXTENDED)
    out = np.empty((len(t_out), y.size), dtype=EXTENDED)
    out[0] = y
    W = np.zeros((order + 1, 3), dtype=EXTENDED)
    G = np.zeros((order + 1, 3), dtype=EXTENDED)
    A = np.zeros((order + 1, y.size - 6), dtype=EXTENDED)  # α's rows (none without it)
    t, i = t_out[0], 1
    powers = np.arange(order + 1)
    while i < len(t_out):
        W[0], G[0], A[0] = y[:3], y[3:6], y[6:]
        for k in range(order):
            torque = _cauchy_cross(inertia * W, W, k) + np.cross(w, G[k]) - n_grad * _cauchy_cross(inertia * G, G, k)
            W[k + 1] = torque / inertia / (k + 1)
            G[k + 1] = _cauchy_cross(G, W, k) / (k + 1)
            if A.shape[1]:
                A[k + 1] = _cauchy_cross(A, W, k) / (k + 1)
        scale = max(EXTENDED(1), np.max(np.abs(y)))
        norms = [max(np.max(np.abs(W[k])), np.max(np.abs(G[k]))) for k in (order - 1, order)]
        h = min((tol * scale / nk) ** (EXTENDED(1) / k) for nk, k in zip(norms, (order - 1, order)) if nk > 0)
        t_new = min(t + EXTENDED(0.9) * h, t_out[-1])
        while i < len(t_out) and t_out[i] <= t_new:
            dt_powers = (t_out[i] - t) ** powers
            out[i] = np.concatenate([dt_powers @ W, dt_powers @ G, dt_powers @ A])
            i += 1
        h_powers = (t_new - t) ** powers
        y = np.concatenate([h_powers @ W, h_powers @ G, h_powers @ A])
        t = t_new
    return out
