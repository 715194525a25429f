"""The Taylor step (``taylor.run``) on the fixed point's generated series, against independent computations."""

import math

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.kernels import models, taylor, taylor_series

EXTENDED = np.longdouble


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


def _random_scene(rng):
    """A fixed point with random inertia, gravity and Newtonian centre (the built-in torques, traced into the
    generated series) and a random unit γ; its packed parameters for the extended-precision oracle."""
    a, b = rng.uniform(0.6, 1.6, 2)
    scene = compose_scene(["experiment=perf_reference", f"body.a={a}", f"body.b={b}",
                           f"initial.p0={rng.uniform(-1, 1)}",
                           f"initial.q0={rng.uniform(-1, 1)}", f"initial.r0={rng.uniform(-3, 3)}"])
    return scene.compiled, scene.compiled.built_in, scene.system.initial_state()


def test_generated_coefficients_equal_extended_precision_cauchy_products():
    """Random scenes, orders 4..30: per order k, the generated series within 2e-15 (k + 1) of the row's max of the
    extended-precision Cauchy products (measured: at most ~3e-16 (k + 1))."""
    import numba

    @numba.njit
    def series(p, y, order):
        T = np.zeros((order + 1, y.size))
        T[0] = y
        models.taylor_coefficients(p, T, order)
        return T

    rng = np.random.default_rng(7)
    for _ in range(5):
        compiled, packed, y = _random_scene(rng)
        assert taylor_series.ready(compiled)
        for order in (4, 9, 17, 30):
            got = series(compiled.params, y, order)
            exact = _extended_coefficients(packed, y, order)
            bound = 2e-15 * (np.arange(order + 1) + 1)[:, None] * np.abs(exact).max(axis=1, keepdims=True)
            assert np.all(np.abs(got - exact.astype(float)) <= bound.astype(float)), order
            assert np.array_equal(got[0], y)


def _reference_scene(tol, end=300.0, n_output=3001):
    return compose_scene(["experiment=perf_reference", "integrator=taylor", f"integrator.tol={tol}",
                          f"time.end={end}", f"time.n_output={n_output}"])


def _run(compiled, order, tol, t_out, y0):
    out = np.full((t_out.size, y0.size), -1.0)
    out[0] = y0
    y, state, carry, stats = y0.copy(), np.array([t_out[0]]), np.zeros(y0.size), np.zeros(2, dtype=np.int64)
    assert taylor_series.ready(compiled)
    code, reached = taylor.run(compiled.params, order, tol, t_out, out, 1, t_out.size, state,
                               y, carry, stats)
    return code, reached, out, y, state[0], carry, stats


@pytest.mark.parametrize("tol", [1e-9, 1e-13])
def test_reference_scene_against_scipy(tol):
    """The whole reference scene (t ∈ [0, 300], 3,001 output times) fills every output; over t ∈ [0, 20] it is
    within 500 tolerances of scipy's DOP853 at rtol = atol = 1e-13 (the error/tolerance ratios of the Taylor method
    measured in auto.py span 24 to 470)."""
    scene = _reference_scene(tol)
    order, y0 = scene.integrator.order, scene.system.initial_state()
    result = _run(scene.compiled, order, tol, scene.times, y0)
    assert result[0] == taylor.OK and result[1] == scene.times.size and result[6][1] > 1000  # many chunks' worth
    short = scene.times[scene.times <= 20.0]
    reference = solve_ivp(scene.system.rhs, (0.0, 20.0), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                          t_eval=short).y.T
    assert 0 < np.max(np.abs(result[2][: short.size] - reference)) <= 500 * max(tol, 1e-13)


@pytest.mark.parametrize("component", [0, 4])
def test_a_nan_state_stops_with_not_finite(component):
    """A NaN in ω or γ: the status is NOT_FINITE, no step counted, the time not advanced, NaN outputs."""
    scene = _reference_scene(1e-10, end=2.0, n_output=11)
    y0 = scene.system.initial_state()
    y0[component] = np.nan
    code, reached, out, y, t, carry, stats = _run(scene.compiled, 13, 1e-10, scene.times, y0)
    assert (code, t, stats[1]) == (taylor.NOT_FINITE, 0.0, 0)
    assert np.isnan(y[component]) and np.isnan(out[1:reached]).all()


def test_a_step_below_the_spacing_of_times_stops_with_too_small_step():
    """tol = 1e-300 at t = 1 (spacing 2.2e-16, a step of ~1e-100): TOO_SMALL_STEP, nothing advanced, the state
    and its Kahan carry untouched (``test_compiled`` checks the integrator's sentence)."""
    scene = _reference_scene(1e-10, end=2.0, n_output=3)
    y0 = scene.system.initial_state()
    t_out = np.array([1.0, 1.5, 2.0])
    code, reached, out, y, t, carry, stats = _run(scene.compiled, 4, 1e-300, t_out, y0)
    assert (code, reached, t, stats[0], stats[1]) == (taylor.TOO_SMALL_STEP, 1, 1.0, 1, 0)
    np.testing.assert_array_equal(y, y0)
    assert not carry.any() and (out[1:] == -1.0).all()


@numba.njit
def _sums_through_the_step(T, order, h, y, carry, Y):
    """taylor's dense output into Y[0] at h, into Y[1] and Y[2] at (h/3, h/2) (a pair), and its compensated update of
    y, on coefficients in its own padded rows."""
    rows = taylor._coefficient_rows(T.shape[0], T.shape[1])
    rows[:] = T
    taylor._dense_output(rows, order, (h,), y, carry, Y, 0)
    taylor._dense_output(rows, order, (h / 3, h / 2), y, carry, Y, 1)
    return taylor._advance(rows, order, h, y, carry)


@pytest.mark.parametrize("n", [1, 6, 8, 9, 16, 17, 40])
@pytest.mark.parametrize("order", [4, 9, 23])
def test_the_vector_horner_sums_match_numpy_for_every_state_size(n, order):
    """The step's Horner sums run in vector lanes, sixteen components at a time (past a row's end), the outputs one
    or two at a time: every component of any state size gets y + Σ_k T[k] h^k, against numpy's polynomial
    evaluation of each component, and the masked stores write nothing past the components they fill (row 3 and the
    columns past the state's size, in an output array wider than the state, stay NaN)."""
    rng = np.random.default_rng(n * 100 + order)
    T = rng.normal(size=(order + 1, n)) / np.arange(1, order + 2)[:, None] ** 2
    y, carry, h = T[0].copy(), rng.normal(scale=1e-17, size=n), 0.37
    Y = np.full((4, n + 3), np.nan)
    expected = np.array([[np.polyval(T[::-1, m], x) for m in range(n)] for x in (h, h / 3, h / 2)])
    assert _sums_through_the_step(T, order, h, y, carry.copy(), Y)
    np.testing.assert_allclose(Y[:3, :n], expected - carry, rtol=1e-14, atol=1e-15)
    assert np.isnan(Y[3]).all() and np.isnan(Y[:, n:]).all()
    np.testing.assert_allclose(y, expected[0] - carry, rtol=1e-14, atol=1e-15)
    T[order, n - 1] = np.inf
    assert not _sums_through_the_step(T, order, h, T[0].copy(), carry.copy(), Y)


@pytest.mark.parametrize("overhead", [0.0, 16.0, taylor.STEP_OVERHEAD, 200.0])
def test_the_order_rule_takes_the_least_work_per_unit_time(overhead):
    """``order_for``: with no step overhead Jorba & Zou's ⌈−ln(tol)/2 + 1⌉ (their paper, §3.2); with one, the
    real p minimising (overhead + p²)·tol^(−1/p) found by brute force over a fine grid, rounded up the same way."""
    grid = np.linspace(0.5, 80.0, 400_001)
    for tol in np.logspace(-1, -32, 63):
        if overhead == 0.0:
            expected = math.ceil(-math.log(tol) / 2.0 + 1.0)
        else:
            work = (overhead + grid ** 2) * np.exp(-math.log(tol) / grid)
            expected = math.ceil(grid[np.argmin(work)] + 1.0)
        assert taylor.order_for(tol, overhead) == min(taylor.MAX_ORDER, max(taylor.MIN_ORDER, expected)), tol
