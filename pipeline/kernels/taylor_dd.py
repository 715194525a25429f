"""The Taylor series method in double-double arithmetic (≈ 32 digits): "clean numerical simulation" (Liao 2009).

Every model's coefficients come from its generated series (``series_dd``: Cauchy products as compensated dot
products, ``double_double.dot_add``, error ≤ ~k·u²·Σ|terms| for the k-th coefficient, u² = 2^-106; the numbers
derived from the parameters, 1/I included, computed in double-double, so no double rounding caps the run at 16
digits). The method is ``taylor.run``'s: Jorba & Zou's order (``taylor.order_for``) and step (``taylor.step_size``,
from the last two coefficients' max norms) for a tolerance down to 1e-32, the series as the dense output. Every
number that enters the state is a double-double (``double_double``):

* the state is carried in double-double between steps (``yh``, ``yl``: high and low parts);
* time stays a double: a step ends on fl(t + h), and the step actually taken, t_new − t, and every dense
  output's offset t_out[i] − t are formed exactly as double-doubles (``two_sum``), so no time error enters;
* the state update and the dense output are Horner sums in double-double; an output is stored as the double
  nearest its double-double value (its high part), and optionally its low part (``Ylo``).

Step selection works on the high parts (a step size needs no 32 digits). Status codes as ``taylor``'s.
"""

from __future__ import annotations

import math

import numpy as np

from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.double_double import dd_add, dd_mul, two_sum
from gyrolab.kernels.taylor import NOT_FINITE, OK, TOO_SMALL_STEP, _call_dd_series, _norm_row, order_for, step_size

#: the smallest tolerance the double-double kernel takes (its unit round-off is 2^-106 ≈ 1.2e-32)
MIN_TOL = 1e-32


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


@kernel
def run(p, order, tol, t_out, Y, Ylo, i_next, i_stop, state, yh, yl, stats):
    """Advance until t_out[i_stop − 1] is filled: ``taylor.run``'s contract (steps clipped at the last output
    time only, every output a step passes filled, state = [t], stats = [coefficient evaluations, steps],
    returns (status, next output index)) with the state in double-double (yh, yl). Y receives the outputs
    rounded to double; Ylo their low parts when it has Y's shape (else it is not touched). The series is the
    model's generated one (``series_dd``), whose address and scratch columns end ``p``."""
    n = yh.size
    Th = np.zeros((order + 1, n))
    Tl = np.zeros((order + 1, n))
    vh, vl = np.empty(n), np.empty(n)
    S = np.zeros((order + 1) * 2 * int(p[p.size - 1]))
    address = int(p[p.size - 2])
    if address == 0:  # the series was not compiled (``series_dd.ready`` not called): no step, not a crash
        return NOT_FINITE, i_next
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
        _call_dd_series(address, t, order, Th, Tl, S, p)
        stats[0] += 1
        scale = max(1.0, _norm_row(Th, 0))  # row 0: the state's high parts
        h = step_size(tol, scale, _norm_row(Th, order - 1), _norm_row(Th, order), order, safety)
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


def propagate(p: np.ndarray, tol: float, t_out, y0, order: int | None = None, y0_low=None):
    """The states at ``t_out`` from ``y0`` (doubles, or double-doubles with ``y0_low``) in one call into the kernel:
    (high parts, low parts), each (len(t_out), state size), the first row the initial state. For tests, benchmarks
    and callers that want all 32 digits; the integrator plugin (``Taylor(precision="double-double")``) chunks
    its calls for progress instead. Raises RuntimeError on a non-OK status."""
    t_out = np.asarray(t_out, dtype=float)
    yh = np.array(y0, dtype=float)
    yl = np.zeros_like(yh) if y0_low is None else np.array(y0_low, dtype=float)
    Y = np.empty((len(t_out), len(yh)))
    Ylo = np.empty_like(Y)
    Y[0], Ylo[0] = yh, yl
    state = np.array([t_out[0]])
    stats = np.zeros(2, dtype=np.int64)
    order = order_for(tol, overhead=0.0) if order is None else order
    status, _ = run(p, order, tol, t_out, Y, Ylo, 1, len(t_out), state, yh, yl, stats)
    if status != OK:
        raise RuntimeError(f"double-double Taylor kernel stopped near t={state[0]:.6g} (status {status})")
    return Y, Ylo
