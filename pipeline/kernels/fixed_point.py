"""The fixed-point system's packed built-in torque parameters, and the right-hand side the chaos kernels read.

Parameters are one float array ``p`` (``pack`` writes it), laid out and named in ``layout``: inertia I,
the linear-torque vectors U_i (torque U_i × e_i), the gradient coefficients N_i (torque N_i e_i × I e_i),
a flag saying whether the state carries α, and 1/I. e_0 = α (fixed X), e_1 = β = γ × α (fixed Y),
e_2 = γ (vertical).
"""

from __future__ import annotations

import numpy as np

from gyrolab.kernels.compiler import inline_kernel, kernel
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
    """The packed parameters (``pack``) when every force has ``compiled_terms()``, else None.

    Every kernel runs the system's traced equations; the Lie–Poisson splitting, the regimes and the chaos
    kernels read these parameters."""
    terms = [force.compiled_terms() for force in forces]
    if any(term is None for term in terms):
        return None
    return pack(inertia, terms, carries_alpha)


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
