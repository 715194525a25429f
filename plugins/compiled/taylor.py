"""Taylor series method of high order with automatic step size (Jorba & Zou, Exp. Math. 14, 2005).

The right-hand sides are quadratic, so the Taylor coefficients come from
Cauchy products (``models.taylor_coefficients``). The step is chosen from
the last two coefficients so that the first neglected term is about ``tol``
relative to the state; the series itself is the dense output.
"""

from __future__ import annotations

import numpy as np

from gyrolab.plugins.compiled import kernel
from gyrolab.plugins.compiled.models import taylor_coefficients

OK, NOT_FINITE = 0, 2


@kernel
def _norm_inf(row):
    v = 0.0
    for x in row:
        v = max(v, abs(x))
    return v


@kernel
def run(model, p, order, tol, t_out, Y, i_next, i_stop, state, y, stats):
    """Advance until t_out[i_stop − 1] is filled. state = [t]; stats = [coefficient evaluations, steps]."""
    n = y.size
    T = np.empty((order + 1, n))
    work = np.zeros((order + 1, 3))
    t = state[0]
    t_end = t_out[i_stop - 1]
    i = i_next
    while i < i_stop:
        T[0] = y
        taylor_coefficients(model, p, T, order, work)
        stats[0] += 1
        scale = max(1.0, _norm_inf(y))
        n1 = _norm_inf(T[order - 1])
        n2 = _norm_inf(T[order])
        h = np.inf
        if n1 > 0:
            h = min(h, (tol * scale / n1) ** (1.0 / (order - 1)))
        if n2 > 0:
            h = min(h, (tol * scale / n2) ** (1.0 / order))
        h *= 0.9
        if not h < np.inf:
            h = t_end - t
        t_new = min(t + h, t_end)
        h = t_new - t
        while i < i_stop and t_out[i] <= t_new:
            dt = t_out[i] - t
            for m in range(n):
                v = T[order, m]
                for k in range(order - 1, -1, -1):
                    v = v * dt + T[k, m]
                Y[i, m] = v
            i += 1
        for m in range(n):
            v = T[order, m]
            for k in range(order - 1, -1, -1):
                v = v * h + T[k, m]
            y[m] = v
            if not np.isfinite(v):
                state[0] = t
                return NOT_FINITE, i
        t = t_new
        stats[1] += 1
    state[0] = t
    return OK, i
