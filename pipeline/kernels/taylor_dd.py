"""The Taylor series method in double-double arithmetic (≈ 32 digits): "clean numerical simulation" (Liao 2009).

A traced model's coefficients come from its generated series (``series_dd``, the same rules as below); the
hand-written ones here serve the fixed-point model with its built-in torque forms (``fixed_point``: the gyroscopic torque, U_i × e_i, the
gradient term N_2 γ × I γ, the state (ω, γ)), the same method as ``taylor.run_scalar``: Taylor
coefficients from Cauchy products of the quadratic right-hand side, Jorba & Zou's order (``taylor.order_for``)
and step (``taylor.step_size``, from the last two coefficients' max norms) for a tolerance down to 1e-32,
the series as the dense output. Every number that enters the state is a double-double
(``double_double``):

* the state is carried in double-double between steps (``yh``, ``yl``: high and low parts);
* the Cauchy sums are compensated dot products (``double_double.dot_add``: error ≤ ~k·u²·Σ|terms| for the
  k-th coefficient, u² = 2^-106), the scalings in double-double;
* the parameters are doubles, hence exact as double-doubles, but the derived constants are not: 1/I_k is
  computed in double-double (``dd_div_d``; the parameter array's double ``INV_INERTIA`` is not used, its
  rounding of 1e-16 would cap the run at 16 digits) and I_j − I_k exactly (``two_sum``);
* time stays a double: a step ends on fl(t + h), and the step actually taken, t_new − t, and every dense
  output's offset t_out[i] − t are formed exactly as double-doubles (``two_sum``), so no time error enters;
* the state update and the dense output are Horner sums in double-double; an output is stored as the double
  nearest its double-double value (its high part), and optionally its low part (``Ylo``).

Step selection works on the high parts (a step size needs no 32 digits). Status codes as ``taylor``'s.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.double_double import (
    dd_add, dd_div_d, dd_mul, dd_mul_d, dd_norm, dd_sub, dot_add, two_sum,
)
from gyrolab.kernels.layout import (
    GAMMA, INERTIA, N_PARAMS, N_Z, OMEGA, U_Z,
)
from gyrolab.kernels.taylor import NOT_FINITE, OK, TOO_SMALL_STEP, _norm_inf, order_for, step_size

#: the smallest tolerance the double-double kernel takes (its unit round-off is 2^-106 ≈ 1.2e-32)
MIN_TOL = 1e-32
#: rows of ``constants``: 1/I_k (INV), then d_k = I_{k+1} − I_{k+2} (DIFF), each (hi, lo)
INV, DIFF = 0, 3


@kernel
def constants(p):
    """(2, 6) array: row 0 the high parts, row 1 the low parts of 1/I_0, 1/I_1, 1/I_2 and of the differences
    d = (I_1 − I_2, I_2 − I_0, I_0 − I_1), all in double-double from the double inertia."""
    C = np.zeros((2, 6))
    for k in range(3):
        C[0, INV + k], C[1, INV + k] = dd_div_d(1.0, 0.0, p[INERTIA + k])
        C[0, DIFF + k], C[1, DIFF + k] = two_sum(p[INERTIA + (k + 1) % 3], -p[INERTIA + (k + 2) % 3])
    return C


@inline_kernel
def _pairs(Xh, Xl, ix, Zh, Zl, iz, k):
    """The k-th coefficients of (x_y z_z, x_z z_x, x_x z_y) for x = X[:, ix:ix+3], z = Z[:, iz:iz+3], each
    normalised (six floats: hi, lo of each component)."""
    s0 = l0 = s1 = l1 = s2 = l2 = 0.0
    for j in range(k + 1):
        m = k - j
        s0, l0 = dot_add(s0, l0, Xh[j, ix + 1], Xl[j, ix + 1], Zh[m, iz + 2], Zl[m, iz + 2])
        s1, l1 = dot_add(s1, l1, Xh[j, ix + 2], Xl[j, ix + 2], Zh[m, iz], Zl[m, iz])
        s2, l2 = dot_add(s2, l2, Xh[j, ix], Xl[j, ix], Zh[m, iz + 1], Zl[m, iz + 1])
    s0, l0 = dd_norm(s0, l0)
    s1, l1 = dd_norm(s1, l1)
    s2, l2 = dd_norm(s2, l2)
    return s0, l0, s1, l1, s2, l2


@inline_kernel
def _cross(Xh, Xl, ix, Zh, Zl, iz, k):
    """The k-th coefficient of x × z, Σ_j x_j × z_{k−j}, for x = X[:, ix:ix+3], z = Z[:, iz:iz+3] (six floats)."""
    s0 = l0 = s1 = l1 = s2 = l2 = 0.0
    for j in range(k + 1):
        m = k - j
        x0h, x1h, x2h = Xh[j, ix], Xh[j, ix + 1], Xh[j, ix + 2]
        x0l, x1l, x2l = Xl[j, ix], Xl[j, ix + 1], Xl[j, ix + 2]
        z0h, z1h, z2h = Zh[m, iz], Zh[m, iz + 1], Zh[m, iz + 2]
        z0l, z1l, z2l = Zl[m, iz], Zl[m, iz + 1], Zl[m, iz + 2]
        s0, l0 = dot_add(s0, l0, x1h, x1l, z2h, z2l)
        s0, l0 = dot_add(s0, l0, -x2h, -x2l, z1h, z1l)
        s1, l1 = dot_add(s1, l1, x2h, x2l, z0h, z0l)
        s1, l1 = dot_add(s1, l1, -x0h, -x0l, z2h, z2l)
        s2, l2 = dot_add(s2, l2, x0h, x0l, z1h, z1l)
        s2, l2 = dot_add(s2, l2, -x1h, -x1l, z0h, z0l)
    s0, l0 = dd_norm(s0, l0)
    s1, l1 = dd_norm(s1, l1)
    s2, l2 = dd_norm(s2, l2)
    return s0, l0, s1, l1, s2, l2


@inline_kernel
def _u_cross(u0, u1, u2, h0, l0, h1, l1, h2, l2):
    """U × v for a double vector U and a double-double vector v (six floats)."""
    ph, pl = dd_mul_d(h2, l2, u1)
    qh, ql = dd_mul_d(h1, l1, u2)
    a0, b0 = dd_sub(ph, pl, qh, ql)
    ph, pl = dd_mul_d(h0, l0, u2)
    qh, ql = dd_mul_d(h2, l2, u0)
    a1, b1 = dd_sub(ph, pl, qh, ql)
    ph, pl = dd_mul_d(h1, l1, u0)
    qh, ql = dd_mul_d(h0, l0, u1)
    a2, b2 = dd_sub(ph, pl, qh, ql)
    return a0, b0, a1, b1, a2, b2


@kernel
def coefficients(p, C, Th, Tl, order):
    """Fill rows 1..order of the Taylor coefficients (Th, Tl: high and low parts, (order+1, state size)) from row 0.

    Y_{k+1} = F_k / (k + 1), F_k the k-th coefficient of the right-hand side: I ω̇ = Iω × ω + U_2 × γ + N_2 γ × Iγ,
    γ̇ = γ × ω; the gyroscopic and gradient torques in their component form ((Iω) × ω)_x = (I_y − I_z) ω_y ω_z.
    ``C`` is ``constants(p)``.
    """
    n_z = p[N_Z]
    acc = np.empty((2, 3))
    for k in range(order):
        w = _pairs(Th, Tl, OMEGA, Th, Tl, OMEGA, k)
        g = _pairs(Th, Tl, GAMMA, Th, Tl, GAMMA, k)
        gw = _cross(Th, Tl, GAMMA, Th, Tl, OMEGA, k)
        u = _u_cross(p[U_Z], p[U_Z + 1], p[U_Z + 2], Th[k, GAMMA], Tl[k, GAMMA], Th[k, GAMMA + 1], Tl[k, GAMMA + 1],
                     Th[k, GAMMA + 2], Tl[k, GAMMA + 2])
        for c in range(3):
            # d_c (pairs of ω − N_2 pairs of γ) + (U_2 × γ_k)_c   (N_2 γ × Iγ = −N_2 d ⊙ pairs of γ)
            qh, ql = dd_mul_d(g[2 * c], g[2 * c + 1], n_z)
            sh, sl = dd_sub(w[2 * c], w[2 * c + 1], qh, ql)
            qh, ql = dd_mul(C[0, DIFF + c], C[1, DIFF + c], sh, sl)
            acc[0, c], acc[1, c] = dd_add(qh, ql, u[2 * c], u[2 * c + 1])
        for c in range(3):
            sh, sl = dd_mul(acc[0, c], acc[1, c], C[0, INV + c], C[1, INV + c])
            Th[k + 1, OMEGA + c], Tl[k + 1, OMEGA + c] = dd_div_d(sh, sl, k + 1.0)
            Th[k + 1, GAMMA + c], Tl[k + 1, GAMMA + c] = dd_div_d(gw[2 * c], gw[2 * c + 1], k + 1.0)


@inline_kernel
def _horner(Th, Tl, order, hh, hl, vh, vl):
    """v[m] = Σ_{k=0}^{order} T[k, m] h^k in double-double for a double-double h, every component m side by side
    (independent chains: one Horner sum alone waits on its own latency)."""
    n = vh.size
    for m in range(n):
        vh[m], vl[m] = Th[order, m], Tl[order, m]
    for k in range(order - 1, -1, -1):
        for m in range(n):
            ph, pl = dd_mul(vh[m], vl[m], hh, hl)
            vh[m], vl[m] = dd_add(ph, pl, Th[k, m], Tl[k, m])


@intrinsic
def _call_generated(typingctx, address, t, order, Th, Tl, S, p):
    """Call ``void f(double t, int64 order, double* Th, double* Tl, double* S, double* p)`` at ``address``: a traced
    model's generated double-double series (``series_dd``)."""
    sig = types.void(types.int64, types.float64, types.int64, Th, Tl, S, p)

    def codegen(context, builder, signature, args):
        double_ptr = ir.DoubleType().as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [ir.DoubleType(), ir.IntType(64)] + [double_ptr] * 4)
        data = [builder.bitcast(cgutils.create_struct_proxy(ty)(context, builder, value=v).data, double_ptr)
                for ty, v in zip(signature.args[3:], args[3:])]
        builder.call(builder.inttoptr(args[0], fnty.as_pointer()), [args[1], args[2], *data])
        return context.get_dummy_value()

    return sig, codegen


@kernel
def run(model, p, order, tol, t_out, Y, Ylo, i_next, i_stop, state, yh, yl, stats):
    """Advance until t_out[i_stop − 1] is filled: ``taylor.run``'s contract (steps clipped at the last output
    time only, every output a step passes filled, state = [t], stats = [coefficient evaluations, steps],
    returns (status, next output index)) with the state in double-double (yh, yl). Y receives the outputs
    rounded to double; Ylo their low parts when it has Y's shape (else it is not touched).

    ``model`` is the compiled model's form id: the hand-written fixed point (0, ``coefficients``) or a traced
    model (its generated series, ``series_dd``, whose address and scratch columns end ``p``)."""
    n = yh.size
    Th = np.zeros((order + 1, n))
    Tl = np.zeros((order + 1, n))
    vh, vl = np.empty(n), np.empty(n)
    traced = model != 0
    C = np.zeros((2, 6)) if traced else constants(p)
    S = np.zeros((order + 1) * 2 * int(p[p.size - 1])) if traced else np.zeros(0)
    address = int(p[p.size - 2]) if traced else 0
    low = Ylo.shape[0] == Y.shape[0]
    t = state[0]
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    i = i_next
    safety = math.exp(-0.7 / (order - 1))
    code = OK
    while i < i_stop:
        for m in range(n):
            Th[0, m], Tl[0, m] = yh[m], yl[m]
        if traced:
            _call_generated(address, t, order, Th, Tl, S, p)
        else:
            coefficients(p, C, Th, Tl, order)
        stats[0] += 1
        scale = max(1.0, _norm_inf(yh))
        h = step_size(tol, scale, _norm_inf(Th[order - 1]), _norm_inf(Th[order]), order, safety)
        if not h < np.inf:
            h = t_end - t
        t_new = min(t + h, t_end)
        if t_new <= t:  # the step is below the spacing of floating-point numbers at t: no progress is possible
            code = TOO_SMALL_STEP
            break
        while i < n_out and t_out[i] <= t_new:
            dh, dl = two_sum(t_out[i], -t)  # the offset, exact
            _horner(Th, Tl, order, dh, dl, vh, vl)
            for m in range(n):
                Y[i, m] = vh[m]
                if low:
                    Ylo[i, m] = vl[m]
            i += 1
        hh, hl = two_sum(t_new, -t)  # the step taken, exact
        _horner(Th, Tl, order, hh, hl, yh, yl)
        finite = True
        for m in range(n):
            finite = finite and math.isfinite(yh[m]) and math.isfinite(yl[m])
        if not finite:
            code = NOT_FINITE
            break
        t = t_new
        stats[1] += 1
    state[0] = t
    return code, i


def propagate(p: np.ndarray, tol: float, t_out, y0, order: int | None = None, y0_low=None, model: int = 0):
    """The states at ``t_out`` from ``y0`` (doubles, or double-doubles with ``y0_low``) in one call into the kernel:
    (high parts, low parts), each (len(t_out), state size), the first row the initial state. For tests, benchmarks
    and callers that want all 32 digits; the integrator plugin (``Taylor(precision="double-double")``) chunks
    its calls for progress instead. Raises RuntimeError on a non-OK status."""
    if model == 0 and (len(p) != N_PARAMS or len(y0) != 6):  # (the hand-written kernel would read past them)
        raise ValueError("model 0 is the hand-written fixed point: packed parameters (fixed_point.pack) and a state "
                         "(ω, γ); pass model=1 for a traced model's parameters")
    t_out = np.asarray(t_out, dtype=float)
    yh = np.array(y0, dtype=float)
    yl = np.zeros_like(yh) if y0_low is None else np.array(y0_low, dtype=float)
    Y = np.empty((len(t_out), len(yh)))
    Ylo = np.empty_like(Y)
    Y[0], Ylo[0] = yh, yl
    state = np.array([t_out[0]])
    stats = np.zeros(2, dtype=np.int64)
    order = order_for(tol) if order is None else order
    status, _ = run(model, p, order, tol, t_out, Y, Ylo, 1, len(t_out), state, yh, yl, stats)
    if status != OK:
        raise RuntimeError(f"double-double Taylor kernel stopped near t={state[0]:.6g} (status {status})")
    return Y, Ylo
