"""Compiled (numba) kernels of the fixed-point system (ω, γ): right-hand side and Taylor coefficients.

Parameters are one float array ``p`` (``pack`` writes it), laid out and named in ``layout``: inertia I,
the linear-torque vectors U_i (torque U_i × e_i), the gradient coefficients N_i (torque N_i e_i × I e_i),
a flag saying whether the state carries α, and 1/I. e_0 = α (fixed X), e_1 = β = γ × α (fixed Y),
e_2 = γ (vertical).
"""

from __future__ import annotations

import functools

import numba
import numpy as np

from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.expression import Graph, cross, symbols
from gyrolab.kernels.model import Model
from gyrolab.kernels.layout import (  # noqa: F401  (N_PARAMS: fixed_point.N_PARAMS for callers)
    CARRIES_ALPHA, CompiledTerms, GRADIENT, INERTIA, INV_INERTIA, LINEAR, N_PARAMS, N_Z, U_Z,
)


def pack(inertia: np.ndarray, terms: list[CompiledTerms], carries_alpha: bool) -> np.ndarray:
    p = np.zeros(N_PARAMS)
    p[INERTIA:INERTIA + 3] = inertia
    for term in terms:
        for axis, u in term.linear.items():
            p[LINEAR[axis]:LINEAR[axis] + 3] += u
        for axis, n in term.gradient.items():
            p[GRADIENT[axis]] += n
    p[CARRIES_ALPHA] = 1.0 if carries_alpha else 0.0
    p[INV_INERTIA:INV_INERTIA + 3] = 1.0 / inertia  # multiplications in the inner loop, not divisions
    return p


def built_in(inertia: np.ndarray, forces: list, carries_alpha: bool) -> np.ndarray | None:
    """The hand-written kernels' parameters (``pack``) when every force has ``compiled_terms()``, else None.

    The kernels of ``models.FIXED_POINT`` (below, ``taylor``'s vector step, the batch lanes, double-double,
    the tangent flow) take the state (ω, γ) only; a scene that carries α runs its traced equations, which
    measured 2× faster under ``taylor`` and 10 % faster under DOP853 than the hand-written α form they
    replaced (docs/performance.md). The Lie–Poisson splitting reads these parameters in either case."""
    terms = [force.compiled_terms() for force in forces]
    if any(term is None for term in terms):
        return None
    return pack(inertia, terms, carries_alpha)


@functools.cache
def packed_model() -> Model:
    """The (ω, γ) equations of ``rhs`` traced with the packed parameters as the trace's numbers (p[i] is number i):
    the same model, in the form the generated kernels take (``batch_taylor``'s lanes read ``pack``'s rows as
    they are)."""
    graph = Graph()
    y = symbols(graph, "y", 6)
    p = [graph.lift(0.0) for _ in range(N_PARAMS)]  # numbers 0..N_PARAMS−1: the kernels read them from p
    inertia, inv = np.array(p[INERTIA:INERTIA + 3]), np.array(p[INV_INERTIA:INV_INERTIA + 3])
    omega, gamma = y[0:3], y[3:6]
    torque = cross(inertia * omega, omega) + cross(np.array(p[U_Z:U_Z + 3]), gamma) \
        + p[N_Z] * cross(gamma, inertia * gamma)
    return Model(graph, [*(torque * inv), *cross(gamma, omega)], 6, "the fixed point (ω, γ), built-in torques")


@inline_kernel
def _cross_add(u0, u1, u2, v0, v1, v2, s):
    """s · (u × v) as three floats."""
    return s * (u1 * v2 - u2 * v1), s * (u2 * v0 - u0 * v2), s * (u0 * v1 - u1 * v0)


@inline_kernel
def rhs(t, y, p, out):
    """The right-hand side of the state (ω, γ): I ω̇ = (Iω) × ω + U_2 × γ + N_2 γ × Iγ, γ̇ = γ × ω."""
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    w0, w1, w2 = y[0], y[1], y[2]
    g0, g1, g2 = y[3], y[4], y[5]
    # gyroscopic torque (Iω) × ω + (U_2 × γ + N_2 γ × Iγ), summed in this order
    a0, a1, a2 = _cross_add(p[U_Z], p[U_Z + 1], p[U_Z + 2], g0, g1, g2, 1.0)
    n = p[N_Z]
    out[0] = ((I1 - I2) * w1 * w2 + (a0 + n * (I2 - I1) * g1 * g2)) * p[INV_INERTIA]
    out[1] = ((I2 - I0) * w2 * w0 + (a1 + n * (I0 - I2) * g2 * g0)) * p[INV_INERTIA + 1]
    out[2] = ((I0 - I1) * w0 * w1 + (a2 + n * (I1 - I0) * g0 * g1)) * p[INV_INERTIA + 2]
    out[3] = g1 * w2 - g2 * w1
    out[4] = g2 * w0 - g0 * w2
    out[5] = g0 * w1 - g1 * w0


# The Cauchy sums may be reassociated and contracted (fused multiply-add): ~15 % faster, and a coefficient's
# rounding enters the state multiplied by h^k. The state update itself (``taylor.run``) stays strict: its
# Kahan summation would be optimised away under reassociation.
@numba.njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract", "nsz"})
def taylor_coefficients(p, Y, order, work):
    """Fill Y[1..order] (rows: Taylor coefficients of the state (ω, γ)) from Y[0].

    The right-hand side is quadratic in the state, so the k-th coefficient of
    every product is a Cauchy sum (Jorba & Zou 2005): Y[k+1] = F_k / (k + 1).
    The gyroscopic and gradient torques use their component form,
    ((Iω) × ω)_x = (I_y − I_z) ω_y ω_z, one product per term instead of two.
    The sums over ω and γ (the products of (Iω) × ω, γ × Iγ and γ × ω) share one
    pass over the coefficient rows. ``work`` is unused (the traced form's signature).
    """
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    d0, d1, d2 = I1 - I2, I2 - I0, I0 - I1  # ((Iω) × ω) = (d0 ω_y ω_z, d1 ω_z ω_x, d2 ω_x ω_y)
    n2 = p[N_Z]
    for k in range(order):
        # one pass: pairs of ω (w·), pairs of γ (g·), γ × ω (c·)
        w0 = w1 = w2 = 0.0
        g0 = g1 = g2 = 0.0
        c0 = c1 = c2 = 0.0
        for j in range(k + 1):
            a0, a1, a2 = Y[j, 0], Y[j, 1], Y[j, 2]
            b0, b1, b2 = Y[j, 3], Y[j, 4], Y[j, 5]
            A0, A1, A2 = Y[k - j, 0], Y[k - j, 1], Y[k - j, 2]
            B0, B1, B2 = Y[k - j, 3], Y[k - j, 4], Y[k - j, 5]
            w0 += a1 * A2
            w1 += a2 * A0
            w2 += a0 * A1
            g0 += b1 * B2
            g1 += b2 * B0
            g2 += b0 * B1
            c0 += b1 * A2 - b2 * A1
            c1 += b2 * A0 - b0 * A2
            c2 += b0 * A1 - b1 * A0
        e0, e1, e2 = Y[k, 3], Y[k, 4], Y[k, 5]
        inv = 1.0 / (k + 1)
        # (Iω) × ω + U_2 × γ − N_2 (d ⊙ pairs of γ)   (N_2 γ × Iγ = −N_2 d ⊙ pairs)
        Y[k + 1, 0] = (d0 * (w0 - n2 * g0) + p[U_Z + 1] * e2 - p[U_Z + 2] * e1) * p[INV_INERTIA] * inv
        Y[k + 1, 1] = (d1 * (w1 - n2 * g1) + p[U_Z + 2] * e0 - p[U_Z] * e2) * p[INV_INERTIA + 1] * inv
        Y[k + 1, 2] = (d2 * (w2 - n2 * g2) + p[U_Z] * e1 - p[U_Z + 1] * e0) * p[INV_INERTIA + 2] * inv
        # γ̇ = γ × ω
        Y[k + 1, 3], Y[k + 1, 4], Y[k + 1, 5] = c0 * inv, c1 * inv, c2 * inv


@kernel
def rhs_block(Y, P, out, count):
    """The right-hand side for a block of trajectories stored by columns: Y[:, j] is trajectory j.

    Same arithmetic as ``rhs`` (without the α terms: blocks carry (ω, γ) only), written
    as loops over the block so that they vectorise across trajectories.
    """
    for j in range(count):
        w0, w1, w2 = Y[0, j], Y[1, j], Y[2, j]
        g0, g1, g2 = Y[3, j], Y[4, j], Y[5, j]
        I0, I1, I2 = P[INERTIA, j], P[INERTIA + 1, j], P[INERTIA + 2, j]
        n = P[N_Z, j]
        u0, u1, u2 = P[U_Z, j], P[U_Z + 1, j], P[U_Z + 2, j]
        out[0, j] = ((I1 - I2) * w1 * w2 + u1 * g2 - u2 * g1 + n * (I2 - I1) * g1 * g2) * P[INV_INERTIA, j]
        out[1, j] = ((I2 - I0) * w2 * w0 + u2 * g0 - u0 * g2 + n * (I0 - I2) * g2 * g0) * P[INV_INERTIA + 1, j]
        out[2, j] = ((I0 - I1) * w0 * w1 + u0 * g1 - u1 * g0 + n * (I1 - I0) * g0 * g1) * P[INV_INERTIA + 2, j]
        out[3, j] = g1 * w2 - g2 * w1
        out[4, j] = g2 * w0 - g0 * w2
        out[5, j] = g0 * w1 - g1 * w0
