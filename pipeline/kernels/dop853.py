"""DOP853 (Hairer, Nørsett & Wanner, Solving ODEs I, §II.10) compiled, with scipy's exact controller.

The step-size control, initial step, error norm and 7th-order dense output
replicate ``scipy.integrate.DOP853`` (same coefficients, same formulas, same
order of operations where it matters), so at equal settings both take the
same steps and agree to rounding. The run is resumable: the integrator
state (t, y, f, |h|) lives in arrays the caller keeps between chunks.
"""

from __future__ import annotations

import math

import numpy as np

from gyrolab.kernels import dop853_tableau as _c
from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.models import evaluate, rhs

N_STAGES = _c.N_STAGES  # 12
N_EXTENDED = _c.N_STAGES_EXTENDED  # 16
A = np.ascontiguousarray(_c.A[:N_EXTENDED, :N_EXTENDED])
B = np.ascontiguousarray(_c.B)
C = np.ascontiguousarray(_c.C[:N_EXTENDED])
E3 = np.ascontiguousarray(_c.E3)
E5 = np.ascontiguousarray(_c.E5)
D = np.ascontiguousarray(_c.D)
SAFETY, MIN_FACTOR, MAX_FACTOR = 0.9, 0.2, 10.0
ERROR_EXPONENT = -1.0 / 8.0  # error estimator of order 7

OK, TOO_SMALL_STEP, NOT_FINITE = 0, 1, 2


@kernel
def _rms(x, x0, y, atol, rtol):
    """RMS norm of (x − x0) / (atol + |y| rtol), summed in order (as numpy's sum in numba)."""
    acc = 0.0
    for m in range(x.size):
        v = (x[m] - x0[m]) / (atol + abs(y[m]) * rtol)
        acc += v * v
    return math.sqrt(acc / x.size)


@kernel
def initial_step(p, t0, y0, f0, t_bound, max_step, rtol, atol, stats):
    """scipy.integrate._ivp.common.select_initial_step for order 7.

    Scalar loops instead of numpy's array expressions, which numba compiles as separate kernels
    (the bulk of the first compile); the same operations in the same order.
    """
    n = y0.size
    zero = np.zeros(n)
    interval = abs(t_bound - t0)
    d0 = _rms(y0, zero, y0, atol, rtol)
    d1 = _rms(f0, zero, y0, atol, rtol)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = np.empty(n)
    for m in range(n):
        y1[m] = y0[m] + h0 * f0[m]
    f1 = np.empty(n)
    evaluate(t0 + h0, y1, p, f1)
    stats[0] += 1
    d2 = _rms(f1, f0, y0, atol, rtol) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 8.0)
    return min(100 * h0, h1, interval, max_step)


@kernel
def _stage_sum(K, s, a_row, n, out):
    for i in range(n):
        acc = 0.0
        for j in range(s):
            acc += K[j, i] * a_row[j]
        out[i] = acc


@inline_kernel
def step_error(K, y, y_new, h_abs, rtol, atol):
    """scipy's error norm of the step from y to y_new (K: its stages, rows 0..N_STAGES)."""
    n = y.size
    e5 = 0.0
    e3 = 0.0
    for m in range(n):
        scale = atol + max(abs(y[m]), abs(y_new[m])) * rtol
        a5 = 0.0
        a3 = 0.0
        for j in range(N_STAGES + 1):
            a5 += K[j, m] * E5[j]
            a3 += K[j, m] * E3[j]
        a5 /= scale
        a3 /= scale
        e5 += a5 * a5
        e3 += a3 * a3
    if e5 == 0.0 and e3 == 0.0:
        return 0.0
    return h_abs * e5 / math.sqrt((e5 + 0.01 * e3) * n)


@inline_kernel
def step_factor(error_norm, rejected):
    """scipy's factor of the next step size: after a rejected step (error_norm ≥ 1), or an accepted one (at most 1
    right after a rejection)."""
    if error_norm >= 1.0:
        return max(MIN_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
    factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
    return min(1.0, factor) if rejected else factor


@inline_kernel
def emit(t_out, i, t, t_new, h, y, y_new, f, K, F, Y):
    """Fill Y[i], Y[i + 1], ... for the output times in (t, t_new] of the accepted step from y (rate f) to y_new
    (K: its stages, the dense output's included; F: room for the coefficients, (7, n)) by scipy's 7th-order dense
    output. Returns the next output index."""
    for m in range(y.size):
        delta = y_new[m] - y[m]
        F[0, m] = delta
        F[1, m] = h * f[m] - delta
        F[2, m] = 2.0 * delta - h * (K[N_STAGES, m] + f[m])
        for r in range(4):
            acc = 0.0
            for j in range(N_EXTENDED):
                acc += D[r, j] * K[j, m]
            F[3 + r, m] = h * acc
    while i < t_out.size and t_out[i] <= t_new:
        if t_out[i] == t_new:
            for m in range(y.size):
                Y[i, m] = y_new[m]
        else:
            x = (t_out[i] - t) / h
            for m in range(y.size):
                v = 0.0
                for r in range(7):
                    v += F[6 - r, m]
                    v *= x if r % 2 == 0 else 1.0 - x
                Y[i, m] = v + y[m]
        i += 1
    return i


@kernel
def run(p, t_out, Y, i_next, i_stop, state, y, f, t_bound, rtol, atol, max_step, stats):
    """Advance until t_out[i_stop − 1] is filled. state = [t, h_abs]; stats = [nfev, steps, rejected].

    Returns (status, next output index). y and f are updated in place. The last step fills every
    output it covers, also beyond i_stop (the next call cannot go back): the next index can pass i_stop.

    One loop evaluates every stage, the step's and (on a second pass, ``dense``) the dense output's,
    so that ``models.rhs`` is inlined (and typed by the first compile) once instead of three times.
    """
    n = y.size
    K = np.empty((N_EXTENDED, n))
    dy = np.empty(n)
    ytmp = np.empty(n)
    y_new = np.empty(n)
    F = np.empty((7, n))
    t, h_abs = state[0], state[1]
    i = i_next
    while i < i_stop:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        rejected = False
        dense = False
        h = 0.0
        t_new = t
        while True:
            if dense:  # the step is accepted, and outputs lie inside it
                first, stop = N_STAGES + 1, N_EXTENDED
            else:
                if h_abs < min_step:
                    state[0], state[1] = t, h_abs
                    return TOO_SMALL_STEP, i
                t_new = t + h_abs
                if t_new - t_bound > 0:
                    t_new = t_bound
                h = t_new - t
                h_abs = abs(h)
                for m in range(n):
                    K[0, m] = f[m]
                first, stop = 1, N_STAGES + 1
            # stage s = f(t + C[s] h, y + h Σ_j A[s, j] K[j]); stage N_STAGES is y_new (A[N_STAGES] = B, C = 1)
            for s in range(first, stop):
                _stage_sum(K, s, A[s], n, dy)
                for m in range(n):
                    ytmp[m] = y[m] + dy[m] * h
                rhs(t + C[s] * h, ytmp, p, K[s])
            if dense:
                stats[0] += N_EXTENDED - N_STAGES - 1
                break
            for m in range(n):
                y_new[m] = ytmp[m]
            stats[0] += N_STAGES
            error_norm = step_error(K, y, y_new, h_abs, rtol, atol)
            if error_norm != error_norm:  # NaN in a stage: no step size fixes it, and a NaN step would loop forever
                state[0], state[1] = t, h_abs
                return NOT_FINITE, i
            h_abs *= step_factor(error_norm, rejected)
            if error_norm >= 1.0:
                rejected = True
                stats[2] += 1
                continue
            stats[1] += 1
            for m in range(n):
                if not math.isfinite(y_new[m]):
                    state[0], state[1] = t, h_abs
                    return NOT_FINITE, i
            # dense output for the outputs inside (t, t_new] (then on to every one, past i_stop too)
            if i < i_stop and t_out[i] <= t_new:
                dense = True
                continue
            break
        if dense:
            i = emit(t_out, i, t, t_new, h, y, y_new, f, K, F, Y)
        t = t_new
        for m in range(n):
            y[m] = y_new[m]
            f[m] = K[N_STAGES, m]
    state[0], state[1] = t, h_abs
    return OK, i
