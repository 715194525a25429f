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
from gyrolab.kernels.compiler import kernel
from gyrolab.kernels.dop853 import (A, C, N_EXTENDED, N_STAGES, NOT_FINITE, OK, TOO_SMALL_STEP, emit, step_error,
                                    step_factor)
from gyrolab.kernels.models import call_block

LANES = 32  # trajectories advanced in lock step
TASK = 256  # trajectories per parallel task, at most


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
def _load(lane, traj, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs, index, Y, nfev):
    """Put trajectory ``traj`` into ``lane``: state, parameters, derivative, scipy's initial step."""
    n = Y0.shape[1]
    y0 = Y0[traj].copy()
    p = Params[traj].copy()
    f0 = np.empty(n)
    models.rhs(t0, y0, p, f0)
    stats = np.zeros(3, dtype=np.int64)
    h_abs[lane] = dop853.initial_step(p, t0, y0, f0, t_bound, max_step, rtol, atol, stats)
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
def run_blocks(block, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status,
               task_size):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j]: the stages by the
    model's right-hand side by columns at ``block`` (``models.block_rhs``), the rest by the model's own
    right-hand side (its address in each parameter row).

    steps/rejected_steps/nfev[j] receive its counts, status[j] OK, TOO_SMALL_STEP or NOT_FINITE
    (its outputs from the failed step on are NaN). t_out has at least two times. Tasks of
    ``task_size`` trajectories (``task_size(count)``) run in parallel.
    """
    count = Y0.shape[0]
    n_tasks = (count + task_size - 1) // task_size
    for task in numba.prange(n_tasks):  # the loop stays small: numba's parallel pass compiles slowly on big bodies
        _task(block, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status,
              task * task_size, min(task * task_size + task_size, count))


def task_size(count: int, lanes: int = LANES) -> int:
    """Trajectories per parallel task (of a batch kernel of ``lanes`` lanes): TASK, or fewer so that a small batch
    still gives every thread a few tasks (never fewer than ``lanes``: a task fills its lanes)."""
    return int(max(lanes, min(TASK, -(-count // (4 * numba.get_num_threads())))))


@kernel
def _task(block, Params, t_out, Y0, Y, rtol, atol, max_step, steps, rejected_steps, nfev, status, first, stop):
    """``run_blocks`` for the trajectories first..stop−1, LANES at a time."""
    n = Y0.shape[1]
    t0, t_bound = t_out[0], t_out[t_out.size - 1]
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
    F = np.empty((7, n))
    following = first
    for lane in range(LANES):
        if following < stop:
            traj[lane] = following
            active[lane] = True
            _load(lane, following, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs, index,
                  Y, nfev)
            following += 1
        else:  # an idle lane computes on a finite copy of lane 0 and is never read
            y[:, lane] = y[:, 0]
            for c in range(P.shape[0]):  # (P holds a parameter per row, a lane per column)
                P[c, lane] = P[c, 0]
    busy = min(LANES, stop - first)
    while busy > 0:
        _trial_steps(active, retry, t, h_abs, h, t_next, t_bound, max_step, traj, status)
        K[0] = f
        for s in range(1, N_STAGES + 1):  # stage N_STAGES is y_new (A[N_STAGES] = B)
            out = y_new if s == N_STAGES else ytmp
            _stage(K, s, A[s], y, h, out, sums)
            _stage_times(t, C[s], h, ts)
            call_block(block, ts, out, P, K[s], LANES)
        if _judge(K, y, y_new, h_abs, rtol, atol, active, retry, dense, traj, index, t_out, t_next, steps,
                  rejected_steps, nfev, status):
            for s in range(N_STAGES + 1, N_EXTENDED):  # the dense output's three extra stages
                _stage(K, s, A[s], y, h, ytmp, sums)
                _stage_times(t, C[s], h, ts)
                call_block(block, ts, ytmp, P, K[s], LANES)
        for lane in range(LANES):
            j = traj[lane]
            if j < 0 or (active[lane] and retry[lane]):
                continue  # an idle lane, or a rejected trial: the lane retries with its smaller step
            if active[lane]:  # an accepted step
                if dense[lane]:
                    nfev[j] += N_EXTENDED - N_STAGES - 1
                    index[lane] = emit(t_out, index[lane], t[lane], t_next[lane], h[lane], y[:, lane],
                                       y_new[:, lane], f[:, lane], K[:, :, lane], F, Y[j])
                t[lane] = t_next[lane]
                y[:, lane] = y_new[:, lane]
                f[:, lane] = K[N_STAGES, :, lane]
                if index[lane] < t_out.size:
                    continue
                status[j] = OK
            else:  # failed: its outputs from here on are NaN
                Y[j, index[lane]:] = np.nan
            if following < stop:  # the lane takes the task's next trajectory
                traj[lane] = following
                active[lane] = True
                retry[lane] = False
                _load(lane, following, Y0, Params, t0, t_bound, max_step, rtol, atol, y, f, P, t, h_abs,
                      index, Y, nfev)
                following += 1
            else:  # idle from now on: a finite state, no step
                traj[lane] = -1
                active[lane] = False
                busy -= 1
                h[lane] = 0.0
                y[:, lane] = 0.0
                f[:, lane] = 0.0


@kernel
def _trial_steps(active, retry, t, h_abs, h, t_next, t_bound, max_step, traj, status):
    """Each active lane's trial step, with the single kernel's clamping and minimum step; a lane whose step is
    below the minimum is marked TOO_SMALL_STEP and inactive (finished after the stages)."""
    for lane in range(active.size):
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
            active[lane] = False
            h[lane] = 0.0
            continue
        t_new = t[lane] + h_abs[lane]
        if t_new - t_bound > 0:
            t_new = t_bound
        t_next[lane] = t_new
        h[lane] = t_new - t[lane]
        h_abs[lane] = abs(h[lane])


@kernel
def _judge(K, y, y_new, h_abs, rtol, atol, active, retry, dense, traj, index, t_out, t_next, steps, rejected_steps,
           nfev, status):
    """Each active lane's error norm, acceptance and next step size (the single kernel's controller); marks the
    accepted steps that cover an output time (``dense``) and returns whether any does."""
    need_dense = False
    for lane in range(active.size):
        dense[lane] = False
        if not active[lane]:
            continue
        j = traj[lane]
        nfev[j] += N_STAGES
        error_norm = step_error(K[:, :, lane], y[:, lane], y_new[:, lane], h_abs[lane], rtol, atol)
        h_abs[lane] *= step_factor(error_norm, retry[lane])
        retry[lane] = error_norm >= 1.0
        if retry[lane]:
            rejected_steps[j] += 1
            continue
        steps[j] += 1
        finite = True
        for c in range(y_new.shape[0]):
            finite = finite and np.isfinite(y_new[c, lane])
        if not finite:
            status[j] = NOT_FINITE
            active[lane] = False
        elif t_out[index[lane]] <= t_next[lane]:
            dense[lane] = True
            need_dense = True
    return need_dense
