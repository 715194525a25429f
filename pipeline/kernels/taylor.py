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

The coefficients come from the model's generated series (``taylor_series``: one kernel per form of the
equations, the fixed point's included), so every model takes the same step code.
"""

from __future__ import annotations

import math

import numpy as np


from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.double_double import fma
from gyrolab.kernels.models import taylor_coefficients

OK, TOO_SMALL_STEP, NOT_FINITE = 0, 1, 2  # dop853's codes
MIN_ORDER, MAX_ORDER = 4, 60


def order_for(tol: float) -> int:
    """Jorba & Zou's optimal order for a tolerance: ⌈−ln(tol)/2 + 1⌉, within [MIN_ORDER, MAX_ORDER]."""
    return int(min(MAX_ORDER, max(MIN_ORDER, math.ceil(-math.log(tol) / 2.0 + 1.0))))


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
def run(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, carry, stats):
    """Advance until t_out[i_stop − 1] is filled.

    Steps are clipped at the run's last output time only, never at i_stop: where a call stops must not
    change the steps (the caller sizes calls by wall time, for progress), so every output the last
    step passes is filled, also beyond i_stop. state = [t]; carry = the Kahan compensation of y (zeros
    at the start); stats = [coefficient evaluations, steps]. Returns (status, index of the next output
    time to fill). ``model`` is a ``models.Form`` or an int (``models.taylor_coefficients``).
    """
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
        scale = max(1.0, _norm_row(T, 0))
        h = step_size(tol, scale, _norm_row(T, order - 1), _norm_row(T, order), order, safety)
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


@inline_kernel
def _horner(T, order, h, v):
    """v = Σ_{k=1..order} T[k] h^(k−1) for every component (Horner, each step one fused multiply-add: the update
    is on the chain of dependent operations from one step to the next, and a fused step takes half the latency of
    a multiply then an add). Six components' chains run side by side in registers (then three, then one), not one
    component after another, and each component takes the same operations, so the same results to the bit."""
    n = v.size
    m = 0
    while m + 6 <= n:
        a0, a1, a2 = T[order, m], T[order, m + 1], T[order, m + 2]
        a3, a4, a5 = T[order, m + 3], T[order, m + 4], T[order, m + 5]
        for k in range(order - 1, 0, -1):
            a0 = fma(a0, h, T[k, m])
            a1 = fma(a1, h, T[k, m + 1])
            a2 = fma(a2, h, T[k, m + 2])
            a3 = fma(a3, h, T[k, m + 3])
            a4 = fma(a4, h, T[k, m + 4])
            a5 = fma(a5, h, T[k, m + 5])
        v[m], v[m + 1], v[m + 2], v[m + 3], v[m + 4], v[m + 5] = a0, a1, a2, a3, a4, a5
        m += 6
    while m + 3 <= n:
        a0, a1, a2 = T[order, m], T[order, m + 1], T[order, m + 2]
        for k in range(order - 1, 0, -1):
            a0 = fma(a0, h, T[k, m])
            a1 = fma(a1, h, T[k, m + 1])
            a2 = fma(a2, h, T[k, m + 2])
        v[m], v[m + 1], v[m + 2] = a0, a1, a2
        m += 3
    for c in range(m, n):
        a = T[order, c]
        for k in range(order - 1, 0, -1):
            a = fma(a, h, T[k, c])
        v[c] = a
