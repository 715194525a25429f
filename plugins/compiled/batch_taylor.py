"""The Taylor method (``taylor``) for many trajectories at once: per-trajectory steps, vectorised across them.

``run_blocks`` (fixed-point (ω, γ) states) advances LANES (8 on AVX-512, 4 on AVX2) trajectories in
lock step, one AVX2 vector: their Taylor coefficients are stored
[order, state, lane], lane innermost, and the series of all four lanes are
computed together in 4-wide SIMD registers (``_series``), as is the state
update (``_update``). Each lane keeps its own time, step, Kahan carry and
output index, with the single-trajectory kernel's step rule and dense output
(``taylor.run``: same order, same Jorba–Zou step from the last two
coefficients, Horner evaluation at the output times, compensated state
update), so a lane takes the steps the single kernel takes on its trajectory,
to rounding (the vector sums fuse multiply and add in another order than the
scalar ones). A lane reads and writes only its own column, so its result does
not depend on its neighbours. Taylor rejects no step: every busy lane advances
at every step. A lane whose trajectory has reached the last output time (or
failed) takes the next trajectory of its task (``task_size`` trajectories;
tasks run in parallel with ``prange``), so easy and hard trajectories in one
task leave no lane idle until the task's last trajectories.

Why LLVM intrinsics: written as numba loops, the Cauchy sums are reductions
whose accumulators LLVM keeps in memory when the loop over lanes is innermost
(numba does not run LLVM's SLP vectoriser, and a 4-iteration lane loop is
unrolled before the loop vectoriser could vectorise it); such a lock-step
kernel was 1.2–2× slower than one trajectory per thread. The intrinsics emit
the arithmetic over ``<4 x double>`` values directly: nine vector accumulators
in registers, twelve vector loads and twelve fused multiply-adds per term of
the sums; a whole step costs 2.7× less per trajectory than one trajectory per
thread (``docs/performance.md``, "Taylor lanes"). The IR helpers are shared with
the single-trajectory kernel's vectorised step (``simd``).

``run_each`` serves every other model with Taylor coefficients, one trajectory
per thread, with the single-trajectory kernel itself.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils

from gyrolab.plugins.compiled.layout import INERTIA, INV_INERTIA, N_Z, U_Z
from gyrolab.plugins.compiled import kernel, simd, taylor
from gyrolab.plugins.compiled.vector_width import batch_lanes

#: trajectories advanced in lock step: one vector register of doubles of the CPU numba compiles for (8 with
#: AVX-512, 4 with AVX2; never fewer than 4). Fixed when this module is imported, so frozen into the compiled
#: kernels; numba's cache keys every kernel by the target CPU's name and features (its ``magic_tuple``), from
#: which the width follows, so a cache written for another width is not loaded.
LANES = batch_lanes()
from gyrolab.plugins.compiled.taylor import NOT_FINITE, OK, TOO_SMALL_STEP

TASK = 256  # trajectories per parallel task, at most
STATE = 6  # (ω, γ)
SUMS = 9  # Cauchy sums per order: pairs of ω (3), pairs of γ (3), γ × ω (3)
CONSTANTS = 10  # a lane's right-hand-side constants (``_load``)


@simd.series(STATE, LANES)
def _series(v, p, row):
    """Fill T[1..order] from T[0] in every lane: ``fixed_point.taylor_coefficients`` without α, lanes in columns.

    T is (order+1, STATE, LANES), Q (CONSTANTS, LANES) the lanes' constants (``_load``). Order k's coefficient is
    F_k / (k + 1), with F_k from the Cauchy sums of the quadratic products, each a sum over j of
    ω_j ω_{k−j}-type terms: pairs of ω (s0..s2), pairs of γ (s3..s5), γ × ω (s6..s8):
    ω̇_x = (I_y − I_z)/I_x (ω_y ω_z − N_2 γ_y γ_z) + (U_y γ_z − U_z γ_y)/I_x (and cyclically; U = U_2, the
    torque U_2 × γ, N_2 γ × Iγ the gradient torque), γ̇ = γ × ω: ``fixed_point.rhs`` without α.
    The sums run over nine vector accumulators in registers, twelve vector loads and twelve fused
    multiply-adds per term.
    """
    b = v.builder
    q = [v.load(2, r) for r in range(CONSTANTS)]
    sums = v.variables(SUMS)
    zero = ir.Constant(v.vec, [0.0] * LANES)
    with cgutils.for_range(b, p) as order_loop:
        k = order_loop.index
        for s in sums:
            b.store(zero, s)
        with cgutils.for_range(b, b.add(k, ir.Constant(k.type, 1))) as term:
            j = term.index
            m = b.sub(k, j)
            w0, w1, w2, g0, g1, g2 = [v.load(0, row(j, c)) for c in range(STATE)]
            W0, W1, W2, G0, G1, G2 = [v.load(0, row(m, c)) for c in range(STATE)]
            for s, x, y, subtract in ((0, w1, W2, False), (1, w2, W0, False), (2, w0, W1, False),
                                      (3, g1, G2, False), (4, g2, G0, False), (5, g0, G1, False),
                                      (6, g1, W2, False), (6, g2, W1, True), (7, g2, W0, False),
                                      (7, g0, W2, True), (8, g0, W1, False), (8, g1, W0, True)):
                v.fma_into(sums[s], x, y, subtract)
        s = [b.load(x) for x in sums]
        e0, e1, e2 = [v.load(0, row(k, c)) for c in (3, 4, 5)]
        inv = v.inverse(k)
        k1 = b.add(k, ir.Constant(k.type, 1))
        rate = [v.fixed_point_rate(q[0], q[3], s[0], s[3], q[4], e2, q[5], e1, inv),
                v.fixed_point_rate(q[1], q[3], s[1], s[4], q[6], e0, q[7], e2, inv),
                v.fixed_point_rate(q[2], q[3], s[2], s[5], q[8], e1, q[9], e0, inv),
                b.fmul(s[6], inv, flags=simd.FUSE), b.fmul(s[7], inv, flags=simd.FUSE),
                b.fmul(s[8], inv, flags=simd.FUSE)]
        for c in range(STATE):
            v.store(rate[c], 0, row(k1, c))


#: Every lane's state T[0] += Σ_{k≥1} T[k] h^k (Horner), a compensated (Kahan) sum with ``carry``: H is (1, LANES),
#: the lanes' steps (0 in idle lanes); carry (STATE, LANES). The Horner sums may fuse multiply and add; the Kahan
#: update is strict (``taylor.run``'s arithmetic), and the six components' Horner chains interleave.
_update = simd.update(STATE, STATE, LANES)


def task_size(count: int) -> int:
    """Trajectories per parallel task: TASK, or fewer so that a small batch still gives every thread
    a few tasks (never fewer than LANES: a task fills its lanes)."""
    return int(max(LANES, min(TASK, -(-count // (4 * numba.get_num_threads())))))


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_blocks(Params, order, tol, t_out, Y0, Y, steps, status, task_size):
    """Every trajectory j (initial (ω, γ) Y0[j], fixed-point parameters Params[j] without α) over t_out into Y[j].

    steps[j] receives its number of steps, status[j] OK, NOT_FINITE or TOO_SMALL_STEP (a step of a
    huge series that does not advance time; the single kernel would loop forever); its outputs from the
    failed step on are NaN. t_out has at least two times. Tasks of ``task_size`` trajectories run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(Params, order, tol, t_out, Y0, Y, steps, status, task * task_size,
              min(task * task_size + task_size, count))


@kernel
def _load(lane, j, Y0, Params, T, Q, carry):
    """Put trajectory j into ``lane`` (or, with j < 0, make the lane idle: a zero state, whose series is zero).

    Q[:, lane] = the constants of its right-hand side (``_series``): (I_y − I_z)/I_x (and cyclically),
    N_2, and U_2's components over the inertia, U_y/I_x, U_z/I_x, U_z/I_y, U_x/I_y, U_x/I_z, U_y/I_z.
    """
    for c in range(STATE):
        T[0, c, lane] = Y0[j, c] if j >= 0 else 0.0
        carry[c, lane] = 0.0
    if j < 0:
        for r in range(Q.shape[0]):
            Q[r, lane] = 0.0
        return
    p = Params[j]
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    u0, u1, u2 = p[U_Z], p[U_Z + 1], p[U_Z + 2]
    Q[0, lane] = (I1 - I2) * p[INV_INERTIA]
    Q[1, lane] = (I2 - I0) * p[INV_INERTIA + 1]
    Q[2, lane] = (I0 - I1) * p[INV_INERTIA + 2]
    Q[3, lane] = p[N_Z]
    Q[4, lane], Q[5, lane] = u1 * p[INV_INERTIA], u2 * p[INV_INERTIA]
    Q[6, lane], Q[7, lane] = u2 * p[INV_INERTIA + 1], u0 * p[INV_INERTIA + 1]
    Q[8, lane], Q[9, lane] = u0 * p[INV_INERTIA + 2], u1 * p[INV_INERTIA + 2]


@kernel
def _task(Params, order, tol, t_out, Y0, Y, steps, status, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    T = np.zeros((order + 1, STATE, LANES))
    Q = np.zeros((CONSTANTS, LANES))
    H = np.zeros((1, LANES))  # each lane's step (0 in idle lanes)
    carry = np.zeros((STATE, LANES))  # the Kahan compensation of each lane's state
    t = np.zeros(LANES)
    t_next = np.zeros(LANES)
    index = np.zeros(LANES, dtype=np.int64)  # each lane's next output time
    traj = np.full(LANES, -1, dtype=np.int64)
    safety = math.exp(-0.7 / (order - 1))
    following = first
    for lane in range(LANES):
        if following < stop:
            traj[lane] = following
            Y[following, 0] = Y0[following]
            following += 1
        _load(lane, traj[lane], Y0, Params, T, Q, carry)
        t[lane] = t_out[0]
        index[lane] = 1
    busy = min(LANES, stop - first)
    while busy > 0:
        _series(T, order, Q)
        for lane in range(LANES):
            j = traj[lane]
            if j >= 0:
                t_next[lane] = _step(lane, T, order, tol, safety, t_out, t_end, t[lane], index, carry, Y[j])
                H[0, lane] = t_next[lane] - t[lane]
        _update(T, order, H, carry)
        for lane in range(LANES):
            j = traj[lane]
            if j < 0:
                continue
            finite = True
            for c in range(STATE):
                finite = finite and math.isfinite(T[0, c, lane])
            if finite and t_next[lane] > t[lane]:
                steps[j] += 1
                t[lane] = t_next[lane]
                if index[lane] < n_out:
                    continue
                status[j] = OK
            else:  # non-finite, or a step too small to advance time: its outputs from here on are NaN
                status[j] = NOT_FINITE if not finite else TOO_SMALL_STEP
                for i in range(index[lane], n_out):
                    for c in range(STATE):
                        Y[j, i, c] = np.nan
            traj[lane] = following if following < stop else -1  # the lane takes the task's next trajectory
            if following < stop:
                Y[following, 0] = Y0[following]
                following += 1
            else:
                busy -= 1
            _load(lane, traj[lane], Y0, Params, T, Q, carry)
            t[lane] = t_out[0]
            index[lane] = 1
            H[0, lane] = 0.0


@kernel
def _step(lane, T, order, tol, safety, t_out, t_end, t, index, carry, Yj):
    """The end of ``lane``'s next step (``taylor.run``'s step rule from its series T[:, :, lane], starting at t)
    and the outputs that step covers (Horner evaluation of the series, the Kahan carry subtracted, as there)."""
    scale = 1.0
    n1 = 0.0
    n2 = 0.0
    for c in range(STATE):
        scale = max(scale, abs(T[0, c, lane]))
        n1 = max(n1, abs(T[order - 1, c, lane]))
        n2 = max(n2, abs(T[order, c, lane]))
    h = taylor.step_size(tol, scale, n1, n2, order, safety)
    if not h < np.inf:
        h = t_end - t
    t_new = min(t + h, t_end)
    n_out = t_out.size
    i = index[lane]
    while i < n_out and t_out[i] <= t_new:
        dt = t_out[i] - t
        for c in range(STATE):
            v = T[order, c, lane]
            for k in range(order - 1, 0, -1):
                v = v * dt + T[k, c, lane]
            Yj[i, c] = T[0, c, lane] + (v * dt - carry[c, lane])
        i += 1
    index[lane] = i
    return t_new


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_each(model, Params, order, tol, t_out, Y0, Y, steps, status):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j], one per thread.

    steps[j] receives its number of steps, status[j] OK, NOT_FINITE or TOO_SMALL_STEP (its outputs from the
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
