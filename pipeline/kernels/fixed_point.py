"""Compiled (numba) kernels of the fixed-point system: right-hand side and Taylor coefficients.

Parameters are one float array ``p`` (``pack`` writes it), laid out and named in ``layout``: inertia I,
the linear-torque vectors U_i (torque U_i × e_i), the gradient coefficients N_i (torque N_i e_i × I e_i),
a flag saying whether the state carries α, and 1/I. e_0 = α (fixed X), e_1 = β = γ × α (fixed Y),
e_2 = γ (vertical).
"""

from __future__ import annotations

import numba
import numpy as np

from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.layout import (  # noqa: F401  (N_PARAMS: fixed_point.N_PARAMS for callers)
    CARRIES_ALPHA, CompiledTerms, GRADIENT, INERTIA, INV_INERTIA, LINEAR, N_PARAMS, N_X, N_Y, N_Z, U_X, U_Y, U_Z,
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


def compiled_model(inertia: np.ndarray, forces: list, carries_alpha: bool):
    """The hand-written kernels' model (``models.FIXED_POINT``) when every force has ``compiled_terms()``, else None
    (the system is then compiled from its traced equations, ``model.compiled_system``)."""
    from gyrolab.kernels.model import CompiledModel

    terms = [force.compiled_terms() for force in forces]
    if any(term is None for term in terms):
        return None
    return CompiledModel(0, pack(inertia, terms, carries_alpha))  # models.FIXED_POINT (models imports numba's types)


@inline_kernel
def _cross_add(u0, u1, u2, v0, v1, v2, s):
    """s · (u × v) as three floats."""
    return s * (u1 * v2 - u2 * v1), s * (u2 * v0 - u0 * v2), s * (u0 * v1 - u1 * v0)


def _rhs_form(alpha: bool | None):
    """The right-hand side for states (ω, γ, α) if ``alpha``, (ω, γ) if not, either by the flag p[CARRIES_ALPHA] if None.

    ``alpha`` is a constant of the closure: numba drops the dead branches before typing, so the (ω, γ)
    form types and compiles none of the α terms (``models.Form``: kernels compiled per model).
    """

    @inline_kernel
    def rhs(t, y, p, out):
        has_alpha = p[CARRIES_ALPHA] != 0.0 if alpha is None else alpha
        I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
        w0, w1, w2 = y[0], y[1], y[2]
        g0, g1, g2 = y[3], y[4], y[5]
        # gyroscopic torque (Iω) × ω
        t0 = (I1 - I2) * w1 * w2
        t1 = (I2 - I0) * w2 * w0
        t2 = (I0 - I1) * w0 * w1
        # U_2 × γ  and  N_2 γ × Iγ
        a0, a1, a2 = _cross_add(p[U_Z], p[U_Z + 1], p[U_Z + 2], g0, g1, g2, 1.0)
        n = p[N_Z]
        t0 += a0 + n * (I2 - I1) * g1 * g2
        t1 += a1 + n * (I0 - I2) * g2 * g0
        t2 += a2 + n * (I1 - I0) * g0 * g1
        out[3] = g1 * w2 - g2 * w1
        out[4] = g2 * w0 - g0 * w2
        out[5] = g0 * w1 - g1 * w0
        if has_alpha:
            x0, x1, x2 = y[6], y[7], y[8]
            b0, b1, b2 = g1 * x2 - g2 * x1, g2 * x0 - g0 * x2, g0 * x1 - g1 * x0
            c0, c1, c2 = _cross_add(p[U_X], p[U_X + 1], p[U_X + 2], x0, x1, x2, 1.0)
            d0, d1, d2 = _cross_add(p[U_Y], p[U_Y + 1], p[U_Y + 2], b0, b1, b2, 1.0)
            nx, ny = p[N_X], p[N_Y]
            t0 += c0 + d0 + nx * (I2 - I1) * x1 * x2 + ny * (I2 - I1) * b1 * b2
            t1 += c1 + d1 + nx * (I0 - I2) * x2 * x0 + ny * (I0 - I2) * b2 * b0
            t2 += c2 + d2 + nx * (I1 - I0) * x0 * x1 + ny * (I1 - I0) * b0 * b1
            out[6] = x1 * w2 - x2 * w1
            out[7] = x2 * w0 - x0 * w2
            out[8] = x0 * w1 - x1 * w0
        out[0] = t0 * p[INV_INERTIA]
        out[1] = t1 * p[INV_INERTIA + 1]
        out[2] = t2 * p[INV_INERTIA + 2]

    return rhs


#: The right-hand side of the state (ω, γ), of (ω, γ, α), and of either (by p[CARRIES_ALPHA] at run time).
rhs_gamma = _rhs_form(False)
rhs_alpha = _rhs_form(True)
rhs = _rhs_form(None)


@kernel
def _cauchy_cross(A, ia, B, ib, k, s0, s1, s2, out):
    """out += Σ_j s ⊙ (A[j, ia:ia+3]) × B[k−j, ib:ib+3] with a per-component scale s of A."""
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    for j in range(k + 1):
        u0, u1, u2 = s0 * A[j, ia], s1 * A[j, ia + 1], s2 * A[j, ia + 2]
        v0, v1, v2 = B[k - j, ib], B[k - j, ib + 1], B[k - j, ib + 2]
        r0 += u1 * v2 - u2 * v1
        r1 += u2 * v0 - u0 * v2
        r2 += u0 * v1 - u1 * v0
    out[0] += r0
    out[1] += r1
    out[2] += r2


@kernel
def _cauchy_pairs(A, ia, k, out):
    """k-th coefficients of (e_y e_z, e_z e_x, e_x e_y) for e = A[:, ia:ia+3]: the products behind e × I e."""
    r0 = 0.0
    r1 = 0.0
    r2 = 0.0
    for j in range(k + 1):
        x0, x1, x2 = A[j, ia], A[j, ia + 1], A[j, ia + 2]
        z0, z1, z2 = A[k - j, ia], A[k - j, ia + 1], A[k - j, ia + 2]
        r0 += x1 * z2
        r1 += x2 * z0
        r2 += x0 * z1
    out[0] = r0
    out[1] = r1
    out[2] = r2


# The Cauchy sums may be reassociated and contracted (fused multiply-add): ~15 % faster, and a coefficient's
# rounding enters the state multiplied by h^k. The state update itself (``taylor.run``) stays strict: its
# Kahan summation would be optimised away under reassociation.
def _taylor_form(alpha: bool | None):
    """``taylor_coefficients`` for states (ω, γ, α) if ``alpha``, (ω, γ) if not (the other form's code pruned as in
    ``_rhs_form``), either by the flag p[CARRIES_ALPHA] if None."""

    @numba.njit(cache=True, error_model="numpy", fastmath={"reassoc", "contract", "nsz"})
    def taylor_coefficients(p, Y, order, work):
        """Fill Y[1..order] (rows: Taylor coefficients of the state) from Y[0].

        The right-hand side is quadratic in the state, so the k-th coefficient of
        every product is a Cauchy sum (Jorba & Zou 2005): Y[k+1] = F_k / (k + 1).
        The gyroscopic and gradient torques use their component form,
        ((Iω) × ω)_x = (I_y − I_z) ω_y ω_z, one product per term instead of two.
        The sums over ω and γ (the products of (Iω) × ω, γ × Iγ and γ × ω) share one
        pass over the coefficient rows. ``work`` (order+1, 3) holds the coefficients
        of β = γ × α in the form with α.
        """
        I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
        d0, d1, d2 = I1 - I2, I2 - I0, I0 - I1  # ((Iω) × ω) = (d0 ω_y ω_z, d1 ω_z ω_x, d2 ω_x ω_y)
        has_alpha = p[CARRIES_ALPHA] != 0.0 if alpha is None else alpha
        n2 = p[N_Z]
        acc = np.empty(3)
        tmp = np.empty(3)
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
            # (Iω) × ω + U_2 × γ − N_2 (d ⊙ pairs of γ)   (N_2 γ × Iγ = −N_2 d ⊙ pairs)
            acc[0] = d0 * (w0 - n2 * g0) + p[U_Z + 1] * e2 - p[U_Z + 2] * e1
            acc[1] = d1 * (w1 - n2 * g1) + p[U_Z + 2] * e0 - p[U_Z] * e2
            acc[2] = d2 * (w2 - n2 * g2) + p[U_Z] * e1 - p[U_Z + 1] * e0
            if has_alpha:
                work[k, 0] = work[k, 1] = work[k, 2] = 0.0  # β_k = Σ γ_j × α_{k−j}
                _cauchy_cross(Y, 3, Y, 6, k, 1.0, 1.0, 1.0, work[k])
                x0, x1, x2 = Y[k, 6], Y[k, 7], Y[k, 8]
                b0, b1, b2 = work[k, 0], work[k, 1], work[k, 2]
                acc[0] += p[U_X + 1] * x2 - p[U_X + 2] * x1 + p[U_Y + 1] * b2 - p[U_Y + 2] * b1
                acc[1] += p[U_X + 2] * x0 - p[U_X] * x2 + p[U_Y + 2] * b0 - p[U_Y] * b2
                acc[2] += p[U_X] * x1 - p[U_X + 1] * x0 + p[U_Y] * b1 - p[U_Y + 1] * b0
                if p[N_X] != 0.0:
                    _cauchy_pairs(Y, 6, k, tmp)
                    acc[0] -= p[N_X] * d0 * tmp[0]
                    acc[1] -= p[N_X] * d1 * tmp[1]
                    acc[2] -= p[N_X] * d2 * tmp[2]
                if p[N_Y] != 0.0:
                    _cauchy_pairs(work, 0, k, tmp)
                    acc[0] -= p[N_Y] * d0 * tmp[0]
                    acc[1] -= p[N_Y] * d1 * tmp[1]
                    acc[2] -= p[N_Y] * d2 * tmp[2]
            inv = 1.0 / (k + 1)
            Y[k + 1, 0] = acc[0] * p[INV_INERTIA] * inv
            Y[k + 1, 1] = acc[1] * p[INV_INERTIA + 1] * inv
            Y[k + 1, 2] = acc[2] * p[INV_INERTIA + 2] * inv
            # γ̇ = γ × ω, α̇ = α × ω
            Y[k + 1, 3], Y[k + 1, 4], Y[k + 1, 5] = c0 * inv, c1 * inv, c2 * inv
            if has_alpha:
                acc[0] = acc[1] = acc[2] = 0.0
                _cauchy_cross(Y, 6, Y, 0, k, 1.0, 1.0, 1.0, acc)
                Y[k + 1, 6], Y[k + 1, 7], Y[k + 1, 8] = acc[0] * inv, acc[1] * inv, acc[2] * inv

    return taylor_coefficients


taylor_gamma = _taylor_form(False)
taylor_alpha = _taylor_form(True)
taylor_coefficients = _taylor_form(None)


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
