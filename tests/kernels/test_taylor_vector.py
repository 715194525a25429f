"""The vectorised Taylor step (``taylor.run_vector``: the fixed-point model without α, its components across the
lanes of ``<4 x double>``) against the scalar step (``taylor.run_scalar``) and independent computations."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.kernels import fixed_point, models, taylor

EXTENDED = np.longdouble


def _random_params(rng):
    """Every parameter slot nonzero: the inertia, U_2 (9..11), N_2 (14), 1/I, and also the α slots (U_0, U_1,
    N_0, N_1), which both kernels must ignore when the state carries no α (p[15] = 0)."""
    p = rng.uniform(-1.5, 1.5, fixed_point.N_PARAMS)
    p[0:3] = rng.uniform(0.5, 2.0, 3)
    p[15] = 0.0
    p[16:19] = 1.0 / p[0:3]
    return p


def _extended_coefficients(p, y, order):
    """The Taylor coefficients of I ω̇ = Iω × ω + U_2 × γ + N_2 γ × Iγ, γ̇ = γ × ω (the fixed-point equations
    without α, ``fixed_point`` module docstring), from Cauchy products of the vector products in extended precision:
    independent of both kernels' component forms."""
    inertia = p[0:3].astype(EXTENDED)
    u2, n2 = p[9:12].astype(EXTENDED), EXTENDED(p[14])
    W = np.zeros((order + 1, 3), dtype=EXTENDED)
    G = np.zeros((order + 1, 3), dtype=EXTENDED)
    W[0], G[0] = y[:3], y[3:]

    def cross(a, b, k):
        return np.cross(a[: k + 1], b[k::-1]).sum(axis=0)

    for k in range(order):
        torque = cross(inertia * W, W, k) + np.cross(u2, G[k]) + n2 * cross(G, inertia * G, k)
        W[k + 1] = torque / inertia / (k + 1)
        G[k + 1] = cross(G, W, k) / (k + 1)
    return np.hstack([W, G])


def test_vector_coefficients_equal_the_scalar_kernels_to_rounding():
    """Random states and parameters, orders 4..30: per order k, both kernels within 2e-15 (k + 1) of the row's max
    norm of the extended-precision coefficients (double rounding, 1.1e-16 per operation, ~k + 1 of them in a
    sum; measured: at most 3.1e-16 (k + 1)), and within twice that of each other."""
    rng = np.random.default_rng(20261124)
    for order in range(4, 31):
        for _ in range(3):
            p = _random_params(rng)
            y = rng.uniform(-1.0, 1.0, 6)
            scalar = np.zeros((order + 1, 6))
            scalar[0] = y
            fixed_point.taylor_coefficients(p, scalar, order, np.zeros((order + 1, 3)))
            vector = taylor.series(p, y, order)
            exact = _extended_coefficients(p, y, order)
            bound = 2e-15 * np.arange(1, order + 2)[:, None] * np.max(np.abs(exact), axis=1, keepdims=True)
            assert np.all(np.abs(vector - exact) <= bound), order
            assert np.all(np.abs(scalar - exact) <= bound), order
            assert np.all(np.abs(vector - scalar) <= 2 * bound), order
            assert np.array_equal(vector[0], y)


def _reference_scene(tol, end=300.0, n_output=3001):
    return compose_scene(["experiment=perf_reference", "integrator=taylor", f"integrator.tol={tol}",
                          f"time.end={end}", f"time.n_output={n_output}"])


def _run(kernel, compiled, order, tol, t_out, y0, **kwargs):
    out = np.full((t_out.size, y0.size), -1.0)
    out[0] = y0
    y, state, carry, stats = y0.copy(), np.array([t_out[0]]), np.zeros(y0.size), np.zeros(2, dtype=np.int64)
    args = (order, tol, t_out, out, 1, t_out.size, state, y, carry, stats)
    if kernel is taylor.run_vector:
        code, reached = kernel(compiled.params, *args)
    else:
        code, reached = kernel(compiled.model, compiled.params, *args)
    return code, reached, out, y, state[0], carry, stats


def test_run_takes_the_vector_step_for_the_fixed_point_model_without_alpha_only():
    """``taylor.run`` dispatches: the reference scene (fixed point, (ω, γ)) bit for bit as ``run_vector``; the
    same scene carrying α (Euler angles on: its traced equations) bit for bit as ``run_scalar``."""
    scene = _reference_scene(1e-10, end=20.0, n_output=201)
    assert scene.compiled.model == models.FIXED_POINT and scene.compiled.params[15] == 0.0
    y0 = scene.system.initial_state()
    for kernel in (taylor.run, taylor.run_vector):
        result = _run(kernel, scene.compiled, scene.integrator.order, 1e-10, scene.times, y0)
        if kernel is taylor.run:
            first = result
        else:
            for a, b in zip(first, result):
                np.testing.assert_array_equal(a, b)
    with_alpha = compose_scene(["experiment=perf_reference", "integrator=taylor", "integrator.tol=1e-10",
                                "time.end=20", "time.n_output=201", "output.euler_angles=true"])
    assert with_alpha.compiled.model == models.TRACED  # α: the traced equations, the scalar step
    from gyrolab.kernels import taylor_series

    assert taylor_series.ready(with_alpha.compiled)
    y0 = with_alpha.system.initial_state()
    a, b = (_run(kernel, with_alpha.compiled, 13, 1e-10, with_alpha.times, y0)
            for kernel in (taylor.run, taylor.run_scalar))
    for x, z in zip(a, b):
        np.testing.assert_array_equal(x, z)


@pytest.mark.parametrize("tol", [1e-9, 1e-13])
def test_reference_scene_vector_against_scalar_and_scipy(tol):
    """The whole reference scene (t ∈ [0, 300], 3,001 output times): the vector and scalar steps take the same
    number of steps and agree to rounding, within 1e-12 at every output (measured 5e-14; the final errors against
    the extended-precision reference are 6.5e-8 at tol 1e-9 and 2.8e-11 at 1e-13, benchmarks/taylor_step.py).
    Over t ∈ [0, 20], both within 500 tolerances of scipy's DOP853 at rtol = atol = 1e-13 (the error/tolerance
    ratios of the Taylor method measured in auto.py span 24 to 470)."""
    scene = _reference_scene(tol)
    order, y0 = scene.integrator.order, scene.system.initial_state()
    vector = _run(taylor.run_vector, scene.compiled, order, tol, scene.times, y0)
    scalar = _run(taylor.run_scalar, scene.compiled, order, tol, scene.times, y0)
    assert vector[0] == scalar[0] == taylor.OK and vector[1] == scalar[1] == scene.times.size
    assert vector[6][1] == scalar[6][1] > 2000
    assert np.max(np.abs(vector[2] - scalar[2])) <= 1e-12
    short = scene.times[scene.times <= 20.0]
    reference = solve_ivp(scene.system.rhs, (0.0, 20.0), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                          t_eval=short).y.T
    for result in (vector, scalar):
        assert 0 < np.max(np.abs(result[2][: short.size] - reference)) <= 500 * max(tol, 1e-13)


@pytest.mark.parametrize("component", [0, 4])
def test_a_nan_state_stops_with_not_finite(component):
    """A NaN in ω or γ: the status is NOT_FINITE, no step counted, the time not advanced, and the same (NaN)
    outputs and state as the scalar path."""
    scene = _reference_scene(1e-10, end=2.0, n_output=11)
    y0 = scene.system.initial_state()
    y0[component] = np.nan
    vector = _run(taylor.run_vector, scene.compiled, 13, 1e-10, scene.times, y0)
    scalar = _run(taylor.run_scalar, scene.compiled, 13, 1e-10, scene.times, y0)
    assert vector[0] == scalar[0] == taylor.NOT_FINITE
    assert vector[1] == scalar[1] and vector[4] == scalar[4] == 0.0 and vector[6][1] == scalar[6][1] == 0
    assert np.isnan(vector[3][component]) and np.isnan(vector[2][1]).all()
    np.testing.assert_array_equal(vector[2], scalar[2])
    np.testing.assert_array_equal(vector[3], scalar[3])


def test_a_step_below_the_spacing_of_times_stops_with_too_small_step():
    """tol = 1e-300 at t = 1 (spacing 2.2e-16, a step of ~1e-100): TOO_SMALL_STEP, nothing advanced, the state
    and its Kahan carry untouched (``test_compiled`` checks the integrator's sentence)."""
    scene = _reference_scene(1e-10, end=2.0, n_output=3)
    y0 = scene.system.initial_state()
    t_out = np.array([1.0, 1.5, 2.0])
    code, reached, out, y, t, carry, stats = _run(taylor.run_vector, scene.compiled, 4, 1e-300, t_out, y0)
    assert (code, reached, t, stats[0], stats[1]) == (taylor.TOO_SMALL_STEP, 1, 1.0, 1, 0)
    np.testing.assert_array_equal(y, y0)
    assert not carry.any() and (out[1:] == -1.0).all()
