"""Lie–Poisson splitting for the heavy body about a fixed point (Touma & Wisdom 1994; McLachlan 1993).

H = L1²/2A + L2²/2B + L3²/2C + V(e_i). Each piece has an exact flow:
rotation of L, γ (and α) about body axis i by the angle −τ L_i/I_i for the
kinetic pieces, and the kick L ← L + τ Σ e_i × ∂V/∂e_i for the potential.
Strang composition K(h/2) R1(h/2) R2(h/2) R3(h) R2(h/2) R1(h/2) K(h/2) is a
second-order Poisson integrator; Yoshida's triple jump raises it to order 4
and 6. Every sub-flow is a rotation or leaves γ fixed, so |γ| = 1 and the
Casimir L·γ hold to round-off for any step, and the energy error stays
bounded instead of drifting.
"""

from __future__ import annotations

import math

import numpy as np

from gyrolab.kernels.layout import CARRIES_ALPHA, INERTIA, INV_INERTIA, N_X, N_Y, N_Z, U_X, U_Y, U_Z
from gyrolab.kernels.compiler import inline_kernel, kernel

# Yoshida (1990) triple-jump weights: order 2 -> 4 -> 6
_W4 = (1.0 / (2.0 - 2.0 ** (1.0 / 3.0)), -(2.0 ** (1.0 / 3.0)) / (2.0 - 2.0 ** (1.0 / 3.0)))
_W6 = (1.0 / (2.0 - 2.0 ** (1.0 / 5.0)), -(2.0 ** (1.0 / 5.0)) / (2.0 - 2.0 ** (1.0 / 5.0)))


def weights(order: int) -> np.ndarray:
    """Step fractions of the Strang sub-steps for a composition of the given order."""
    if order == 2:
        return np.array([1.0])
    if order == 4:
        a, b = _W4
        return np.array([a, b, a])
    if order == 6:
        a, b = _W6
        inner = weights(4)
        return np.concatenate([a * inner, b * inner, a * inner])
    raise ValueError(order)


@inline_kernel
def _rotate(v, i, j, angle_cos, angle_sin):
    """Rotate the (i, j) components of v: (v_i, v_j) ← (c v_i + s v_j, c v_j − s v_i)."""
    vi, vj = v[i], v[j]
    v[i] = angle_cos * vi + angle_sin * vj
    v[j] = angle_cos * vj - angle_sin * vi


@inline_kernel
def _free_rotation(axis, tau, L, g, a, p, has_alpha):
    """Exact flow of L_axis²/(2 I_axis) for time tau: v̇ = v × (L_axis/I_axis) e_axis for v = L, γ, α."""
    rate = L[axis] * p[INV_INERTIA + axis] * tau
    c, s = math.cos(rate), math.sin(rate)
    # v̇ = c0 v × e_x: (y, z) rotate with +; e_y: (z, x); e_z: (x, y)
    i, j = (1, 2) if axis == 0 else ((2, 0) if axis == 1 else (0, 1))
    _rotate(L, i, j, c, s)
    _rotate(g, i, j, c, s)
    if has_alpha:
        _rotate(a, i, j, c, s)


@inline_kernel
def _kick(tau, L, g, a, p, has_alpha):
    """Exact flow of the potential: L += tau · (U2 × γ + N2 γ × Iγ [+ U0 × α + U1 × β + N0 α × Iα + N1 β × Iβ])."""
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    g0, g1, g2 = g[0], g[1], g[2]
    t0 = p[U_Z + 1] * g2 - p[U_Z + 2] * g1 + p[N_Z] * (I2 - I1) * g1 * g2
    t1 = p[U_Z + 2] * g0 - p[U_Z] * g2 + p[N_Z] * (I0 - I2) * g2 * g0
    t2 = p[U_Z] * g1 - p[U_Z + 1] * g0 + p[N_Z] * (I1 - I0) * g0 * g1
    if has_alpha:
        x0, x1, x2 = a[0], a[1], a[2]
        b0, b1, b2 = g1 * x2 - g2 * x1, g2 * x0 - g0 * x2, g0 * x1 - g1 * x0
        t0 += p[U_X + 1] * x2 - p[U_X + 2] * x1 + p[U_Y + 1] * b2 - p[U_Y + 2] * b1 + (I2 - I1) * (p[N_X] * x1 * x2 + p[N_Y] * b1 * b2)
        t1 += p[U_X + 2] * x0 - p[U_X] * x2 + p[U_Y + 2] * b0 - p[U_Y] * b2 + (I0 - I2) * (p[N_X] * x2 * x0 + p[N_Y] * b2 * b0)
        t2 += p[U_X] * x1 - p[U_X + 1] * x0 + p[U_Y] * b1 - p[U_Y + 1] * b0 + (I1 - I0) * (p[N_X] * x0 * x1 + p[N_Y] * b0 * b1)
    L[0] += tau * t0
    L[1] += tau * t1
    L[2] += tau * t2


@kernel
def _strang(h, L, g, a, p, has_alpha):
    _kick(0.5 * h, L, g, a, p, has_alpha)
    _free_rotation(0, 0.5 * h, L, g, a, p, has_alpha)
    _free_rotation(1, 0.5 * h, L, g, a, p, has_alpha)
    _free_rotation(2, h, L, g, a, p, has_alpha)
    _free_rotation(1, 0.5 * h, L, g, a, p, has_alpha)
    _free_rotation(0, 0.5 * h, L, g, a, p, has_alpha)
    _kick(0.5 * h, L, g, a, p, has_alpha)


@kernel
def run(p, t_out, steps_per_interval, w, y, Y, i_next, i_stop):
    """Fill Y[i_next:i_stop] (state ω, γ[, α]); y advanced in place. Returns the first non-finite index or i_stop."""
    has_alpha = p[CARRIES_ALPHA] != 0.0
    L = np.empty(3)
    g = np.empty(3)
    a = np.empty(3)
    for m in range(3):
        L[m] = p[m] * y[m]
        g[m] = y[3 + m]
        if has_alpha:
            a[m] = y[6 + m]
    for i in range(i_next, i_stop):
        h = (t_out[i] - t_out[i - 1]) / steps_per_interval[i - 1]
        for _ in range(steps_per_interval[i - 1]):
            for weight in w:
                _strang(weight * h, L, g, a, p, has_alpha)
        for m in range(3):
            y[m] = L[m] * p[INV_INERTIA + m]
            y[3 + m] = g[m]
            if has_alpha:
                y[6 + m] = a[m]
        for m in range(y.size):
            if not math.isfinite(y[m]):
                return i
            Y[i, m] = y[m]
    return i_stop
