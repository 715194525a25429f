"""Classical RK4 with a fixed step, compiled; one trajectory or a batch in parallel."""

from __future__ import annotations

import numba
import numpy as np

from gyrolab.plugins.compiled import kernel
from gyrolab.plugins.compiled.fixed_point import rhs_block
from gyrolab.plugins.compiled.models import rhs


@kernel
def _advance(model, p, t0, y, interval, steps, k1, k2, k3, k4, tmp):
    h = interval / steps
    n = y.size
    for j in range(steps):
        t = t0 + j * h
        rhs(model, t, y, p, k1)
        for m in range(n):
            tmp[m] = y[m] + 0.5 * h * k1[m]
        rhs(model, t + 0.5 * h, tmp, p, k2)
        for m in range(n):
            tmp[m] = y[m] + 0.5 * h * k2[m]
        rhs(model, t + 0.5 * h, tmp, p, k3)
        for m in range(n):
            tmp[m] = y[m] + h * k3[m]
        rhs(model, t + h, tmp, p, k4)
        for m in range(n):
            y[m] += (h / 6.0) * (k1[m] + 2.0 * k2[m] + 2.0 * k3[m] + k4[m])


@kernel
def run(model, p, t_out, steps_per_interval, y, Y, i_next, i_stop):
    """Fill Y[i_next:i_stop]; y is advanced in place. Returns the first index left non-finite, or i_stop."""
    n = y.size
    k1, k2, k3, k4, tmp = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    for i in range(i_next, i_stop):
        _advance(model, p, t_out[i - 1], y, t_out[i] - t_out[i - 1], steps_per_interval[i - 1], k1, k2, k3, k4, tmp)
        for m in range(n):
            if not np.isfinite(y[m]):
                return i
        Y[i] = y
    return i_stop


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_batch(model, P, t_out, steps_per_interval, Y0, Y):
    """Many trajectories at once: P[j] parameters and Y0[j] initial state of trajectory j; Y[j, i] the outputs."""
    count, n = Y0.shape
    for j in numba.prange(count):
        y = Y0[j].copy()
        k1, k2, k3, k4, tmp = np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        Y[j, 0] = y
        for i in range(1, t_out.size):
            _advance(model, P[j], t_out[i - 1], y, t_out[i] - t_out[i - 1], steps_per_interval[i - 1],
                     k1, k2, k3, k4, tmp)
            Y[j, i] = y


BLOCK = 64


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_batch_blocks(P, t_out, steps_per_interval, Y0, Y):
    """``run_batch`` for fixed-point (ω, γ) states, by blocks of trajectories stored column-wise.

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
        k1, k2, k3 = np.empty((n, BLOCK)), np.empty((n, BLOCK)), np.empty((n, BLOCK))
        k4, tmp = np.empty((n, BLOCK)), np.empty((n, BLOCK))
        for i in range(1, t_out.size):
            steps = steps_per_interval[i - 1]
            h = (t_out[i] - t_out[i - 1]) / steps
            for _ in range(steps):
                rhs_block(y, p, k1, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = y[c, j] + 0.5 * h * k1[c, j]
                rhs_block(tmp, p, k2, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = y[c, j] + 0.5 * h * k2[c, j]
                rhs_block(tmp, p, k3, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = y[c, j] + h * k3[c, j]
                rhs_block(tmp, p, k4, m)
                for c in range(n):
                    for j in range(m):
                        y[c, j] += (h / 6.0) * (k1[c, j] + 2.0 * k2[c, j] + 2.0 * k3[c, j] + k4[c, j])
            for j in range(m):
                Y[j0 + j, i] = y[:, j]
