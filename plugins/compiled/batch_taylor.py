"""The Taylor method (``taylor``) for many trajectories at once: per-trajectory steps, vectorised across them.

``run_blocks`` (fixed-point (ω, γ) states) advances LANES = 4 trajectories in
lock step, one AVX2 vector: their Taylor coefficients are stored
[order, state, lane], lane innermost, and the Cauchy sums of all four lanes are
computed together in 4-wide SIMD registers (``_cauchy_sums``). Each lane keeps
its own time, step, Kahan carry and output index, with the single-trajectory
kernel's step rule and dense output (``taylor.run``: same order, same
Jorba–Zou step from the last two coefficients, Horner evaluation at the output
times, compensated state update), so a lane takes the steps the single kernel
takes on its trajectory, to rounding (the vector sums fuse multiply and add in
another order than the scalar ones). A lane reads and writes only its own
column, so its result does not depend on its neighbours. A lane whose
trajectory has reached the last output time (or failed) takes the next
trajectory of its task (``task_size`` trajectories; tasks run in parallel with
``prange``), so easy and hard trajectories in one task leave no lane idle until
the task's last trajectories.

Why an LLVM intrinsic: written as numba loops, the Cauchy sums are reductions
whose accumulators LLVM keeps in memory when the loop over lanes is innermost
(numba does not run LLVM's SLP vectoriser, and its loop vectoriser fully
unrolls a 4-lane loop before it could vectorise it); such a lock-step kernel
was 1.2–2× slower than one trajectory per thread. The intrinsic emits the sums
over ``<4 x double>`` values directly: nine vector accumulators in registers,
twelve vector loads and twelve fused multiply-adds per term of the sums, 2×
faster per trajectory than the scalar sums (``docs/performance.md``).

``run_each`` serves every other model with Taylor coefficients, one trajectory
per thread, with the single-trajectory kernel itself.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.plugins.compiled import kernel, taylor
from gyrolab.plugins.compiled.taylor import NOT_FINITE, OK

LANES = 4  # trajectories advanced in lock step: one AVX2 vector of doubles
TASK = 256  # trajectories per parallel task, at most
STATE = 6  # (ω, γ)
SUMS = 9  # Cauchy sums per order: pairs of ω (3), pairs of γ (3), γ × ω (3)
RUNNING = -1  # a lane's trajectory after a step that did not reach the last output time


@intrinsic
def _cauchy_sums(typingctx, T, k, acc):
    """acc[s, :] = the k-th coefficients of the nine quadratic products, every lane at once.

    T is C-contiguous (order+1, STATE, LANES) (rows 0..k filled), acc C-contiguous (SUMS, LANES):
    acc[0:3] = Σ_j (ω1_j ω2_{k−j}, ω2_j ω0_{k−j}, ω0_j ω1_{k−j}), acc[3:6] the same for γ,
    acc[6:9] = Σ_j γ_j × ω_{k−j}: the sums ``fixed_point.taylor_coefficients`` forms, per lane.
    """
    if not (isinstance(T, types.Array) and T.ndim == 3 and T.layout == "C" and T.dtype == types.float64
            and isinstance(acc, types.Array) and acc.ndim == 2 and acc.layout == "C" and acc.dtype == types.float64
            and isinstance(k, types.Integer)):
        return None
    sig = types.void(T, k, acc)

    def codegen(context, builder, signature, args):
        vec = ir.VectorType(ir.DoubleType(), LANES)
        rows = builder.bitcast(context.make_array(signature.args[0])(context, builder, args[0]).data, vec.as_pointer())
        out = builder.bitcast(context.make_array(signature.args[2])(context, builder, args[2]).data, vec.as_pointer())
        order_k = context.cast(builder, args[1], signature.args[1], types.intp)
        sums = [cgutils.alloca_once_value(builder, ir.Constant(vec, [0.0] * LANES)) for _ in range(SUMS)]
        fuse = ("contract",)  # multiply and add may fuse (as in the scalar kernel's fastmath)

        def load(row, c):
            return builder.load(builder.gep(rows, [builder.add(row, ir.Constant(row.type, c))]), align=8)

        def accumulate(s, x, y, subtract=False):
            product = builder.fmul(x, y, flags=fuse)
            value = builder.load(sums[s])
            value = builder.fsub(value, product, flags=fuse) if subtract else builder.fadd(value, product, flags=fuse)
            builder.store(value, sums[s])

        with cgutils.for_range(builder, builder.add(order_k, ir.Constant(order_k.type, 1))) as loop:
            j = loop.index
            row_j = builder.mul(j, ir.Constant(j.type, STATE))
            row_m = builder.mul(builder.sub(order_k, j), ir.Constant(j.type, STATE))
            w0, w1, w2, g0, g1, g2 = [load(row_j, c) for c in range(STATE)]
            W0, W1, W2, G0, G1, G2 = [load(row_m, c) for c in range(STATE)]
            accumulate(0, w1, W2)
            accumulate(1, w2, W0)
            accumulate(2, w0, W1)
            accumulate(3, g1, G2)
            accumulate(4, g2, G0)
            accumulate(5, g0, G1)
            accumulate(6, g1, W2)
            accumulate(6, g2, W1, subtract=True)
            accumulate(7, g2, W0)
            accumulate(7, g0, W2, subtract=True)
            accumulate(8, g0, W1)
            accumulate(8, g1, W0, subtract=True)
        for s in range(SUMS):
            builder.store(builder.load(sums[s]), builder.gep(out, [ir.Constant(ir.IntType(64), s)]), align=8)
        return context.get_dummy_value()

    return sig, codegen


@kernel
def _coefficients(P, T, order, acc):
    """Fill T[1..order] from T[0] in every lane: ``fixed_point.taylor_coefficients`` without α, lanes in columns.

    Y[k+1] = F_k / (k + 1), F_k from the Cauchy sums: ω̇ = I⁻¹((Iω) × ω + U_2 × γ + N_2 γ × Iγ), γ̇ = γ × ω.
    """
    for k in range(order):
        _cauchy_sums(T, k, acc)
        inv = 1.0 / (k + 1)
        for lane in range(LANES):
            I0, I1, I2 = P[0, lane], P[1, lane], P[2, lane]
            d0, d1, d2 = I1 - I2, I2 - I0, I0 - I1  # ((Iω) × ω) = (d0 ω_y ω_z, d1 ω_z ω_x, d2 ω_x ω_y)
            n2 = P[14, lane]
            u0, u1, u2 = P[9, lane], P[10, lane], P[11, lane]
            e0, e1, e2 = T[k, 3, lane], T[k, 4, lane], T[k, 5, lane]
            T[k + 1, 0, lane] = (d0 * (acc[0, lane] - n2 * acc[3, lane]) + u1 * e2 - u2 * e1) * P[16, lane] * inv
            T[k + 1, 1, lane] = (d1 * (acc[1, lane] - n2 * acc[4, lane]) + u2 * e0 - u0 * e2) * P[17, lane] * inv
            T[k + 1, 2, lane] = (d2 * (acc[2, lane] - n2 * acc[5, lane]) + u0 * e1 - u1 * e0) * P[18, lane] * inv
            T[k + 1, 3, lane] = acc[6, lane] * inv
            T[k + 1, 4, lane] = acc[7, lane] * inv
            T[k + 1, 5, lane] = acc[8, lane] * inv


def task_size(count: int) -> int:
    """Trajectories per parallel task: TASK, or fewer so that a small batch still gives every thread
    a few tasks (never fewer than LANES: a task fills its lanes)."""
    return int(max(LANES, min(TASK, -(-count // (4 * numba.get_num_threads())))))


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_blocks(Params, order, tol, t_out, Y0, Y, steps, status, task_size):
    """Every trajectory j (initial (ω, γ) Y0[j], fixed-point parameters Params[j] without α) over t_out into Y[j].

    steps[j] receives its number of steps, status[j] OK or NOT_FINITE (its outputs from the failed
    step on are NaN). t_out has at least two times. Tasks of ``task_size`` trajectories run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(Params, order, tol, t_out, Y0, Y, steps, status, task * task_size,
              min(task * task_size + task_size, count))


@kernel
def _load(lane, j, Y0, Params, T, P, carry):
    """Put trajectory j into ``lane`` (or, with j < 0, make the lane idle: a zero state, whose series is zero)."""
    for c in range(STATE):
        T[0, c, lane] = Y0[j, c] if j >= 0 else 0.0
        carry[c, lane] = 0.0
    for c in range(P.shape[0]):
        P[c, lane] = Params[j, c] if j >= 0 else 0.0


@kernel
def _task(Params, order, tol, t_out, Y0, Y, steps, status, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    T = np.zeros((order + 1, STATE, LANES))
    acc = np.zeros((SUMS, LANES))
    P = np.zeros((Params.shape[1], LANES))
    carry = np.zeros((STATE, LANES))  # the Kahan compensation of each lane's state
    t = np.zeros(LANES)
    index = np.zeros(LANES, dtype=np.int64)  # each lane's next output time
    traj = np.full(LANES, -1, dtype=np.int64)
    safety = math.exp(-0.7 / (order - 1))
    following = first
    for lane in range(LANES):
        if following < stop:
            traj[lane] = following
            following += 1
        _load(lane, traj[lane], Y0, Params, T, P, carry)
        t[lane] = t_out[0]
        index[lane] = 1
        if traj[lane] >= 0:
            Y[traj[lane], 0] = Y0[traj[lane]]
    busy = min(LANES, stop - first)
    while busy > 0:
        _coefficients(P, T, order, acc)
        for lane in range(LANES):
            j = traj[lane]
            if j < 0:
                continue
            code = _advance(lane, T, order, tol, safety, t_out, t_end, t, index, carry, Y[j])
            if code == RUNNING:
                steps[j] += 1
                continue
            if code == NOT_FINITE:  # its outputs from the failed step on are NaN
                for i in range(index[lane], n_out):
                    for c in range(STATE):
                        Y[j, i, c] = np.nan
            else:
                steps[j] += 1
            status[j] = code
            traj[lane] = following if following < stop else -1  # the lane takes the task's next trajectory
            if following < stop:
                following += 1
                Y[traj[lane], 0] = Y0[traj[lane]]
            else:
                busy -= 1
            _load(lane, traj[lane], Y0, Params, T, P, carry)
            t[lane] = t_out[0]
            index[lane] = 1



@kernel
def _advance(lane, T, order, tol, safety, t_out, t_end, t, index, carry, Yj):
    """One step of ``lane`` with its series T[:, :, lane]: ``taylor.run``'s step rule, dense output and Kahan update.

    Returns RUNNING, OK (the last output time is filled) or NOT_FINITE (the state became non-finite).
    """
    scale = 1.0
    n1 = 0.0
    n2 = 0.0
    for c in range(STATE):
        scale = max(scale, abs(T[0, c, lane]))
        n1 = max(n1, abs(T[order - 1, c, lane]))
        n2 = max(n2, abs(T[order, c, lane]))
    h = np.inf
    if n1 > 0:
        h = min(h, (tol * scale / n1) ** (1.0 / (order - 1)))
    if n2 > 0:
        h = min(h, (tol * scale / n2) ** (1.0 / order))
    h *= safety
    t0 = t[lane]
    if not h < np.inf:
        h = t_end - t0
    t_new = min(t0 + h, t_end)
    h = t_new - t0
    n_out = t_out.size
    i = index[lane]
    while i < n_out and t_out[i] <= t_new:
        dt = t_out[i] - t0
        for c in range(STATE):
            v = T[order, c, lane]
            for k in range(order - 1, 0, -1):
                v = v * dt + T[k, c, lane]
            Yj[i, c] = T[0, c, lane] + (v * dt - carry[c, lane])
        i += 1
    index[lane] = i
    finite = True
    for c in range(STATE):
        v = T[order, c, lane]
        for k in range(order - 1, 0, -1):
            v = v * h + T[k, c, lane]
        y = T[0, c, lane]
        inc = v * h - carry[c, lane]  # Kahan: y + v·h with the bits lost in earlier additions carried
        s = y + inc
        carry[c, lane] = (s - y) - inc
        T[0, c, lane] = s
        finite = finite and math.isfinite(s)
    if not finite:
        return NOT_FINITE
    t[lane] = t_new
    return OK if i >= n_out else RUNNING


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_each(model, Params, order, tol, t_out, Y0, Y, steps, status):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j], one per thread.

    steps[j] receives its number of steps, status[j] OK or NOT_FINITE (its outputs from the
    failed step on are NaN). t_out has at least two times.
    """
    for j in numba.prange(Y0.shape[0]):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _one(model, Params, order, tol, t_out, Y0, Y, steps, status, j)


@kernel
def _one(model, Params, order, tol, t_out, Y0, Y, steps, status, j):
    y = Y0[j].copy()
    Y[j, 0] = y
    state = np.array([t_out[0]])
    carry = np.zeros(y.size)
    stats = np.zeros(2, dtype=np.int64)
    code, reached = taylor.run(model, Params[j], order, tol, t_out, Y[j], 1, t_out.size, state, y, carry, stats)
    steps[j] = stats[1]
    status[j] = code
    if code != OK:
        for r in range(reached, t_out.size):
            Y[j, r] = np.nan
