"""DOP853 (``dop853``) for many trajectories at once: per-trajectory step control, vectorised across them.

``run_blocks`` advances LANES trajectories of any compiled model in lock step,
stored column-wise as in ``rk4.run_batch_blocks``: every stage is one call of
the model's right-hand side by columns (generated from its equations,
``models.block_rhs``) and one stage sum over all lanes, so the arithmetic
vectorises across trajectories. Each lane keeps its own time, step, derivative,
output index and accept/reject state, with the single-trajectory kernel's
controller (scipy's: same initial step, error norm, step factors, minimum
step), so a lane takes the steps the single kernel takes on its trajectory, to
rounding. A lane reads and writes only its own column, so its result does not
depend on its neighbours. A lane whose trajectory has reached the last output
time takes the next trajectory of its task (TASK trajectories; tasks run in
parallel with ``prange``): easy and hard trajectories in one task cost no idle
lanes until the task's last trajectories. Outputs come from the 7th-order
dense output (three extra stages, computed on the steps that cover an output).
"""

from __future__ import annotations

import numba
import numpy as np

from gyrolab.kernels import dop853, models
from gyrolab.kernels.dop853 import (A, B, C, D, E3, E5, ERROR_EXPONENT, MAX_FACTOR, MIN_FACTOR, N_EXTENDED,
                                             N_STAGES, NOT_FINITE, OK, SAFETY, TOO_SMALL_STEP)
from gyrolab.kernels.models import call_block

LANES = 32  # trajectories advanced in lock step
TASK = 256  # trajectories per parallel task, at most
RUNNING = -1  # status of a trajectory not finished yet


@numba.njit(cache=True, error_model="numpy")
def _stage(K, s, a_row, y, h, ytmp, acc):
    """ytmp = y + h ⊙ Σ_{l<s} a_row[l] K[l] in every lane (the single kernel's order of operations per lane;
    the loops over lanes are innermost and vectorise)."""
    n, lanes = y.shape
    for c in range(n):
        for j in range(lanes):
            acc[j] = 0.0
        for l in range(s):
            a = a_row[l]
            for j in range(lanes):
                acc[j] += K[l, c, j] * a
        for j in range(lanes):
            ytmp[c, j] = y[c, j] + acc[j] * h[j]


@numba.njit(cache=True, error_model="numpy")
def _stage_times(t, c, h, ts):
    """ts = t + c h in every lane (the single kernel's stage time)."""
    for j in range(t.size):
        ts[j] = t[j] + c * h[j]


@numba.njit(cache=True, error_model="numpy")
def _load(model, lane, traj, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs, index, Y, nfev):
    """Put trajectory ``traj`` into ``lane``: state, parameters, derivative, scipy's initial step."""
    n = Y0.shape[1]
    y0 = Y0[traj].copy()
    p = Params[traj].copy()
    f0 = np.empty(n)
    models.rhs(model, t0, y0, p, f0)
    stats = np.zeros(3, dtype=np.int64)
    h_abs[lane] = dop853.initial_step(model, p, t0, y0, f0, t_bound, max_step, rtol, atol, stats)
    nfev[traj] = 1 + stats[0]
    for c in range(n):
        y[c, lane] = y0[c]
        f[c, lane] = f0[c]
        Y[traj, 0, c] = y0[c]
    for c in range(p.size):
        P[c, lane] = p[c]
    t[lane] = t0
    index[lane] = 1


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_blocks(block, model, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status,
               task_size):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j]: the stages by the
    model's right-hand side by columns at ``block`` (``models.block_rhs``), the rest by ``model`` (a Form).

    steps/rejected_steps/nfev[j] receive its counts, status[j] OK, TOO_SMALL_STEP or NOT_FINITE
    (its outputs from the failed step on are NaN). t_out has at least two times. Tasks of
    ``task_size`` trajectories (``task_size(count)``) run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(block, model, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status,
              task * task_size, min(task * task_size + task_size, count))


def task_size(count: int) -> int:
    """Trajectories per parallel task: TASK, or fewer so that a small batch still gives every thread
    a few tasks (never fewer than LANES: a task fills its lanes)."""
    return int(max(LANES, min(TASK, -(-count // (4 * numba.get_num_threads())))))


@numba.njit(cache=True, error_model="numpy")
def _task(block, model, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n = Y0.shape[1]
    n_out = t_out.size
    t0, t_bound = t_out[0], t_out[n_out - 1]
    K = np.zeros((N_EXTENDED, n, LANES))
    y = np.zeros((n, LANES))
    f = np.zeros((n, LANES))
    ytmp = np.zeros((n, LANES))
    y_new = np.zeros((n, LANES))
    P = np.zeros((Params.shape[1], LANES))
    t = np.zeros(LANES)
    ts = np.zeros(LANES)  # each lane's stage time
    sums = np.zeros(LANES)
    h = np.zeros(LANES)  # the trial step of each lane (0 in idle and failed lanes)
    t_next = np.zeros(LANES)  # the trial step's end (kept: t + (t_next − t) need not round to t_next)
    h_abs = np.zeros(LANES)
    index = np.zeros(LANES, dtype=np.int64)
    traj = np.full(LANES, -1, dtype=np.int64)
    active = np.zeros(LANES, dtype=np.bool_)  # the lane holds a trajectory
    retry = np.zeros(LANES, dtype=np.bool_)  # the lane's last trial step was rejected
    dense = np.zeros(LANES, dtype=np.bool_)  # the lane's accepted step covers an output time
    F = np.empty(7)
    following = first
    for lane in range(LANES):
        if following < stop:
            traj[lane] = following
            active[lane] = True
            _load(model, lane, following, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs, index,
                  Y, nfev)
            following += 1
        else:  # an idle lane computes on a finite copy of lane 0 and is never read
            for c in range(n):
                y[c, lane] = y[c, 0]
            for c in range(P.shape[0]):
                P[c, lane] = P[c, 0]
    busy = min(LANES, stop - first)
    while busy > 0:
        # each lane's trial step (the single kernel's clamping and minimum step)
        for lane in range(LANES):
            if not active[lane]:
                continue
            min_step = 10.0 * abs(np.nextafter(t[lane], np.inf) - t[lane])
            if not retry[lane]:
                if h_abs[lane] > max_step:
                    h_abs[lane] = max_step
                elif h_abs[lane] < min_step:
                    h_abs[lane] = min_step
            if h_abs[lane] < min_step:
                status[traj[lane]] = TOO_SMALL_STEP
                active[lane] = False  # finished below, after the stages
                h[lane] = 0.0
                continue
            t_new = t[lane] + h_abs[lane]
            if t_new - t_bound > 0:
                t_new = t_bound
            t_next[lane] = t_new
            h[lane] = t_new - t[lane]
            h_abs[lane] = abs(h[lane])
        for c in range(n):
            for lane in range(LANES):
                K[0, c, lane] = f[c, lane]
        for s in range(1, N_STAGES):
            _stage(K, s, A[s], y, h, ytmp, sums)
            _stage_times(t, C[s], h, ts)
            call_block(block, ts, ytmp, P, K[s], LANES)
        _stage(K, N_STAGES, B, y, h, y_new, sums)
        _stage_times(t, C[N_STAGES], h, ts)
        call_block(block, ts, y_new, P, K[N_STAGES], LANES)
        # each lane's error norm, acceptance and next step
        need_dense = False
        for lane in range(LANES):
            dense[lane] = False
            if not active[lane]:
                continue
            j = traj[lane]
            nfev[j] += N_STAGES
            e5 = 0.0
            e3 = 0.0
            for c in range(n):
                scale = atol + max(abs(y[c, lane]), abs(y_new[c, lane])) * rtol
                a5 = 0.0
                a3 = 0.0
                for l in range(N_STAGES + 1):
                    a5 += K[l, c, lane] * E5[l]
                    a3 += K[l, c, lane] * E3[l]
                a5 /= scale
                a3 /= scale
                e5 += a5 * a5
                e3 += a3 * a3
            if e5 == 0.0 and e3 == 0.0:
                error_norm = 0.0
            else:
                error_norm = h_abs[lane] * e5 / np.sqrt((e5 + 0.01 * e3) * n)
            if error_norm >= 1.0:
                h_abs[lane] *= max(MIN_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
                retry[lane] = True
                rejected_steps[j] += 1
                continue
            factor = MAX_FACTOR if error_norm == 0.0 else min(MAX_FACTOR, SAFETY * error_norm ** ERROR_EXPONENT)
            if retry[lane]:
                factor = min(1.0, factor)
            h_abs[lane] *= factor
            retry[lane] = False
            steps[j] += 1
            finite = True
            for c in range(n):
                finite = finite and np.isfinite(y_new[c, lane])
            if not finite:
                status[j] = NOT_FINITE
                active[lane] = False
                continue
            if t_out[index[lane]] <= t_next[lane]:
                dense[lane] = True
                need_dense = True
        if need_dense:  # the three extra stages of the dense output, for the lanes that need them
            for s in range(N_STAGES + 1, N_EXTENDED):
                _stage(K, s, A[s], y, h, ytmp, sums)
                _stage_times(t, C[s], h, ts)
                call_block(block, ts, ytmp, P, K[s], LANES)
        for lane in range(LANES):
            j = traj[lane]
            if j < 0:
                continue
            if active[lane] and not retry[lane]:  # an accepted step
                t_old = t[lane]
                t_new = t_next[lane]
                if dense[lane]:
                    nfev[j] += N_EXTENDED - N_STAGES - 1
                    hl = h[lane]
                    while index[lane] < n_out and t_out[index[lane]] <= t_new:
                        i = index[lane]
                        x = (t_out[i] - t_old) / hl
                        for c in range(n):
                            if t_out[i] == t_new:
                                Y[j, i, c] = y_new[c, lane]
                                continue
                            delta = y_new[c, lane] - y[c, lane]
                            F[0] = delta
                            F[1] = hl * f[c, lane] - delta
                            F[2] = 2.0 * delta - hl * (K[N_STAGES, c, lane] + f[c, lane])
                            for r in range(4):
                                acc = 0.0
                                for l in range(N_EXTENDED):
                                    acc += D[r, l] * K[l, c, lane]
                                F[3 + r] = hl * acc
                            v = 0.0
                            for r in range(7):
                                v += F[6 - r]
                                v *= x if r % 2 == 0 else 1.0 - x
                            Y[j, i, c] = v + y[c, lane]
                        index[lane] = i + 1
                t[lane] = t_new
                for c in range(n):
                    y[c, lane] = y_new[c, lane]
                    f[c, lane] = K[N_STAGES, c, lane]
                if index[lane] < n_out:
                    continue
                status[j] = OK
            elif active[lane]:
                continue  # a rejected trial: the lane retries with its smaller step
            else:  # failed: its outputs from here on are NaN
                for i in range(index[lane], n_out):
                    for c in range(n):
                        Y[j, i, c] = np.nan
            if following < stop:  # the lane takes the task's next trajectory
                traj[lane] = following
                active[lane] = True
                retry[lane] = False
                _load(model, lane, following, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs,
                      index, Y, nfev)
                following += 1
            else:  # idle from now on: a finite state, no step
                traj[lane] = -1
                active[lane] = False
                busy -= 1
                h[lane] = 0.0
                for c in range(n):
                    y[c, lane] = 0.0
                    f[c, lane] = 0.0
