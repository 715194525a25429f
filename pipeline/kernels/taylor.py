"""Taylor series method of high order with automatic step size (Jorba & Zou, Exp. Math. 14, 2005).

The coefficients come from the model's generated series (``taylor_series``, one kernel per form of the equations),
so every model takes the same step code. The order follows from the tolerance (``order_for``: Jorba and Zou's
p = ⌈−ln(tol)/2 + 1⌉ minimises the series' work per unit time; counting a step's other work too, the cheapest order
is a few higher) and the step from the last two coefficients, h = min_k (tol·max(1, ‖y‖)/‖y_k‖)^(1/k) for
k = p−1, p, times Jorba and Zou's safety factor exp(−0.7/(p−1)). The series is the dense output: every output time
inside a step is one Horner evaluation, no extra step.

The state update y ← y + Σ_{k≥1} y_k h^k is a compensated (Kahan) sum: the low bits lost when a small increment is
added to an O(1) state are carried to the next step, so round-off does not grow as one ulp of the state per step
(docs/performance.md, "The Taylor integrator"). Time needs no compensation: the step actually taken is
h = fl(t + h) − t, exact in floating point, and the state advances by exactly it.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels import simd
from gyrolab.kernels.simd import array_data as _data
from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.double_double import dd_add, dd_mul_d
from gyrolab.kernels.models import taylor_coefficients

OK, TOO_SMALL_STEP, NOT_FINITE = 0, 1, 2  # dop853's codes
MIN_ORDER, MAX_ORDER = 4, 60


#: a double step's work besides its series (step size, Kahan update, dense output, the loop), in units of the
#: series' work per order²: the series costs ~p², the rest ~STEP_OVERHEAD (measured: docs/performance.md, "The order
#: rule"). Double-double steps are series-bound: 0 there.
STEP_OVERHEAD = 64.0


def order_for(tol: float, overhead: float = STEP_OVERHEAD) -> int:
    """The order of least work per unit time at ``tol``, within [MIN_ORDER, MAX_ORDER]: a step of order p costs
    ~(overhead + p²) and spans ~tol^(1/p), so the work per unit time (overhead + p²)·e^(L/p), L = −ln tol, is least
    at the root of 2p³ = L (p² + overhead) (with no overhead p = L/2), rounded up as Jorba & Zou's ⌈L/2 + 1⌉."""
    L = -math.log(tol)
    if not L > 0.0:  # (tol ≥ 1: no accuracy asked)
        return MIN_ORDER
    p = L / 2.0 + (L * overhead / 2.0) ** (1.0 / 3.0)  # above the root: Newton descends to it monotonically
    for _ in range(50):
        step = (2.0 * p ** 3 - L * (p * p + overhead)) / (6.0 * p * p - 2.0 * L * p)
        p -= step
        if abs(step) < 1e-9:
            break
    return int(min(MAX_ORDER, max(MIN_ORDER, math.ceil(p + 1.0))))


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


@inline_kernel
def _norm_row(T, k):
    """The max norm of row k of T (no view of the row: a slice's reference counting costs more than the loop)."""
    v = 0.0
    for m in range(T.shape[1]):
        v = max(v, abs(T[k, m]))
    return v


@kernel
def run(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats, head=0):
    """Advance until t_out[i_stop − 1] is filled.

    Steps are clipped at the run's last output time only, never at i_stop: where a call stops must not
    change the steps (the caller sizes calls by wall time, for progress), so every output the last
    step passes is filled, also beyond i_stop. state = [t]; carry = the Kahan compensation of y (zeros
    at the start); stats = [coefficient evaluations, steps]. ``head`` > 0: the series' first ``head`` orders and
    the update in double-double (``_steps``). Returns (status, index of the next output time to fill).
    """
    return _steps(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats, np.empty(0), np.empty(0),
                  np.empty((0, y.size)), np.empty(0), np.empty(0), 0, head)


#: the one-pass error estimate (``run_measured``): the series' orders beyond the step's, whose terms are the step's
#: truncation error with its sign; the order of the tangent series that carries the error so far along the step (the
#: highest of the tangent vector's); the relative error a step the tangent vector's series may have (which sets its
#: order). gyrolab.accuracy.calibration's table holds the same values with the measurements behind them
#: (benchmarks/one_pass_estimate.py checks them)
EXTRA_ORDERS, TANGENT_ORDER, GROWTH_PER_STEP = 4, 10, 1e-5
#: the finite difference's step along the error's direction, relative to the state's scale: ~√eps, so that its
#: truncation and its round-off both leave the tangent series ~1e-8 relative error (the estimate needs one digit)
DIFFERENCE_STEP = 2.0 ** -26


@inline_kernel
def tangent_order(order, tol):
    """The order of the tangent vector's series in the one pass, shorter than the step's: the lowest order m whose
    first neglected term, ~(m + 1)·step^(m + 1) of the vector (a derivative brings down a factor ~k at order k: the
    tangent series' terms fall slower than the state's), is below GROWTH_PER_STEP, at a step spanning
    ~tol^(1/order)·safety of the series' radius of convergence; at most TANGENT_ORDER. Without the factor a fast top's
    growth came out e^8.23 at tol 1e-10 where the orders of 10 measure e^8.67 (r0 = 15 over t = 185, audit seed 5,
    scene 93); with it e^8.56. The error's series stays at TANGENT_ORDER: at this order (6 to 9) the same top's
    estimate drifted to 0.6× at tol 1e-10 and 2.0× at 2.9e-12 (0.99–1.05× at 10)."""
    m = min(TANGENT_ORDER, order)
    if tol < 1.0:
        step = tol ** (1.0 / order) * math.exp(-0.7 / (order - 1))
        k = MIN_ORDER
        while k < m and (k + 1) * step ** (k + 1) > GROWTH_PER_STEP:
            k += 1
        m = k
    return m


@kernel
def run_measured(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats, e, u, E, growth, G, flow, head=0):
    """``run``, its global error estimated and its perturbations' growth measured in the same pass (docs/integrators.md,
    "A one-pass error estimate"). e, the error of y (exact − computed; zeros at the start), is carried along each step
    by the linearised equation e' = J(y(t)) e, whose Taylor series (to ``tangent_order``) is the directional
    difference of the model's series at y + δ e/|e| and at y (``_tangent_series``), and each step adds its truncation
    error, the series' next ``EXTRA_ORDERS`` terms: E[i] = the estimated error at output time i. u, a unit tangent
    vector, is carried the same way and renormalised at each step: growth = [ln|δ| of the tangent vector it stands
    for (the fast Lyapunov indicator's quantity), its running maximum, a time t_mark, that maximum at t_mark (the
    last step ending there or before), with a double-double ``head`` Σ over the steps of the max norm of their terms
    computed in double (their round-off's bound in units of u: it adds up coherently, the model's numbers derived in
    double, 1/I, erring the same way at every step)], G[i] = the maximum at output time i. (The error's own growth is
    no such measure: each step's truncation error turns it, and on a regular motion the sum of its growths over the
    steps climbs where a tangent vector's oscillates.) The tangent vector follows the first ``flow`` components
    (``tangent.flow_size``: the fixed point's (ω, γ), not the fixed axis α that no torque reads), zeros beyond, as
    the chaos measure's tangent run does: α, carried, grows like the integral of δω and raised the default scene's
    growth after the pilot from e^2.12 to e^2.35, past what ``auto`` keeps without a tangent run (with
    ``integrator=auto``: ~4 ms instead of ~2). With E of no rows (and e empty) the growth alone is measured (``auto``
    without an error estimate): the error's series and the extra orders are ~half the pass."""
    return _steps(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats, e, u, E, growth, G, flow, head)


@inline_kernel
def _steps(p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats, e, u, E, growth, G, flow, head):
    """``run`` and ``run_measured``: the growth measured when u has components, the error estimated when E has rows
    too. ``head`` > 0, a double-double head: the series' first ``head`` orders from the model's generated
    double-double series (``series_dd``, its address in ``p``) at the state y − carry taken as a double-double, and
    the update y − carry ← y − carry + Σ_{k≥1} T_k h^k in double-double, the terms beyond the head in double. A
    step's round-off is then that of those terms, ~u·|T_(head+1)·h^(head+1)|, instead of ~u·|T_1·h|: a step's terms
    fall by ~tol^(1/order) each order (at tol 1e-18 and head 4, ~2,000× less round-off), and the model's numbers
    derived in double (1/I) reach only those terms (docs/integrators.md, "A companion with a double-double head")."""
    n = y.size
    Th, Tl, tail = np.zeros((head + 1, n)), np.zeros((head + 1, n)), np.empty(n if head > 0 else 0)
    S = np.zeros((head + 1) * 2 * int(p[p.size - 1]) if head > 0 else 0)
    address = int(p[p.size - 2]) if head > 0 else 0
    if head > 0 and address == 0:  # the series was not compiled (``series_dd.ready`` not called): no step, not a crash
        return NOT_FINITE, i_next
    measured, estimating = u.size > 0, E.shape[0] > 0
    extra = EXTRA_ORDERS if estimating else 0
    T = _coefficient_rows(order + 1 + extra, n)
    safety = math.exp(-0.7 / (order - 1))
    m = tangent_order(order, tol)
    m_error = min(TANGENT_ORDER, order)  # (shorter, a fast top's error drifted: ``tangent_order``)
    # the error's series: rows 0 … m_error the carried error's (the tangent series), rows order + 1 … the step's
    # truncation error (T's), zeros between: one Horner sum gives both (``_series_at``)
    R = _coefficient_rows(order + 1 + extra if estimating else 0, n)
    R[:, :] = 0.0
    U = _coefficient_rows(m + 1 if measured else 0, n)
    end = np.empty((2, n))  # the whole error and the tangent vector at a step's end
    t = state[0]
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    i = i_next
    while i < i_stop:
        for k in range(n):
            T[0, k] = y[k]
        taylor_coefficients(p, T, order + extra, t)
        if head > 0:
            for k in range(n):
                Th[0, k], Tl[0, k] = y[k], -carry[k]
            _call_dd_series(address, t, head, Th, Tl, S, p)
            for j in range(1, head + 1):
                for k in range(n):
                    T[j, k] = Th[j, k]
        stats[0] += 1
        scale = max(1.0, _norm_row(T, 0))
        h = step_size(tol, scale, _norm_row(T, order - 1), _norm_row(T, order), order, safety)
        if not h < np.inf:
            h = t_end - t
        t_new = min(t + h, t_end)
        h = t_new - t
        if h <= 0.0:  # the step is below the spacing of floating-point numbers at t: no progress is possible
            state[0] = t
            return TOO_SMALL_STEP, i
        first = i
        while i + 1 < n_out and t_out[i + 1] <= t_new:  # outputs by pairs: two Horner chains in the time of one
            _dense_output(T, order, (t_out[i] - t, t_out[i + 1] - t), y, carry, Y, i)
            i += 2
        if i < n_out and t_out[i] <= t_new:
            _dense_output(T, order, (t_out[i] - t,), y, carry, Y, i)
            i += 1
        if estimating:
            _tangent_series(p, T, R, m_error, e, scale, t)
            for k in range(n):
                for j in range(order + 1, order + 1 + extra):
                    R[j, k] = T[j, k]
            j = first
            while j + 1 < i:
                _series_at(R, order + extra, (t_out[j] - t, t_out[j + 1] - t), E, j)
                j += 2
            if j < i:
                _series_at(R, order + extra, (t_out[j] - t,), E, j)
            _series_at(R, order + extra, (h,), end, 0)
            for k in range(n):
                e[k] = end[0, k]
        if measured:
            _tangent_series(p, T, U, m, u, scale, t)
            for j in range(first, i):
                G[j] = growth[1]
            _series_at(U, m, (h,), end, 1)
            size = 0.0
            for k in range(flow):
                size += end[1, k] * end[1, k]
            size = math.sqrt(size)
            if size > 0.0 and size < np.inf:  # (a tangent vector that vanished or overflowed: its last direction)
                for k in range(flow):
                    u[k] = end[1, k] / size
                growth[0] += math.log(size)
                growth[1] = max(growth[1], growth[0])
            if t_new <= growth[2]:
                growth[3] = growth[1]
        if head == 0:
            finite = _advance(T, order, h, y, carry)
        else:
            finite, doubled = _advance_head(T, Th, Tl, order, head, h, y, carry, tail)
            if measured:  # the round-off's bound: Σ |the step's terms computed in double| (``growth``)
                growth[4] += doubled
        if not finite:
            state[0] = t
            return NOT_FINITE, i
        t = t_new
        stats[1] += 1
    state[0] = t
    return OK, i


@inline_kernel
def _advance_head(T, Th, Tl, order, head, h, y, carry, tail):
    """``_advance`` with a double-double head (``_steps``): Σ_{k>head} T_k h^k in double (in ``tail``: rows outside,
    components inside, the components' Horner chains side by side), then the head's orders and the state y − carry
    in double-double; y the new state's high part, carry minus its low part. Returns (whether every new component is
    finite, the max norm of the terms computed in double: the step's round-off is a few ulps of it)."""
    n = y.size
    for m in range(n):
        tail[m] = T[order, m]
    for k in range(order - 1, head, -1):
        for m in range(n):
            tail[m] = tail[m] * h + T[k, m]
    finite, doubled, power = True, 0.0, abs(h) ** (head + 1)
    for m in range(n):
        doubled = max(doubled, abs(tail[m]) * power)
        vh, vl = tail[m], 0.0
        for k in range(head, -1, -1):
            vh, vl = dd_mul_d(vh, vl, h)
            vh, vl = dd_add(vh, vl, Th[k, m], Tl[k, m])
        y[m], carry[m] = vh, -vl
        finite = finite and math.isfinite(vh) and math.isfinite(vl)
    return finite, doubled


@intrinsic
def _call_dd_series(typingctx, address, t, order, Th, Tl, S, p):
    """Call ``void f(double t, int64 order, double* Th, double* Tl, double* S, double* p)`` at ``address``: a traced
    model's generated double-double series (``series_dd``)."""
    return types.void(types.int64, types.float64, types.int64, Th, Tl, S, p), simd.call_address


@inline_kernel
def _tangent_series(p, T, D, m, v, scale, t):
    """D[0..m] = the Taylor series of the vector v carried along the step by the linearised equations (T: the state's
    series): (series at y + δ v/|v| − series at y)·|v|/δ, δ = DIFFERENCE_STEP·scale; zero for v = 0."""
    n = v.size
    size = 0.0
    for k in range(n):
        size = max(size, abs(v[k]))
    if size == 0.0:
        for j in range(m + 1):
            for k in range(n):
                D[j, k] = 0.0
        return
    delta = DIFFERENCE_STEP * scale
    forward, back = delta / size, size / delta
    for k in range(n):
        D[0, k] = T[0, k] + v[k] * forward
    taylor_coefficients(p, D, m, t)
    for k in range(n):
        D[0, k] = v[k]
    for j in range(1, m + 1):
        for k in range(n):
            D[j, k] = (D[j, k] - T[j, k]) * back


#: lanes of the Horner sums' vectors (AVX-512's; an AVX2 CPU runs each as two, a CPU without vectors as scalars)
_LANES = 8
#: doubles readable past the last row of the coefficients (``_coefficient_rows``): the Horner sums load whole vectors
_PAST_END = 2 * _LANES


@inline_kernel
def _coefficient_rows(rows, n):
    """An uninitialised rows × n array followed by _PAST_END zeros, read by ``_emit_horner``'s vector loads: lanes
    computed and dropped, but left uninitialised a subnormal number there made every output ~4x slower in some
    processes (each multiply-add on it a microcode assist)."""
    buffer = np.empty(rows * n + _PAST_END)
    buffer[rows * n:] = 0.0
    return buffer[:rows * n].reshape((rows, n))


def _emit_horner(context, b, T, T_type, order, hs, each):
    """Emit v_j = Σ_{k=1..order} T[k] h_j^(k−1) for every component and every h_j of ``hs``, then ``each(j, c, v)``
    once per vector v of components c … c + 7 (lanes past the state's end are junk: ``_lanes_in``).

    A Horner chain is bound by the latency of its multiply-adds, so each sum runs as two chains side by side, the low
    rows 1 … K and the high rows K + 1 … order (K = ⌈order/2⌉), joined as low + high·h^K, h^K multiplied up beside
    them: half the latency of one chain (reference scene, tol 6.5e-13, order 16: the bare run 4 % faster, the
    measured one 3 %). Two h_j (two output times) run side by side too. Eight components a ``<8 x double>`` register;
    T must come from ``_coefficient_rows`` (the vectors load whole, past a row's end)."""
    i64, double = ir.IntType(64), ir.DoubleType()
    vec = ir.VectorType(double, _LANES)
    array = context.make_array(T_type)(context, b, T)
    rows = b.bitcast(array.data, double.as_pointer())
    n = b.extract_value(array.shape, 1)
    fma = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec] * 3), f"llvm.fma.v{_LANES}f64")
    hvs = [simd.splat(b, h, _LANES) for h in hs]
    one = ir.Constant(i64, 1)
    low_rows = b.sdiv(b.add(order, one), ir.Constant(i64, 2))  # K
    has_high = b.icmp_signed(">", order, low_rows)  # (order 1: no high rows)
    chunks = b.udiv(b.add(n, ir.Constant(i64, _LANES - 1)), ir.Constant(i64, _LANES))
    with cgutils.for_range(b, chunks) as chunk:
        column = b.mul(chunk.index, ir.Constant(i64, _LANES))

        def row(k):
            return b.load(b.bitcast(b.gep(rows, [b.add(b.mul(k, n), column)]), vec.as_pointer()), align=8)

        top = b.select(has_high, row(order), ir.Constant(vec, [0.0] * _LANES))
        chains = [(cgutils.alloca_once_value(b, row(low_rows)), cgutils.alloca_once_value(b, top),
                   cgutils.alloca_once_value(b, hv)) for hv in hvs]  # (low, high, h^(1 + iterations))
        with cgutils.for_range(b, b.sub(low_rows, one)) as loop:
            k = b.add(loop.index, one)
            x_low, high_row = row(b.sub(low_rows, k)), b.sub(order, k)
            in_high = b.icmp_signed(">", high_row, low_rows)
            x_high = row(b.select(in_high, high_row, low_rows))  # (a row in range, its product dropped below)
            for hv, (low, high, power) in zip(hvs, chains):
                b.store(b.call(fma, [b.load(low), hv, x_low]), low)
                h_old = b.load(high)
                b.store(b.select(in_high, b.call(fma, [h_old, hv, x_high]), h_old), high)
                b.store(b.fmul(b.load(power), hv), power)
        for j, (low, high, power) in enumerate(chains):  # (column < n: chunks of eight components, rounded up)
            each(j, column, b.call(fma, [b.load(high), b.load(power), b.load(low)]))


_LANE_INDEX = ir.Constant(ir.VectorType(ir.IntType(64), _LANES), list(range(_LANES)))


def _masked_load(b, pointer, mask):
    """The 8 doubles from ``pointer`` where ``mask`` is set, 0 elsewhere (nothing read there)."""
    vec = ir.VectorType(ir.DoubleType(), _LANES)
    load = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec.as_pointer(), ir.IntType(32),
                                                                          mask.type, vec]),
                                          f"llvm.masked.load.v{_LANES}f64.p0")
    return b.call(load, [b.bitcast(pointer, vec.as_pointer()), ir.Constant(ir.IntType(32), 8), mask,
                         ir.Constant(vec, [0.0] * _LANES)])


def _masked_store(b, value, pointer, mask):
    """Store the lanes of ``value`` where ``mask`` is set at ``pointer`` (nothing written elsewhere)."""
    vec = value.type
    store = cgutils.get_or_insert_function(b.module, ir.FunctionType(ir.VoidType(), [vec, vec.as_pointer(),
                                                                                     ir.IntType(32), mask.type]),
                                           f"llvm.masked.store.v{_LANES}f64.p0")
    b.call(store, [value, b.bitcast(pointer, vec.as_pointer()), ir.Constant(ir.IntType(32), 8), mask])


def _lanes_in(b, c, n):
    """The mask of the lanes c … c + 7 that are components (below n)."""
    return b.icmp_unsigned("<", b.add(simd.splat(b, c, _LANES), _LANE_INDEX), simd.splat(b, n, _LANES))


@intrinsic
def _dense_output(typingctx, T, order, dts, y, carry, Y, i):
    """Y[i + j] = y + (v_j·dt_j − carry), v_j = Σ_{k≥1} T[k] dt_j^(k−1) (``_emit_horner``), for each dt_j of the tuple
    ``dts`` (one or two): the state dt_j after the step's start from its series, with the compensation the state
    carries."""
    if not (simd.vector_arrays([T, y, carry, Y]) and isinstance(dts, types.UniTuple)):
        return None
    sig = types.void(T, order, dts, y, carry, Y, i)

    def codegen(context, b, signature, args):
        T_, order_, dts_, y_, carry_, Y_, i_ = args
        types_ = signature.args
        i_ = context.cast(b, i_, types_[6], types.intp)
        hs = [b.extract_value(dts_, j) for j in range(types_[2].count)]

        def each(j, c, v):  # y_m + (v_m·dt − c_m) on 8 components at once: masked loads and stores
            mask = _lanes_in(b, c, n)
            y_v, c_v = (_masked_load(b, b.gep(_data(context, b, types_[a], args[a]), [c]), mask) for a in (3, 4))
            row = b.gep(_data(context, b, types_[5], Y_), [b.add(b.mul(b.add(i_, ir.Constant(i_.type, j)), width), c)])
            _masked_store(b, b.fadd(y_v, b.fsub(b.fmul(v, simd.splat(b, hs[j], _LANES)), c_v)), row, mask)

        n = b.extract_value(context.make_array(types_[3])(context, b, y_).shape, 0)
        width = b.extract_value(context.make_array(types_[5])(context, b, Y_).shape, 1)  # Y's row length (≥ n)
        _emit_horner(context, b, T_, types_[0], context.cast(b, order_, types_[1], types.int64), hs, each)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _series_at(typingctx, R, rows, dts, out, i):
    """out[i + j] = R[0] + v_j·dt_j, v_j = Σ_{k=1..rows} R[k] dt_j^(k−1) (``_emit_horner``), for each dt_j of the tuple
    ``dts`` (one or two): a series at dt_j, all components in one vector chain (one component's chain after another's
    took ~80 ns an output time, bound by the multiply-adds' latency)."""
    if not (simd.vector_arrays([R, out]) and isinstance(dts, types.UniTuple)):
        return None
    sig = types.void(R, rows, dts, out, i)

    def codegen(context, b, signature, args):
        R_, rows_, dts_, out_, i_ = args
        types_ = signature.args
        i_ = context.cast(b, i_, types_[4], types.intp)
        hs = [b.extract_value(dts_, j) for j in range(types_[2].count)]
        R_data = _data(context, b, types_[0], R_)

        def each(j, c, v):
            mask = _lanes_in(b, c, n)
            row = b.gep(_data(context, b, types_[3], out_), [b.add(b.mul(b.add(i_, ir.Constant(i_.type, j)), n), c)])
            start = _masked_load(b, b.gep(R_data, [c]), mask)
            _masked_store(b, b.call(fma, [v, simd.splat(b, hs[j], _LANES), start]), row, mask)

        n = b.extract_value(context.make_array(types_[0])(context, b, R_).shape, 1)
        vec = ir.VectorType(ir.DoubleType(), _LANES)
        fma = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec] * 3), f"llvm.fma.v{_LANES}f64")
        _emit_horner(context, b, R_, types_[0], context.cast(b, rows_, types_[1], types.int64), hs, each)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _advance(typingctx, T, order, h, y, carry):
    """y ← y + v·h as a compensated (Kahan) sum, v = Σ_{k≥1} T[k] h^(k−1) (``_emit_horner``): the bits lost in the
    additions carried in ``carry``. Returns whether every new component is finite."""
    if not simd.vector_arrays([T, y, carry]):
        return None
    sig = types.boolean(T, order, types.float64, y, carry)

    def codegen(context, b, signature, args):
        T_, order_, h_, y_, carry_ = args
        types_ = signature.args
        n = b.extract_value(context.make_array(types_[3])(context, b, y_).shape, 0)
        finite = cgutils.alloca_once_value(b, cgutils.true_bit)
        vec = ir.VectorType(ir.DoubleType(), _LANES)
        fabs = cgutils.get_or_insert_function(b.module, ir.FunctionType(vec, [vec]), f"llvm.fabs.v{_LANES}f64")
        every = cgutils.get_or_insert_function(b.module, ir.FunctionType(ir.IntType(1), [ir.VectorType(
            ir.IntType(1), _LANES)]), f"llvm.vector.reduce.and.v{_LANES}i1")

        def each(_, c, v):  # the Kahan update of 8 components at once: masked loads and stores
            mask = _lanes_in(b, c, n)
            y_at, c_at = (b.gep(_data(context, b, types_[a], args[a]), [c]) for a in (3, 4))
            y_v = _masked_load(b, y_at, mask)
            inc = b.fsub(b.fmul(v, simd.splat(b, h_, _LANES)), _masked_load(b, c_at, mask))
            total = b.fadd(y_v, inc)
            _masked_store(b, b.fsub(b.fsub(total, y_v), inc), c_at, mask)
            _masked_store(b, total, y_at, mask)
            # finite: |total| < inf (false for NaN and ±inf), in every lane that is a component
            bounded = b.fcmp_ordered("<", b.call(fabs, [total]), ir.Constant(vec, [math.inf] * _LANES))
            b.store(b.and_(b.load(finite), b.call(every, [b.or_(bounded, b.not_(mask))])), finite)

        _emit_horner(context, b, T_, types_[0], context.cast(b, order_, types_[1], types.int64), [h_], each)
        return b.load(finite)

    return sig, codegen
