"""Taylor series method of high order with automatic step size (Jorba & Zou, Exp. Math. 14, 2005).

The right-hand sides are quadratic, so the Taylor coefficients come from
Cauchy products (``models.taylor_coefficients``). The order follows from the
tolerance (``order_for``: p = ⌈−ln(tol)/2 + 1⌉, which minimises the work per
unit time when the coefficients decay geometrically) and the step from the last
two coefficients, h = min_k (tol·max(1, ‖y‖)/‖y_k‖)^(1/k) for k = p−1, p,
times Jorba and Zou's safety factor exp(−0.7/(p−1)). The series is the dense
output: every output time inside a step is one Horner evaluation, no extra step.

The state update y ← y + Σ_{k≥1} y_k h^k is a compensated (Kahan) sum: the low
bits lost when a small increment is added to an O(1) state are carried to the
next step, so round-off no longer grows as one ulp of the state per step (the
floor of the uncompensated update was ~2e-12 over the 3,000 steps of the
reference scene). Time needs no compensation: the step actually taken is
h = fl(t + h) − t, exact in floating point, and the state advances by exactly it.

The fixed-point model without α (the common case) takes a vectorised step
(``run_vector``): the state's components across the lanes of ``<4 x double>``
vectors, the nine scalar Cauchy sums as three vector sums (four fused
multiply-adds per term instead of eighteen scalar products), and the dense output
and the update over two vectors (ω, 0) and (γ, 0). It takes the same steps as
the scalar step (``run_scalar``, every other model) to rounding, at about half
the cost (``benchmarks/taylor_step.py``, docs/performance.md).
"""

from __future__ import annotations

import math

import numpy as np

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from gyrolab.kernels.layout import INERTIA, INV_INERTIA, N_Z, U_Z
from gyrolab.kernels import simd
from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.models import FIXED_POINT, FormType, taylor_coefficients
from gyrolab.kernels.simd import LANES

OK, TOO_SMALL_STEP, NOT_FINITE = 0, 1, 2  # dop853's codes
MIN_ORDER, MAX_ORDER = 4, 60


def order_for(tol: float) -> int:
    """Jorba & Zou's optimal order for a tolerance: ⌈−ln(tol)/2 + 1⌉, within [MIN_ORDER, MAX_ORDER]."""
    return int(min(MAX_ORDER, max(MIN_ORDER, math.ceil(-math.log(tol) / 2.0 + 1.0))))


@kernel
def _norm_inf(row):
    v = 0.0
    for x in row:
        v = max(v, abs(x))
    return v


@inline_kernel
def step_size(tol, scale, n1, n2, order, safety):
    """Jorba & Zou's step from the max norms n1, n2 of the last two coefficients (order − 1, order) and the
    state's scale; inf when both vanish (the caller then steps to the end)."""
    h = np.inf
    if n1 > 0:
        h = min(h, (tol * scale / n1) ** (1.0 / (order - 1)))
    if n2 > 0:
        h = min(h, (tol * scale / n2) ** (1.0 / order))
    return h * safety


@kernel
def run(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    """Advance until t_out[i_stop − 1] is filled.

    Steps are clipped at the run's last output time only, never at i_stop: where a call stops must not
    change the steps (the caller sizes calls by wall time, for progress), so every output the last
    step passes is filled, also beyond i_stop. state = [t]; carry = the Kahan compensation of y (zeros
    at the start); stats = [coefficient evaluations, steps]. Returns (status, index of the next output
    time to fill).

    The fixed-point model without α takes the vectorised step (``run_vector``), every other model
    ``run_scalar``. ``model`` is a ``models.Form`` (the choice is made when the kernel is compiled, which
    then compiles that form's step only) or an int (the choice is made at run time: every form compiled).
    """
    return _route(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats)


def _route(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    """``run``'s choice of step; compiled code only (the overload below)."""
    raise TypeError("taylor._route is called from compiled kernels only")


@overload(_route, jit_options={"error_model": "numpy"})
def _route_by_model(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    if isinstance(model, FormType):
        if model.id == FIXED_POINT:
            def vector(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
                return run_vector(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats)
            return vector

        def scalar(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
            return run_scalar(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats)
        return scalar
    if isinstance(model, types.Integer):
        def either(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
            if model == FIXED_POINT:
                return run_vector(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats)
            return run_scalar(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats)
        return either
    return None


@inline_kernel
def _horner(T, order, h, v):
    """v = Σ_{k=1..order} T[k] h^(k−1) for every component (Horner). The state's 3-vectors' three chains of
    dependent multiply-adds run side by side in registers, not one component after another: 8–16 % of a
    plugin scene's step, and the same operations per component, so the same results to the bit."""
    n = v.size
    whole = n - n % 3
    for b in range(0, whole, 3):
        a0, a1, a2 = T[order, b], T[order, b + 1], T[order, b + 2]
        for k in range(order - 1, 0, -1):
            a0 = a0 * h + T[k, b]
            a1 = a1 * h + T[k, b + 1]
            a2 = a2 * h + T[k, b + 2]
        v[b], v[b + 1], v[b + 2] = a0, a1, a2
    for m in range(whole, n):
        a = T[order, m]
        for k in range(order - 1, 0, -1):
            a = a * h + T[k, m]
        v[m] = a


@kernel
def run_scalar(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    """``run`` with scalar arithmetic, for every model with Taylor coefficients (``models.taylor_coefficients``)."""
    n = y.size
    T = np.empty((order + 1, n))
    work = np.zeros((order + 1, 3))
    v = np.empty(n)
    t = state[0]
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    i = i_next
    safety = math.exp(-0.7 / (order - 1))
    while i < i_stop:
        for m in range(n):
            T[0, m] = y[m]
        taylor_coefficients(model, p, T, order, work, t)
        stats[0] += 1
        scale = max(1.0, _norm_inf(y))
        n1 = _norm_inf(T[order - 1])
        n2 = _norm_inf(T[order])
        h = step_size(tol, scale, n1, n2, order, safety)
        if not h < np.inf:
            h = t_end - t
        t_new = min(t + h, t_end)
        h = t_new - t
        if h <= 0.0:  # the step is below the spacing of floating-point numbers at t: no progress is possible
            state[0] = t
            return TOO_SMALL_STEP, i
        while i < n_out and t_out[i] <= t_new:
            dt = t_out[i] - t
            _horner(T, order, dt, v)
            for m in range(n):
                Y[i, m] = y[m] + (v[m] * dt - carry[m])
            i += 1
        finite = True
        _horner(T, order, h, v)
        for m in range(n):
            # Kahan: y + v·h with the bits lost in the previous additions carried in `carry`
            inc = v[m] * h - carry[m]
            s = y[m] + inc
            carry[m] = (s - y[m]) - inc
            y[m] = s
            finite = finite and math.isfinite(s)
        if not finite:
            state[0] = t
            return NOT_FINITE, i
        t = t_new
        stats[1] += 1
    state[0] = t
    return OK, i


# The vectorised step of the fixed-point model without α: one trajectory, its components across the lanes of
# ``<4 x double>`` vectors. Each order's coefficients are stored as ROWS vectors: ω = (ω_x, ω_y, ω_z, 0),
# γ likewise, and their cyclic permutations ω⁽¹²⁰⁾ = (ω_y, ω_z, ω_x, 0), ω⁽²⁰¹⁾ = (ω_z, ω_x, ω_y, 0), so the
# nine scalar Cauchy sums of ``fixed_point.taylor_coefficients`` become three vector sums, four fused
# multiply-adds and four vector loads per term: pairs of ω Σ ω⁽¹²⁰⁾_j ⊙ ω⁽²⁰¹⁾_{k−j} (= (ω_y ω_z, ω_z ω_x, ω_x ω_y)
# terms), pairs of γ likewise, γ × ω = Σ γ⁽¹²⁰⁾_j ⊙ ω⁽²⁰¹⁾_{k−j} − γ⁽²⁰¹⁾_j ⊙ ω⁽¹²⁰⁾_{k−j}, whose minus part is summed
# as Σ ω⁽¹²⁰⁾_j ⊙ γ⁽²⁰¹⁾_{k−j} (j ↔ k − j).
W, G, W120, G120, W201, G201 = range(6)
ROWS = 6
_CYCLE = {W120: (1, 2, 0, 3), W201: (2, 0, 1, 3)}


@simd.series(ROWS)
def _coefficients(v, p, row):
    """Fill T[1..order] from T[0] (rows W, G and their permutations; T is (order+1, ROWS, LANES)).

    Q is (4, LANES): q = (I_y − I_z)/I_x (and cyclically), N_2 in every lane, and the torque U_2 × γ's
    constants qa = (U_y/I_x, U_z/I_y, U_x/I_z), qb = (U_z/I_x, U_x/I_y, U_y/I_z) (``_constants``); the
    fourth lane of each is 0. The rate is ``simd.Lanes.fixed_point_rate``. The
    cross product's sum runs in two accumulators (its plus and minus products), so that no chain of
    dependent fused multiply-adds is longer than one per term; the terms that involve the newest
    coefficient k come last (see the loop). Both orders differ from the scalar kernel's and the batch
    lanes': the coefficients agree with theirs to rounding.
    """
    b = v.builder
    q, n, qa, qb = [v.load(2, r) for r in range(4)]
    pairs_w, pairs_g, cross_plus, cross_minus = sums = v.variables(4)
    zero = ir.Constant(v.vec, [0.0] * LANES)

    def term(a, c):
        """The sums' term of the rows a (index j) and c (index k − j), each given as its ROWS vectors."""
        v.fma_into(pairs_w, a[W120], c[W201])
        v.fma_into(pairs_g, a[G120], c[G201])
        v.fma_into(cross_plus, a[G120], c[W201])
        v.fma_into(cross_minus, a[W120], c[G201])  # Σ_j γ⁽²⁰¹⁾_{k−j} ⊙ ω⁽¹²⁰⁾_j: four loads per term

    def load_row(index):
        return [v.load(0, row(index, c)) for c in range(ROWS)]

    first = load_row(ir.Constant(p.type, 0))
    newest = v.variables(ROWS)  # row k, carried in registers from one order to the next
    for c in range(ROWS):
        b.store(first[c], newest[c])
    one = ir.Constant(p.type, 1)
    with cgutils.for_range(b, p) as order_loop:
        k = order_loop.index
        for s in sums:
            b.store(zero, s)
        # the terms of rows 1..k−1 first, those of the newest row k (j = 0 and j = k) last: the former do
        # not wait for row k, so they overlap the computation of row k in the processor's pipeline
        with cgutils.for_range(b, k, start=one) as middle:
            term(load_row(middle.index), load_row(b.sub(k, middle.index)))
        last = [b.load(x) for x in newest]
        term(first, last)
        with b.if_then(b.icmp_signed(">", k, ir.Constant(k.type, 0))):
            term(last, first)
        inv = v.inverse(k)
        omega = v.fixed_point_rate(q, n, b.load(pairs_w), b.load(pairs_g), qa, last[G201], qb, last[G120], inv)
        gamma = b.fmul(b.fsub(b.load(cross_plus), b.load(cross_minus), flags=simd.FUSE), inv, flags=simd.FUSE)
        k1 = b.add(k, ir.Constant(k.type, 1))
        for base, value in ((W, omega), (G, gamma)):
            rows = {base: value}
            for shift, lanes in _CYCLE.items():
                mask = ir.Constant(ir.VectorType(ir.IntType(32), LANES), list(lanes))
                rows[base + shift] = b.shuffle_vector(value, value, mask)
            for c, x in rows.items():
                v.store(x, 0, row(k1, c))
                b.store(x, newest[c])


@intrinsic
def _dense(typingctx, T, order, dt, carry, out):
    """out[0], out[1] = the state rows T[0, W], T[0, G] + (Σ_{k≥1} T[k] dt^k − carry): the series at t + dt,
    Horner with strict arithmetic (``run_scalar``'s dense output, two components' chains at once)."""
    if not (simd.vector_arrays([T, carry, out]) and T.ndim == 3 and isinstance(order, types.Integer)
            and isinstance(dt, types.Float)):
        return None
    sig = types.void(T, order, types.float64, carry, out)

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args)
        b = builder
        p = context.cast(builder, args[1], signature.args[1], types.intp)
        h = v.splat(args[2])
        acc = v.variables(2)
        for c in (W, G):
            b.store(v.load(0, v.row(b, p, ROWS, c)), acc[c])
        with cgutils.for_range(b, b.sub(p, ir.Constant(p.type, 1))) as loop:
            k = b.sub(b.sub(p, ir.Constant(p.type, 1)), loop.index)  # order − 1 … 1
            for c in (W, G):
                b.store(b.fadd(b.fmul(b.load(acc[c]), h), v.load(0, v.row(b, k, ROWS, c))), acc[c])
        for c in (W, G):
            v.store(b.fadd(v.load(0, c), b.fsub(b.fmul(b.load(acc[c]), h), v.load(3, c))), 4, c)
        return context.get_dummy_value()

    return sig, codegen


#: The state rows T[0, W], T[0, G] += Σ_{k≥1} T[k] h^k, compensated (``simd.update``, the batch lanes' arithmetic).
_update = simd.update(ROWS, 2)


@kernel
def _constants(p, Q):
    """``_coefficients``' constants from the parameters (``fixed_point.pack``), in the order the batch lanes read them."""
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    u0, u1, u2 = p[U_Z], p[U_Z + 1], p[U_Z + 2]
    Q[0, 0], Q[0, 1], Q[0, 2] = (I1 - I2) * p[INV_INERTIA], (I2 - I0) * p[INV_INERTIA + 1], (I0 - I1) * p[INV_INERTIA + 2]
    Q[1, 0] = Q[1, 1] = Q[1, 2] = p[N_Z]
    Q[2, 0], Q[2, 1], Q[2, 2] = u1 * p[INV_INERTIA], u2 * p[INV_INERTIA + 1], u0 * p[INV_INERTIA + 2]
    Q[3, 0], Q[3, 1], Q[3, 2] = u2 * p[INV_INERTIA], u0 * p[INV_INERTIA + 1], u1 * p[INV_INERTIA + 2]


@kernel
def _set_state(T, y):
    """T[0]'s rows (W, G and their permutations) from the state y = (ω, γ)."""
    for m in range(3):
        for base in (W, G):
            T[0, base, m] = y[3 * base + m]
            T[0, base + W120, m] = y[3 * base + (m + 1) % 3]
            T[0, base + W201, m] = y[3 * base + (m + 2) % 3]


@kernel
def _norm_rows(T, k):
    """The max norm of order k's coefficient (rows W and G, lanes 0..2)."""
    v = 0.0
    for base in (W, G):
        for m in range(3):
            v = max(v, abs(T[k, base, m]))
    return v


@kernel
def series(p, y, order):
    """The Taylor coefficients (order+1, 6) of the fixed-point state y without α from the vectorised sums."""
    T = np.zeros((order + 1, ROWS, LANES))
    Q = np.zeros((4, LANES))
    _constants(p, Q)
    _set_state(T, y)
    _coefficients(T, order, Q)
    out = np.empty((order + 1, 6))
    for k in range(order + 1):
        for m in range(3):
            out[k, m] = T[k, W, m]
            out[k, 3 + m] = T[k, G, m]
    return out


@kernel
def run_vector(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    """``run`` for the fixed-point model (y = (ω, γ)), the step vectorised across the
    components: ``_coefficients``, the dense output (``_dense``) and the compensated update (``_update``) in
    ``<4 x double>``. Same order, step rule, dense output (strict arithmetic), compensated update, status
    codes, stats and chunking contract as ``run_scalar``; the coefficients and the update's Horner sums fuse
    multiply and add (as the batch lanes do), so the results agree with ``run_scalar``'s to rounding."""
    T = np.zeros((order + 1, ROWS, LANES))
    Q = np.zeros((4, LANES))
    C = np.zeros((2, LANES))  # the Kahan compensation, rows W and G
    H = np.zeros((1, LANES))
    D = np.zeros((2, LANES))  # a dense output, rows W and G
    _constants(p, Q)
    for m in range(3):
        C[0, m], C[1, m] = carry[m], carry[3 + m]
    t = state[0]
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    i = i_next
    safety = math.exp(-0.7 / (order - 1))
    code = OK
    while i < i_stop:
        _set_state(T, y)
        _coefficients(T, order, Q)
        stats[0] += 1
        scale = max(1.0, _norm_rows(T, 0))
        h = step_size(tol, scale, _norm_rows(T, order - 1), _norm_rows(T, order), order, safety)
        if not h < np.inf:
            h = t_end - t
        t_new = min(t + h, t_end)
        h = t_new - t
        if h <= 0.0:  # the step is below the spacing of floating-point numbers at t: no progress is possible
            code = TOO_SMALL_STEP
            break
        while i < n_out and t_out[i] <= t_new:
            _dense(T, order, t_out[i] - t, C, D)
            for m in range(3):
                Y[i, m], Y[i, 3 + m] = D[0, m], D[1, m]
            i += 1
        for m in range(3):
            H[0, m] = h
        _update(T, order, H, C)
        finite = True
        for m in range(3):
            y[m], y[3 + m] = T[0, W, m], T[0, G, m]
            carry[m], carry[3 + m] = C[0, m], C[1, m]
            finite = finite and math.isfinite(y[m]) and math.isfinite(y[3 + m])
        if not finite:
            code = NOT_FINITE
            break
        t = t_new
        stats[1] += 1
    state[0] = t
    return code, i
