"""The single-trajectory Taylor kernel run on each trajectory of a batch: the reference of the batch lanes' tests."""

import numba
import numpy as np

from gyrolab.kernels import taylor, taylor_series
from gyrolab.kernels.model import bind


@numba.njit(cache=True)
def _each(Params, order, tol, t_out, Y0, Y, steps, status):
    for j in range(Y0.shape[0]):
        y = Y0[j].copy()
        Y[j, 0] = y
        state = np.array([t_out[0]])
        stats = np.zeros(2, dtype=np.int64)
        code, reached = taylor.run(Params[j], order, tol, t_out, Y[j], 1, t_out.size, state, y,
                                   np.zeros(y.size), stats)
        steps[j], status[j] = stats[1], code
        if code != taylor.OK:
            Y[j, reached:] = np.nan


def single_kernel_runs(compiled, P, integrator, times, y0s):
    """Each trajectory j (state y0s[j], parameters P[j]) by ``taylor.run`` with ``integrator``'s order and tol, alone:
    (outputs, steps, status) shaped as a ``BatchSolution``'s; the status must be OK for every one."""
    P = bind(compiled, np.array(P, dtype=float))
    assert taylor_series.ready(compiled, P)
    out = np.empty((len(y0s), len(times), y0s.shape[1]))
    steps, status = np.zeros(len(y0s), dtype=np.int64), np.zeros(len(y0s), dtype=np.int64)
    _each(P, integrator.order, integrator.tol, np.asarray(times, dtype=float),
          np.ascontiguousarray(y0s, dtype=float), out, steps, status)
    assert not status.any()
    return out, steps


def fixed_point_rows(overrides, a_values, k_values):
    """Per-trajectory parameter rows of the fixed point with A/C = a_values[j] and the Newtonian k = k_values[j]
    (each row a scene of its own, composed from ``overrides``): (the compiled models' rows, their packed built-in
    parameters for the references)."""
    from gyrolab import compose_scene

    scenes = [compose_scene([*overrides, f"body.a={a}", f"force.newtonian.k={k}"])
              for a, k in zip(a_values, k_values)]
    return (np.array([s.compiled.params for s in scenes]), np.array([s.compiled.built_in for s in scenes]))
