"""The batch Taylor kernel's vector parts against independent code: the generated series against an
extended-precision reference, the step rule against the scalar one, the outputs of a step over several output
times against the single-trajectory kernel, and a lane's independence from its neighbours."""

import math

import numba
import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.kernels import batch_taylor, taylor
from gyrolab.kernels.layout import N_Z
from tests.helpers.taylor import fixed_point_rows, single_kernel_runs

LANES = batch_taylor.LANES


@numba.njit
def _both_rules(T, order, tol, vector, scalar, flags):
    """The vector step sizes of every lane (and their flags) beside the scalar rule ``taylor.step_size``."""
    safety = math.exp(-0.7 / (order - 1))
    K = np.empty((4, LANES))
    K[0], K[1], K[2], K[3] = tol, safety, 1.0 / (order - 1), 1.0 / order
    S = np.zeros((2, LANES))
    batch_taylor._step_sizes(T, order, T.shape[1], K, S)
    for lane in range(LANES):
        vector[lane], flags[lane] = S[0, lane], S[1, lane]
        scale, n1, n2 = 1.0, 0.0, 0.0
        for c in range(6):
            scale = max(scale, abs(T[0, c, lane]))
            n1 = max(n1, abs(T[order - 1, c, lane]))
            n2 = max(n2, abs(T[order, c, lane]))
        scalar[lane] = taylor.step_size(tol, scale, n1, n2, order, safety)


def test_vector_step_sizes_are_the_scalar_rule_to_rounding():
    """Random series over 60 decades of magnitude, orders 4–30, tolerances 1e-16…1e-3: every lane the vector
    path keeps has the scalar rule's step (powers by libm) within 1e-13 relative, and the lanes it hands back to
    the scalar rule are exactly those it cannot take (a non-finite coefficient, both last coefficients zero)."""
    rng = np.random.default_rng(1)
    for trial in range(3000):
        order = int(rng.integers(4, 31))
        T = rng.normal(size=(order + 1, 6, LANES)) * 10.0 ** rng.uniform(-30, 30, size=(order + 1, 1, LANES))
        special = np.zeros(LANES, dtype=bool)
        if trial % 5 == 0:
            T[order - 1, :, rng.integers(LANES)] = 0.0  # one vanishing term: the other decides
        if trial % 7 == 0:
            lane = rng.integers(LANES)
            T[order - 1:, :, lane] = 0.0  # both vanish: the step goes to the end
            special[lane] = True
        if trial % 11 == 0:
            lane = rng.integers(LANES)
            T[rng.choice([0, order - 1, order]), rng.integers(6), lane] = rng.choice([np.nan, np.inf])  # a row the rule reads
            special[lane] = True
        vector, scalar, flags = np.zeros(LANES), np.zeros(LANES), np.zeros(LANES)
        _both_rules(np.ascontiguousarray(T), order, 10.0 ** rng.uniform(-16, -3), vector, scalar, flags)
        kept = flags == 0.0
        assert not (kept & special).any()
        np.testing.assert_allclose(vector[kept], scalar[kept], rtol=1e-13, atol=0)


SCENE = ["experiment=perf_reference", "time.end=2", "time.n_output=11", "integrator=taylor"]


def _scene(extra=()):
    return compose_scene([*SCENE, *extra])


def _starts(scene, count, seed, scale=0.1):
    rng = np.random.default_rng(seed)
    y0s = np.tile(scene.system.initial_state(), (count, 1))
    y0s[:, 0:3] += rng.normal(scale=scale, size=(count, 3))
    return y0s


def test_lanes_follow_the_extended_precision_reference():
    """The generated lanes (the fixed point's traced equations) against an independent oracle,
    ``physics.reference`` (the Euler–Poisson equations' own Taylor series summed in long double, not these
    kernels): spins up to four times the reference's and N₂ from 0 to 2, tol 1e-15 at order 18 on t ∈ [0, 2]:
    every output within 1e-12."""
    from gyrolab.physics.reference import fixed_point_reference
    from gyrolab.kernels.layout import INERTIA, U_Z

    extra = ["integrator.tol=1e-15", "integrator.order=18"]
    scene = _scene(extra)
    y0s = _starts(scene, LANES + 3, seed=11)
    y0s[::3, 0:3] *= 4.0
    P, packed = fixed_point_rows(SCENE + extra, np.full(len(y0s), 2.0), np.linspace(0.0, 2.0, len(y0s)))
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    for j in range(len(y0s)):
        reference = fixed_point_reference(packed[j, INERTIA:INERTIA + 3], packed[j, U_Z:U_Z + 3], packed[j, N_Z],
                                          y0s[j], scene.times).astype(float)
        assert np.max(np.abs(batch.y[j] - reference)) < 1e-12


def test_a_trajectory_in_a_mixed_batch_is_computed_as_alone():
    """A batch mixing parameters (N₂ = 0 for some): each result, bit for bit, the one it has alone (its arithmetic
    follows from its own parameters and state, never from its neighbours)."""
    scene = _scene()
    y0s = _starts(scene, 2 * LANES + 3, seed=13)
    P, _ = fixed_point_rows(SCENE, np.full(len(y0s), 2.0), np.where(np.arange(len(y0s)) % 3 == 0, 0.0, 0.5))
    mixed = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    for j in (0, 1, 3, len(y0s) - 1):
        alone = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s[j:j + 1], P[j:j + 1])
        np.testing.assert_array_equal(mixed.y[j], alone.y[0])
        assert mixed.steps[j] == alone.steps[0]


@pytest.mark.parametrize("n_output", [201, 2001])  # steps of ~0.17 over outputs 0.01 and 0.001 apart
def test_steps_over_several_output_times_agree_with_the_single_kernel(n_output):
    """Output times closer than a step (several outputs per step: the separate output path) against the
    single-trajectory kernel (``taylor.run``, scalar Horner per output): the same steps, outputs within 1e-13."""
    scene = _scene([f"time.n_output={n_output}", "integrator.tol=1e-12"])
    y0s = _starts(scene, LANES + 3, seed=14)
    P = np.tile(scene.compiled.params, (len(y0s), 1))
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    out, steps = single_kernel_runs(scene.compiled, P, scene.integrator, scene.times, y0s)
    assert batch.steps.max() < n_output / 2
    np.testing.assert_array_equal(batch.steps, steps)
    np.testing.assert_allclose(batch.y, out, rtol=0, atol=1e-13)


@numba.njit
def _row_addresses(order):
    T = batch_taylor._rows(order + 1, 6)
    Q = batch_taylor._rows(1, 11)[0]
    return T.ctypes.data % 64, Q.ctypes.data % 64


def test_work_arrays_are_aligned_to_whole_vectors():
    assert _row_addresses(17) == (0, 0)


def _every_function(t, y):
    """A system using every function the lanes have a recurrence for (and time, a division, a real power)."""
    a, b, c = y[0], y[1], y[2]
    return np.array([np.sin(b) * 0.3 + np.sqrt(1.5 + c * c) - a / (2.0 + b * b),
                     np.exp(-0.2 * a) * np.cos(c) + np.arctan(a) - np.tanh(b) + 0.1 * t,
                     np.log(2.0 + a * a) + np.tan(0.1 * b) + np.arctan2(c, 3.0 + a) + abs(1.5 + b) ** 1.5
                     - np.abs(c + 3.0)], dtype=object)


def test_lanes_of_every_function_follow_scipy_and_the_single_kernel():
    """The lanes' recurrences of sin/cos, sqrt, exp, log, tan, tanh, arctan, arctan2, a real power, abs and a
    division (``batch_taylor._Functions``) against scipy's DOP853 on the numpy equations (an independent oracle:
    within 1e-11) and against the single-trajectory kernel's (``taylor_series``): the same steps, outputs within
    1e-13."""
    from scipy.integrate import solve_ivp

    from gyrolab.kernels import model
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    compiled = model.compile(model.trace(_every_function, 3, "every function"))
    y0s = np.random.default_rng(1).normal(scale=0.5, size=(LANES + 5, 3))
    times = np.linspace(0.0, 3.0, 31)
    integrator = Taylor(tol=1e-13)
    batch = integrate_arrays(compiled, integrator, times, y0s)
    for j in (0, LANES + 4):
        reference = solve_ivp(lambda t, y: _every_function(t, y).astype(float), (0.0, 3.0), y0s[j], method="DOP853",
                              rtol=1e-13, atol=1e-13, t_eval=times).y.T
        assert np.max(np.abs(batch.y[j] - reference)) < 1e-11
    out, steps = single_kernel_runs(compiled, np.tile(compiled.params, (len(y0s), 1)), integrator, times, y0s)
    np.testing.assert_array_equal(batch.steps, steps)
    np.testing.assert_allclose(batch.y, out, rtol=0, atol=1e-13)
