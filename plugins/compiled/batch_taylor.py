"""The Taylor method (``taylor``) for many trajectories at once: one trajectory per thread.

Each trajectory runs the single-trajectory kernel (``taylor.run``) with its own
order-p series, steps and Kahan carry, from the first to the last output time
in one call; trajectories run in parallel with ``prange``.

Not vectorised across trajectories, by measurement: a version advancing 4 to 64
trajectories in lock step (coefficients stored lane-innermost, every lane with
its own step and output index) was 1.2–2× slower per trajectory than this one
on AVX2 (numba 0.68): the Cauchy sums of the coefficients are reductions whose
accumulators LLVM keeps in memory when the loop over lanes is innermost, so the
lanes' loads and stores cost more than the scalar sums they replace. DOP853's
stages, sums over earlier stages with no such recurrence, do vectorise
(``batch_dop853.run_blocks``).
"""

from __future__ import annotations

import numba
import numpy as np

from gyrolab.plugins.compiled import kernel, taylor

OK, NOT_FINITE = taylor.OK, taylor.NOT_FINITE


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_each(model, Params, order, tol, t_out, Y0, Y, steps, status):
    """Every trajectory j (initial state Y0[j], parameters Params[j]) over t_out into Y[j].

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
