"""Classical RK4 with a fixed step, compiled; one trajectory or a batch in parallel."""

from __future__ import annotations

import math

import numba
import numpy as np

from gyrolab.kernels.compiler import kernel
from gyrolab.kernels.models import call_block, rhs


#: Nodes of the four stages, as fractions of the step.
NODES = np.array([0.0, 0.5, 0.5, 1.0])


@kernel
def _advance(p, t0, y, interval, steps, K, tmp):
    """``steps`` RK4 steps over ``interval`` from t0; K (4 × n) holds the stages.

    One loop over the stages, so that ``models.rhs`` is inlined (and typed, on the first compile)
    once instead of four times; the arithmetic is the textbook one, operation for operation.
    """
    h = interval / steps
    n = y.size
    for j in range(steps):
        t = t0 + j * h
        for s in range(4):
            if s == 0:
                for m in range(n):
                    tmp[m] = y[m]
            else:
                a = h if s == 3 else 0.5 * h
                for m in range(n):
                    tmp[m] = y[m] + a * K[s - 1, m]
            rhs(t + NODES[s] * h, tmp, p, K[s])
        for m in range(n):
            y[m] += (h / 6.0) * (K[0, m] + 2.0 * K[1, m] + 2.0 * K[2, m] + K[3, m])


@kernel
def run(p, t_out, steps_per_interval, y, Y, i_next, i_stop):
    """Fill Y[i_next:i_stop]; y is advanced in place. Returns the first index left non-finite, or i_stop."""
    n = y.size
    K, tmp = np.empty((4, n)), np.empty(n)
    for i in range(i_next, i_stop):
        _advance(p, t_out[i - 1], y, t_out[i] - t_out[i - 1], steps_per_interval[i - 1], K, tmp)
        for m in range(n):
            if not math.isfinite(y[m]):
                return i
            Y[i, m] = y[m]
    return i_stop


BLOCK = 64


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_batch_blocks(block, P, t_out, steps_per_interval, Y0, Y):
    """Every trajectory j (initial state Y0[j], parameters P[j]) over t_out into Y[j] with ``run``'s steps, by
    blocks of trajectories stored column-wise, the stages by the model's right-hand side by columns at ``block``
    (``models.block_rhs``).

    Each block advances BLOCK trajectories in lock step, so every loop runs across
    trajectories and vectorises; blocks run in parallel.
    """
    count, n = Y0.shape
    n_blocks = (count + BLOCK - 1) // BLOCK
    for b in numba.prange(n_blocks):
        j0 = b * BLOCK
        m = min(BLOCK, count - j0)
        y = np.empty((n, BLOCK))
        p = np.empty((P.shape[1], BLOCK))
        for j in range(m):
            y[:, j] = Y0[j0 + j]
            p[:, j] = P[j0 + j]
            Y[j0 + j, 0] = Y0[j0 + j]
        K, tmp = np.empty((4, n, BLOCK)), np.empty((n, BLOCK))
        ts = np.empty(BLOCK)  # the stage's time (``run``'s), in every lane
        for i in range(1, t_out.size):
            steps = steps_per_interval[i - 1]
            h = (t_out[i] - t_out[i - 1]) / steps
            for step in range(steps):
                t = t_out[i - 1] + step * h
                for s in range(4):  # ``_advance``'s stages, across the block's lanes
                    if s > 0:
                        a = h if s == 3 else 0.5 * h
                        for c in range(n):
                            for j in range(m):
                                tmp[c, j] = y[c, j] + a * K[s - 1, c, j]
                    ts[:] = t + NODES[s] * h
                    call_block(block, ts, y if s == 0 else tmp, p, K[s], m)
                for c in range(n):
                    for j in range(m):
                        y[c, j] += (h / 6.0) * (K[0, c, j] + 2.0 * K[1, c, j] + 2.0 * K[2, c, j] + K[3, c, j])
            for j in range(m):
                Y[j0 + j, i] = y[:, j]
