"""The Taylor method (``taylor``) for many trajectories at once: per-trajectory steps, vectorised across them.

``run_lanes`` (fixed-point (ω, γ) states) advances LANES trajectories in lock step, one vector register of
doubles (8 on AVX-512, 4 on AVX2): their Taylor coefficients are stored [order, state, lane], lane innermost,
and every part of a step runs over all lanes at once in vector registers: the series (``_series``), the step
sizes (``_step_sizes``), the outputs and the state update (``_advance``). Each lane keeps its own time, step,
Kahan carry and output index, with the single-trajectory kernel's step rule and dense output (``taylor.run``:
same order, same Jorba–Zou step from the last two coefficients, Horner evaluation at the output times,
compensated state update), so a lane takes the steps the single kernel takes on its trajectory, to rounding
(the vector sums add in another order than the scalar ones; the step rule's powers go through a vector
log2/exp2 a few ulps from libm's). A lane reads and writes only its own column, and its arithmetic follows
from its own parameters and state (``split_ready``), so its result does not depend on its neighbours. Taylor
rejects no step: every busy lane advances at every step. A lane whose trajectory has reached the last output
time (or failed) takes the next trajectory of its task (``task_size`` trajectories; tasks run in parallel with
``prange``), so easy and hard trajectories in one task leave no lane idle until the task's last trajectories.

Where a step's time goes (AVX-512, order 17, one thread; ``docs/performance.md``, "Batch Taylor"): the series
about half, the step sizes, the lanes' bookkeeping and the update with the outputs a tenth or so each. The
series is bound by its vector loads, so its forms are chosen to load less per fused multiply-add: the Cauchy
sums run over pairs (j, k − j) (twelve loads serve 24 FMAs), and from order SPLIT on over the series
ω ± √N₂ γ, six sums instead of twelve (``_series``). The work arrays start on 64-byte boundaries (``_rows``).

Why LLVM intrinsics: written as numba loops, the Cauchy sums are reductions whose accumulators LLVM keeps in
memory when the loop over lanes is innermost (numba does not run LLVM's SLP vectoriser, and a short lane loop
is unrolled before the loop vectoriser could vectorise it); such a lock-step kernel was 1.2–2× slower than one
trajectory per thread. The intrinsics emit the arithmetic over ``<LANES x double>`` values directly, the
accumulators in registers. The IR helpers are shared with the single-trajectory kernel's vectorised step
(``simd``).

``run_each`` serves every other model with Taylor coefficients, one trajectory per thread, with the
single-trajectory kernel itself.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from gyrolab.kernels.layout import INERTIA, INV_INERTIA, N_Z, U_Z
from gyrolab.kernels import simd, taylor
from gyrolab.kernels.compiler import kernel
from gyrolab.kernels.vector_width import batch_lanes

#: trajectories advanced in lock step: one vector register of doubles of the CPU numba compiles for (8 with
#: AVX-512, 4 with AVX2; never fewer than 4). Fixed when this module is imported, so frozen into the compiled
#: kernels; numba's cache keys every kernel by the target CPU's name and features (its ``magic_tuple``), from
#: which the width follows, so a cache written for another width is not loaded.
LANES = batch_lanes()
from gyrolab.kernels.taylor import NOT_FINITE, OK, TOO_SMALL_STEP

TASK = 256  # trajectories per parallel task, at most
STATE = 6  # (ω, γ)
CONSTANTS = 12  # a lane's right-hand-side constants (``_load``)


#: The twelve Cauchy sums of a term, as (x, y) component pairs of the state (ω_x, ω_y, ω_z, γ_x, γ_y, γ_z = 0..5):
#: Σ_j x_j y_{k−j}. Pairs of ω (0..2), pairs of γ (3..5), then γ × ω's two halves per component (6..11):
#: γ̇_x = γ_y ω_z − γ_z ω_y (and cyclically), each half summed on its own so no sum waits for another.
PRODUCTS = ((1, 2), (2, 0), (0, 1), (4, 5), (5, 3), (3, 4), (4, 2), (5, 1), (5, 0), (3, 2), (3, 1), (4, 0))
#: The six Cauchy sums of the split form (``_series``), as (a, b) pairs of Z's rows (P_x, P_y, P_z, M_x, M_y, M_z =
#: 0..5): Σ_j P_a,j M_b,k−j for a ≠ b, in the order (y, z), (z, y), (z, x), (x, z), (x, y), (y, x).
SPLIT_PRODUCTS = ((1, 5), (2, 4), (2, 3), (0, 5), (0, 4), (1, 3))
#: Orders computed in the direct form before the split form takes over (``_series``): a coefficient of order k
#: weighs about (h/ρ)^k ≈ tol^(k/order) in a step (≈ 0.23^k at the benchmark's setting), so the split form's
#: larger rounding (``split_ready``) stays far below one ulp of the state from order SPLIT + 1 on.
SPLIT = 6


@intrinsic
def _series(typingctx, T, Z, order, Q, split):
    """Fill T[1..order] from T[0] in every lane: ``fixed_point.taylor_coefficients`` without α, lanes in columns.

    T and Z are (order+1, STATE, LANES), Q (CONSTANTS, LANES) the lanes' constants (``_load``). Order k's
    coefficient is F_k / (k + 1), from the Cauchy sums of the right-hand side's quadratic products:
    ω̇_x = (I_y − I_z)/I_x (ω_y ω_z − N_2 γ_y γ_z) + (U_y γ_z − U_z γ_y)/I_x (and cyclically; U = U_2, the
    torque U_2 × γ, N_2 γ × Iγ the gradient torque), γ̇ = γ × ω: ``fixed_point.rhs`` without α.

    Orders k < split take the direct form: the twelve sums of ``PRODUCTS``. Orders k ≥ split take the split form,
    six sums instead of twelve: with a = √N_2 and the series P = ω + a γ, M = ω − a γ (kept in Z),
    P_y M_z + P_z M_y = 2 (ω_y ω_z − N_2 γ_y γ_z) and P_y M_z − P_z M_y = 2 a (γ_y ω_z − γ_z ω_y), so the six
    sums Σ P_a M_b (a ≠ b) give both the ω and the γ rates. It needs N_2 > 0 in every lane; its rounding grows
    with |ω| / (a |γ|) (``split_ready`` decides; split = order keeps the direct form throughout).

    Each sum Σ_{j=0..k} x_j y_{k−j} runs over the pairs (j, k−j) with j < k − j, adding x_j y_{k−j} + x_{k−j} y_j
    (and the middle term x_{k/2} y_{k/2} when k is even), the pair with the newest coefficient (j = 0) last: the
    vectors loaded for a pair serve twice as many fused multiply-adds, the FMA units bound the loop, and the
    next order's older terms overlap the newest coefficient's computation in the processor's pipeline.
    """
    if not (simd.vector_arrays([T, Z, Q]) and T.ndim == 3 and Z.ndim == 3 and Q.ndim == 2
            and isinstance(order, types.Integer) and isinstance(split, types.Integer)):
        return None
    sig = types.void(T, Z, order, Q, split)

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args, LANES)
        b = builder
        p = context.cast(builder, args[2], signature.args[2], types.intp)
        cut = context.cast(builder, args[4], signature.args[4], types.intp)
        cut = b.select(b.icmp_signed("<", cut, p), cut, p)
        q = [v.load(3, r) for r in range(CONSTANTS)]
        a, half_inv_a, half = q[10], q[11], v.constant(0.5)
        zero = v.constant(0.0)
        one = ir.Constant(p.type, 1)
        sums = v.variables(len(PRODUCTS))

        def row(index, column):
            return v.row(b, index, STATE, column)

        def split_rows(index):
            """Z[index] = (ω + a γ, ω − a γ) from T[index]."""
            x = [v.load(0, row(index, c)) for c in range(STATE)]
            for c in range(3):
                ag = b.fmul(a, x[3 + c], flags=simd.FUSE)
                v.store(b.fadd(x[c], ag, flags=simd.FUSE), 1, row(index, c))
                v.store(b.fsub(x[c], ag, flags=simd.FUSE), 1, row(index, 3 + c))

        def cauchy(k, array, products):
            """Σ_j x_j y_{k−j} over ``array``'s rows (x, y) = products[i], by pairs (j, k − j). With six
            products, the two halves of a pair go to two accumulators (twelve in all), so no accumulator takes
            two dependent fused multiply-adds per pair."""
            twin = len(products) * 2 <= len(sums)
            used = sums[:2 * len(products)] if twin else sums[:len(products)]
            for s in used:
                b.store(zero, s)
            pairs = b.lshr(b.add(k, one), one)
            with cgutils.for_range(b, pairs) as term:
                j = b.sub(b.sub(pairs, one), term.index)  # the pair with the newest coefficient (j = 0) last
                low = [v.load(array, row(j, c)) for c in range(STATE)]
                high = [v.load(array, row(b.sub(k, j), c)) for c in range(STATE)]
                for i, (x, y) in enumerate(products):
                    v.fma_into(sums[i], low[x], high[y])
                    v.fma_into(sums[i + len(products)] if twin else sums[i], high[x], low[y])
            with b.if_then(b.icmp_unsigned("==", b.and_(k, one), ir.Constant(p.type, 0))):  # the middle term
                middle = [v.load(array, row(b.lshr(k, one), c)) for c in range(STATE)]
                for s, (x, y) in zip(sums, products):
                    v.fma_into(s, middle[x], middle[y])
            total = [b.load(x) for x in sums[:len(products)]]
            if twin:
                total = [b.fadd(x, b.load(y), flags=simd.FUSE) for x, y in zip(total, sums[len(products):])]
            return total

        def store_rates(k, pairs, cross):
            """T[k+1] from the ω sums' combinations ``pairs`` (ω_y ω_z − N_2 γ_y γ_z, cyclically) and γ × ω's
            ``cross``; Z[k+1] from T[k+1]."""
            e0, e1, e2 = [v.load(0, row(k, c)) for c in (3, 4, 5)]
            inv = v.inverse(k)
            torque = ((q[4], e2, q[5], e1), (q[6], e0, q[7], e2), (q[8], e1, q[9], e0))
            k1 = b.add(k, one)
            for c in range(3):
                qa, ea, qb, eb = torque[c]
                moment = b.fsub(b.fmul(qa, ea, flags=simd.FUSE), b.fmul(qb, eb, flags=simd.FUSE), flags=simd.FUSE)
                rate = b.fmul(b.fadd(b.fmul(q[c], pairs[c], flags=simd.FUSE), moment, flags=simd.FUSE), inv,
                              flags=simd.FUSE)
                v.store(rate, 0, row(k1, c))
                v.store(b.fmul(cross[c], inv, flags=simd.FUSE), 0, row(k1, 3 + c))
            split_rows(k1)

        split_rows(ir.Constant(p.type, 0))
        with cgutils.for_range(b, cut) as direct:  # orders k < split: the twelve sums of PRODUCTS
            s = cauchy(direct.index, 0, PRODUCTS)
            pairs = [b.fsub(s[c], b.fmul(q[3], s[3 + c], flags=simd.FUSE), flags=simd.FUSE) for c in range(3)]
            cross = [b.fsub(s[6 + 2 * c], s[7 + 2 * c], flags=simd.FUSE) for c in range(3)]
            store_rates(direct.index, pairs, cross)
        with cgutils.for_range(b, p, start=cut) as fast:  # orders k ≥ split: the six sums of SPLIT_PRODUCTS
            s = cauchy(fast.index, 1, SPLIT_PRODUCTS)
            pairs = [b.fmul(b.fadd(s[2 * c], s[2 * c + 1], flags=simd.FUSE), half, flags=simd.FUSE) for c in range(3)]
            cross = [b.fmul(b.fsub(s[2 * c], s[2 * c + 1], flags=simd.FUSE), half_inv_a, flags=simd.FUSE)
                     for c in range(3)]
            store_rates(fast.index, pairs, cross)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _advance(typingctx, T, order, H, carry, D, O):
    """Every lane's output at its own t + dt and its step: O[c] = T[0, c] + (Σ_{k≥1} T[k, c] dt^k − carry[c])
    with dt = D[0] (Horner in strict arithmetic, ``_dense``'s), then the state T[0] += Σ_{k≥1} T[k] h^k with
    h = H[0] (Horner, multiply and add may fuse), a compensated (Kahan, strict) sum with ``carry``
    (``simd.update``'s arithmetic). The twelve Horner chains share their loads of T and interleave: the output
    costs little beside the update. Idle lanes have h = 0; a lane without an output ignores O."""
    if not (simd.vector_arrays([T, H, carry, D, O]) and T.ndim == 3 and isinstance(order, types.Integer)):
        return None
    sig = types.void(T, order, H, carry, D, O)

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args, LANES)
        b = builder
        p = context.cast(builder, args[1], signature.args[1], types.intp)
        h, dt = v.load(2, 0), v.load(4, 0)
        step, output = v.variables(STATE), v.variables(STATE)
        for c in range(STATE):
            top = v.load(0, v.row(b, p, STATE, c))
            b.store(top, step[c])
            b.store(top, output[c])
        last = b.sub(p, ir.Constant(p.type, 1))
        with cgutils.for_range(b, last) as loop:
            k = b.sub(last, loop.index)  # order − 1 … 1
            for c in range(STATE):
                x = v.load(0, v.row(b, k, STATE, c))
                b.store(b.fadd(b.fmul(b.load(step[c]), h, flags=simd.FUSE), x, flags=simd.FUSE), step[c])
                b.store(b.fadd(b.fmul(b.load(output[c]), dt), x), output[c])
        for c in range(STATE):
            y, old = v.load(0, c), v.load(3, c)
            v.store(b.fadd(y, b.fsub(b.fmul(b.load(output[c]), dt), old)), 5, c)
            inc = b.fsub(b.fmul(b.load(step[c]), h), old)
            total = b.fadd(y, inc)
            v.store(b.fsub(b.fsub(total, y), inc), 3, c)
            v.store(total, 0, c)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _step_sizes(typingctx, T, order, K, S):
    """Every lane's Jorba–Zou step (``taylor.step_size``) from its series T[:, :, lane], in vector registers.

    K is (4, LANES): tol, the safety factor, 1/(order − 1), 1/order in every lane. S (2, LANES) receives in row 0
    h = safety · min_k (tol · scale / n_k)^(1/k), k = order − 1, order (scale = max(1, ‖T[0]‖∞), n_k = ‖T[k]‖∞;
    a vanishing n_k drops its term) through 2^(log2(·)/k) (``simd.Lanes.log2``, ``exp2``: a few ulps from the
    scalar power), and in row 1 a flag (1.0) where that path does not apply: a non-finite coefficient, a ratio
    outside the normal doubles, both n_k zero or a step beyond 2^±1000. There the caller takes the scalar rule,
    so every lane steps as ``taylor.run`` would, to rounding. The scalar rule took 2 powers per lane, a quarter
    of the lanes' step.
    """
    if not (simd.vector_arrays([T, K, S]) and T.ndim == 3 and isinstance(order, types.Integer)):
        return None
    sig = types.void(T, order, K, S)

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args, LANES)
        b = builder
        p = context.cast(builder, args[1], signature.args[1], types.intp)
        tol, safety, inv1, inv2 = [v.load(2, r) for r in range(4)]
        zero, one = v.constant(0.0), v.constant(1.0)
        scale, n1, n2, probe = one, zero, zero, zero
        last = b.sub(p, ir.Constant(p.type, 1))
        for c in range(STATE):
            x0, x1, x2 = (v.load(0, v.row(b, index, STATE, c)) for index in (ir.Constant(p.type, 0), last, p))
            a0, a1, a2 = (v.call("fabs", x) for x in (x0, x1, x2))
            scale = b.select(b.fcmp_ordered(">", a0, scale), a0, scale)
            n1 = b.select(b.fcmp_ordered(">", a1, n1), a1, n1)
            n2 = b.select(b.fcmp_ordered(">", a2, n2), a2, n2)
            for x in (x0, x1, x2):  # stays 0 unless a value is inf or NaN (x · 0 is NaN then)
                probe = b.fadd(probe, b.fmul(x, zero))
        special = b.fcmp_unordered("!=", probe, zero)
        smallest, huge, inf = v.constant(2.0 ** -1021), v.constant(1000.0), v.constant(math.inf)
        exponents = []
        for n, inv in ((n1, inv1), (n2, inv2)):
            ratio = b.fdiv(b.fmul(tol, scale), n)
            present = b.fcmp_ordered(">", n, zero)
            normal = b.and_(b.fcmp_ordered(">=", ratio, smallest), b.fcmp_ordered("<", ratio, inf))
            special = b.or_(special, b.and_(present, b.not_(normal)))
            exponents.append(b.select(present, b.fmul(v.log2(ratio), inv), inf))
        y = b.select(b.fcmp_ordered("<", exponents[1], exponents[0]), exponents[1], exponents[0])
        in_range = b.and_(b.fcmp_ordered("<", y, huge), b.fcmp_ordered(">", y, b.fneg(huge)))
        special = b.or_(special, b.not_(in_range))
        y = b.select(in_range, y, zero)
        v.store(b.fmul(v.exp2(y), safety), 3, 0)
        v.store(b.select(special, one, zero), 3, 1)
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _dense(typingctx, T, order, D, carry, O):
    """O[c] = T[0, c] + (Σ_{k≥1} T[k, c] dt^k − carry[c]) in every lane, dt = D[0] (one per lane): each lane's
    series at its own t + dt, Horner in strict arithmetic, the six components' chains interleaved. Lane for
    lane the arithmetic of the scalar dense output of ``taylor.run``."""
    if not (simd.vector_arrays([T, D, carry, O]) and T.ndim == 3 and isinstance(order, types.Integer)):
        return None
    sig = types.void(T, order, D, carry, O)

    def codegen(context, builder, signature, args):
        v = simd.Lanes(context, builder, signature, args, LANES)
        b = builder
        p = context.cast(builder, args[1], signature.args[1], types.intp)
        dt = v.load(2, 0)
        acc = v.variables(STATE)
        for c in range(STATE):
            b.store(v.load(0, v.row(b, p, STATE, c)), acc[c])
        with cgutils.for_range(b, b.sub(p, ir.Constant(p.type, 1))) as loop:
            k = b.sub(b.sub(p, ir.Constant(p.type, 1)), loop.index)  # order − 1 … 1
            for c in range(STATE):
                b.store(b.fadd(b.fmul(b.load(acc[c]), dt), v.load(0, v.row(b, k, STATE, c))), acc[c])
        for c in range(STATE):
            v.store(b.fadd(v.load(0, c), b.fsub(b.fmul(b.load(acc[c]), dt), v.load(3, c))), 4, c)
        return context.get_dummy_value()

    return sig, codegen


def task_size(count: int) -> int:
    """Trajectories per parallel task: TASK, or fewer so that a small batch still gives every thread
    a few tasks (never fewer than LANES: a task fills its lanes)."""
    return int(max(LANES, min(TASK, -(-count // (4 * numba.get_num_threads())))))


#: The split form's bound on |ω| / (√N_2 |γ|) (``split_ready``): its rounding in a coefficient grows about as this
#: ratio; from order SPLIT on, 1024 times an ulp weighs less than 1e-2 ulp of the state in a step. Conservative:
#: against an extended-precision reference (order 18, tol 1e-15, t ∈ [0, 0.2]) the split and direct forms' γ errors
#: agree to three digits at 0.9, 9 and 90 × the bound (8.1e-14, 8.0e-12, 1.1e-9: the fast spin's own error, the
#: tolerance being relative to |ω|), tests/test_batch_taylor_lanes.py checks the edge.
SPLIT_RATIO = 1024.0


def split_ready(Params: np.ndarray, Y0: np.ndarray) -> np.ndarray:
    """Which trajectories take the split form from order SPLIT on (``_series``): N_2 > 0, and |ω| stays within
    SPLIT_RATIO · √N_2 |γ| over the whole trajectory. The bound on |ω| is energy's: ½ ω·Iω changes by at most the
    potential's range, 2 |U_2| |γ| (torque U_2 × γ) plus ½ |N_2| (I_max − I_min) |γ|² (torque N_2 γ × Iγ), so
    I_min |ω|² ≤ ω0·Iω0 + 4 |U_2| |γ| + |N_2| (I_max − I_min) |γ|²; |γ| is constant."""
    inertia = Params[:, INERTIA:INERTIA + 3]
    n2 = Params[:, N_Z]
    u = np.linalg.norm(Params[:, U_Z:U_Z + 3], axis=1)
    gamma = np.linalg.norm(Y0[:, 3:6], axis=1)
    low, high = inertia.min(axis=1), inertia.max(axis=1)
    with np.errstate(all="ignore"):
        kinetic = np.sum(inertia * Y0[:, 0:3] ** 2, axis=1)
        omega_max2 = (kinetic + 4.0 * u * gamma + np.abs(n2) * (high - low) * gamma ** 2) / low
        return (n2 > 0.0) & (low > 0.0) & np.isfinite(omega_max2) & (omega_max2 <= SPLIT_RATIO ** 2 * n2 * gamma ** 2)


def run_lanes(Params, order, tol, t_out, Y0, Y, steps, status):
    """``run_blocks`` on every trajectory: those ``split_ready`` with the split form from order SPLIT on, the
    others with the direct form throughout (two calls when the batch mixes them). A trajectory's arithmetic
    depends on its own parameters and state only."""
    ready = split_ready(Params, Y0)
    for chosen, split in ((ready, SPLIT), (~ready, order)):
        if chosen.all():
            run_blocks(Params, order, tol, t_out, Y0, Y, steps, status, task_size(len(Y0)), split)
        elif chosen.any():
            rows = np.flatnonzero(chosen)
            part_y, part_steps, part_status = Y[rows], steps[rows], status[rows]
            run_blocks(np.ascontiguousarray(Params[rows]), order, tol, t_out, np.ascontiguousarray(Y0[rows]), part_y,
                       part_steps, part_status, task_size(len(rows)), split)
            Y[rows], steps[rows], status[rows] = part_y, part_steps, part_status


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_blocks(Params, order, tol, t_out, Y0, Y, steps, status, task_size, split):
    """Every trajectory j (initial (ω, γ) Y0[j], fixed-point parameters Params[j] without α) over t_out into Y[j],
    the split form from order ``split`` on (``_series``; ``split`` = order: the direct form throughout). The split
    form is for ``split_ready`` trajectories only: ``run_lanes`` sorts them.

    steps[j] receives its number of steps, status[j] OK, NOT_FINITE or TOO_SMALL_STEP (a step of a
    huge series that does not advance time; the single kernel would loop forever); its outputs from the
    failed step on are NaN. t_out has at least two times. Tasks of ``task_size`` trajectories run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(Params, order, tol, t_out, Y0, Y, steps, status, split, task * task_size,
              min(task * task_size + task_size, count))


@kernel
def _load(lane, j, Y0, Params, T, Q, carry):
    """Put trajectory j into ``lane`` (or, with j < 0, make the lane idle: a zero state, whose series is zero).

    Q[:, lane] = the constants of its right-hand side (``_series``): (I_y − I_z)/I_x (and cyclically),
    N_2, U_2's components over the inertia, U_y/I_x, U_z/I_x, U_z/I_y, U_x/I_y, U_x/I_z, U_y/I_z, and the split
    form's a = √N_2 and 1/(2a) (0 and NaN where N_2 ≤ 0: such a lane runs the direct form only, ``split_ready``).
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
    a = math.sqrt(p[N_Z]) if p[N_Z] > 0.0 else 0.0  # the split form's a = √N_2 and 1/(2a) (``_series``)
    Q[10, lane] = a
    Q[11, lane] = 0.5 / a if a > 0.0 else np.nan  # unused by the direct form; the split form would give NaN, not
    # silently wrong rates, were such a lane given to it


@kernel
def _rows(count, width):
    """Zeros of shape (count, width, LANES) whose rows of LANES doubles start on 64-byte boundaries (numba aligns
    arrays to 32 bytes): a 512-bit load across two cache lines costs two, and the split form's sums are bound by
    their loads (``_series``: 0.2 µs aligned, 0.3 µs not, per lane group and step at order 17)."""
    size = count * width * LANES
    buffer = np.zeros(size + 8)
    start = (-buffer.ctypes.data % 64) // 8
    return buffer[start:start + size].reshape((count, width, LANES))


@kernel
def _task(Params, order, tol, t_out, Y0, Y, steps, status, split, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n_out = t_out.size
    t_end = t_out[n_out - 1]
    T = _rows(order + 1, STATE)
    Z = _rows(order + 1, STATE)  # the split form's series ω ± √N_2 γ (``_series``)
    Q = _rows(1, CONSTANTS)[0]
    H = _rows(1, 1)[0]  # each lane's step (0 in idle lanes)
    carry = _rows(1, STATE)[0]  # the Kahan compensation of each lane's state
    t = np.zeros(LANES)
    t_next = np.zeros(LANES)
    index = np.zeros(LANES, dtype=np.int64)  # each lane's next output time
    traj = np.full(LANES, -1, dtype=np.int64)
    safety = math.exp(-0.7 / (order - 1))
    K = _rows(1, 4)[0]  # _step_sizes' constants
    K[0], K[1], K[2], K[3] = tol, safety, 1.0 / (order - 1), 1.0 / order
    S = _rows(1, 2)[0]  # each lane's step from _step_sizes, and where the scalar rule must take over
    D = _rows(1, 1)[0]  # each lane's time from its step's start to its next output time (_dense)
    O = _rows(1, STATE)[0]  # the lanes' states there
    due = np.zeros(LANES, dtype=np.bool_)  # the lanes with an output in this step
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
        _series(T, Z, order, Q, split)
        _step_sizes(T, order, K, S)
        several = False
        for lane in range(LANES):  # each lane's step (``taylor.run``'s rule) and the outputs it covers
            due[lane] = False
            j = traj[lane]
            if j < 0:
                continue
            h = S[0, lane] if S[1, lane] == 0.0 else _scalar_step_size(lane, T, order, tol, safety)
            if not h < np.inf:
                h = t_end - t[lane]
            t_new = min(t[lane] + h, t_end)
            t_next[lane] = t_new
            H[0, lane] = t_new - t[lane]
            i = index[lane]  # a busy lane has an output time left: i < n_out
            due[lane] = t_out[i] <= t_new
            D[0, lane] = t_out[i] - t[lane] if due[lane] else 0.0
            several = several or (due[lane] and i + 1 < n_out and t_out[i + 1] <= t_new)
        if several:  # a step over two output times or more (rare): all its outputs first, then the step alone
            _outputs(T, order, t_out, t, t_next, traj, index, carry, D, O, Y)
            due[:] = False
            D[0, :] = 0.0
        _advance(T, order, H, carry, D, O)
        for lane in range(LANES):
            if due[lane]:
                for c in range(STATE):
                    Y[traj[lane], index[lane], c] = O[c, lane]
                index[lane] += 1
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
def _scalar_step_size(lane, T, order, tol, safety):
    """``taylor.run``'s step rule on ``lane``'s series T[:, :, lane], in scalar arithmetic (where ``_step_sizes``
    flags the lane)."""
    scale = 1.0
    n1 = 0.0
    n2 = 0.0
    for c in range(STATE):
        scale = max(scale, abs(T[0, c, lane]))
        n1 = max(n1, abs(T[order - 1, c, lane]))
        n2 = max(n2, abs(T[order, c, lane]))
    return taylor.step_size(tol, scale, n1, n2, order, safety)


@kernel
def _outputs(T, order, t_out, t, t_next, traj, index, carry, D, O, Y):
    """The outputs of every lane's step from t to t_next: its series at each output time the step covers
    (``_dense``, all lanes at once; a lane without an output in this step is evaluated and ignored)."""
    n_out = t_out.size
    while True:
        due = False
        for lane in range(LANES):
            D[0, lane] = 0.0
            if traj[lane] >= 0 and index[lane] < n_out and t_out[index[lane]] <= t_next[lane]:
                D[0, lane] = t_out[index[lane]] - t[lane]
                due = True
        if not due:
            return
        _dense(T, order, D, carry, O)
        for lane in range(LANES):
            j = traj[lane]
            if j >= 0 and index[lane] < n_out and t_out[index[lane]] <= t_next[lane]:
                for c in range(STATE):
                    Y[j, index[lane], c] = O[c, lane]
                index[lane] += 1


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
