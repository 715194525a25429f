"""``integrator=taylor integrator.precision=double-double``: the arithmetic, the kernel, the plugin.

Every expected number is independent of the code under test: the double-double primitives against exact
rational arithmetic (``fractions.Fraction``); the kernel against a Taylor series integrator written here in
Python's ``decimal`` at 50 digits (vector cross products, steps landing on the output times: no code shared
with the compiled kernels); and against physics: energy, the area integral and |γ| conserved over a long run,
evaluated exactly (``Fraction``) from the double-double states.
"""

from __future__ import annotations

import decimal
import math
from decimal import Decimal
from fractions import Fraction

import numba
import numpy as np
import pytest

from gyrolab.contracts import CompiledModel
from gyrolab.engine.scene import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.kernels import double_double as dd, taylor, taylor_dd
from gyrolab.kernels.layout import (
    CARRIES_ALPHA, GAMMA, GRADIENT, INERTIA, INV_INERTIA, LINEAR, N_PARAMS, N_X, N_Y, N_Z, OMEGA, U_X, U_Y, U_Z,
)
from gyrolab.plugins.integrators.compiled_solvers import Taylor, _ready_for_double_double
from tests.helpers import VISCOUS_DRAG

U2 = Fraction(1, 2 ** 104)  # "a unit of 2^-104": double-double's unit round-off is 2^-106
RNG = np.random.default_rng(20261126)


# --- the primitives ---------------------------------------------------------------------------------------------

@numba.njit
def _apply(op, A):
    """Row i of A (a, b, c, d) through primitive ``op`` (a compile-time constant), the results as rows."""
    out = np.empty((A.shape[0], 2))
    for i in range(A.shape[0]):
        a, b, c, d = A[i, 0], A[i, 1], A[i, 2], A[i, 3]
        if op == 0:
            r = dd.two_sum(a, b)
        elif op == 1:
            r = dd.quick_two_sum(a, b)
        elif op == 2:
            r = dd.two_prod(a, b)
        elif op == 4:
            r = dd.dd_add(a, b, c, d)
        elif op == 6:
            r = dd.dd_mul(a, b, c, d)
        elif op == 7:
            r = dd.dd_mul_d(a, b, c)
        elif op == 8:
            r = dd.dd_div_d(a, b, c)
        else:
            r = dd.dd_add_d(a, b, c)
        out[i, 0], out[i, 1] = r
    return out


def _doubles(n, spread=30):
    """Random doubles with random signs and exponents over ±spread binary orders."""
    return RNG.choice([-1.0, 1.0], n) * RNG.uniform(1, 2, n) * 2.0 ** RNG.integers(-spread, spread, n)


def _dd_numbers(n):
    """Random normalised double-doubles (hi, lo): lo a random fraction of hi's half ulp."""
    hi = _doubles(n)
    lo = np.spacing(np.abs(hi)) * RNG.uniform(-0.5, 0.5, n)
    return hi, lo


def _exact(hi, lo):
    return Fraction(float(hi)) + Fraction(float(lo))


def _assert_normalised(out):
    assert np.all(out[:, 0] + out[:, 1] == out[:, 0]), "a result's low part exceeds half an ulp of its high part"


def test_error_free_transformations_are_exact():
    a, b = _doubles(2000), _doubles(2000)
    z = np.zeros_like(a)
    big, small = np.where(np.abs(a) >= np.abs(b), a, b), np.where(np.abs(a) >= np.abs(b), b, a)
    cases = {0: (a, b), 1: (big, small)}
    for op, (x, y) in cases.items():
        out = _apply(op, np.column_stack([x, y, z, z]))
        assert all(_exact(*r) == Fraction(u) + Fraction(v) for r, u, v in zip(out, x, y))
        assert np.all(out[:, 0] == x + y)
    out = _apply(2, np.column_stack([a, b, z, z]))  # two_prod, by the fused multiply-add
    assert all(_exact(*r) == Fraction(u) * Fraction(v) for r, u, v in zip(out, a, b))
    assert np.all(out[:, 0] == a * b)


def _relative_errors(out, exact):
    return [abs(_exact(*r) - e) / abs(e) for r, e in zip(out, exact) if e != 0]


def test_double_double_operations_round_to_one_unit_of_2_to_the_minus_104():
    n = 2000
    ah, al = _dd_numbers(n)
    bh, bl = _dd_numbers(n)
    # additions also with heavy cancellation: b = −a (1 + δ), δ ~ 1e-10
    ch = -ah * (1 + RNG.uniform(-1e-10, 1e-10, n))
    ch_l = np.spacing(np.abs(ch)) * RNG.uniform(-0.5, 0.5, n)
    a = [_exact(h, l) for h, l in zip(ah, al)]
    b = [_exact(h, l) for h, l in zip(bh, bl)]
    c = [_exact(h, l) for h, l in zip(ch, ch_l)]
    bounds = {}
    for name, op, args, exact in [
        ("dd_add", 4, (ah, al, bh, bl), [x + y for x, y in zip(a, b)]),
        ("dd_add, cancelling", 4, (ah, al, ch, ch_l), [x + y for x, y in zip(a, c)]),
        ("dd_mul", 6, (ah, al, bh, bl), [x * y for x, y in zip(a, b)]),
        ("dd_mul_d", 7, (ah, al, bh, bh), [x * Fraction(y) for x, y in zip(a, bh)]),
        ("dd_div_d", 8, (ah, al, bh, bh), [x / Fraction(y) for x, y in zip(a, bh)]),
        ("dd_add_d", 9, (ah, al, bh, bh), [x + Fraction(y) for x, y in zip(a, bh)]),
    ]:
        out = _apply(op, np.column_stack(args))
        _assert_normalised(out)
        bounds[name] = max(_relative_errors(out, exact)) / U2
    assert all(bound <= 1 for bound in bounds.values()), bounds  # measured ≤ 0.62 (2.5 u²)


@numba.njit
def _dot(A, B):
    sh = sl = 0.0
    for i in range(A.shape[0]):
        sh, sl = dd.dot_add(sh, sl, A[i, 0], A[i, 1], B[i, 0], B[i, 1])
    return dd.dd_norm(sh, sl)


def test_compensated_dot_product_errs_by_u_squared_times_the_sum_of_the_terms():
    for _ in range(20):
        n = 40
        ah, al = _dd_numbers(n)
        bh, bl = _dd_numbers(n)
        hi, lo = _dot(np.column_stack([ah, al]), np.column_stack([bh, bl]))
        terms = [_exact(*x) * _exact(*y) for x, y in zip(zip(ah, al), zip(bh, bl))]
        assert hi + lo == hi
        assert abs(_exact(hi, lo) - sum(terms)) <= n * U2 * sum(abs(t) for t in terms)


# --- an independent reference: Taylor series in decimal arithmetic ---------------------------------------------

DIGITS = 50


def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _add(*vs):
    return tuple(sum(c, Decimal(0)) for c in zip(*vs))


def _scale(s, v):
    return tuple(s * x for x in v)


def _cauchy(f, A, B, k):
    """Σ_j f(A_j, B_{k−j})."""
    return _add(*(f(A[j], B[k - j]) for j in range(k + 1)))


def decimal_reference(p, y0, t_out, *, order=44, tol=Decimal("1e-42")):
    """The states at t_out of I ω̇ = Iω × ω + Σ_i U_i × e_i + Σ_i N_i e_i × I e_i (e_0 = α, e_1 = β = γ × α,
    e_2 = γ), γ̇ = γ × ω, α̇ = α × ω, by a Taylor series method in ``decimal`` with DIGITS digits; steps are
    clipped to land on every output time. The parameters are read from the double array p (exact in decimal)."""
    with decimal.localcontext() as ctx:
        ctx.prec = DIGITS
        D = lambda x: Decimal(float(x))  # noqa: E731  (exact: a double's decimal expansion)
        inertia = tuple(D(p[INERTIA + k]) for k in range(3))
        U = [tuple(D(p[LINEAR[i] + c]) for c in range(3)) for i in range(3)]
        N = [D(p[GRADIENT[i]]) for i in range(3)]
        alpha = len(y0) == 9
        I_ = lambda v: tuple(i * x for i, x in zip(inertia, v))  # noqa: E731
        y = [D(x) for x in y0]
        t = Fraction(float(t_out[0]))
        out = [list(y0)]
        for t_next in t_out[1:]:
            t_next = Fraction(float(t_next))
            while t < t_next:
                W, G, A, B = [tuple(y[0:3])], [tuple(y[3:6])], [tuple(y[6:9])] if alpha else [], []
                for k in range(order):
                    torque = [_cauchy(lambda a, b: _cross(I_(a), b), W, W, k), _cross(U[2], G[k]),
                              _scale(N[2], _cauchy(lambda a, b: _cross(a, I_(b)), G, G, k))]
                    if alpha:
                        B.append(_cauchy(_cross, G, A, k))
                        torque += [_cross(U[0], A[k]), _cross(U[1], B[k]),
                                   _scale(N[0], _cauchy(lambda a, b: _cross(a, I_(b)), A, A, k)),
                                   _scale(N[1], _cauchy(lambda a, b: _cross(a, I_(b)), B, B, k))]
                        A.append(_scale(Decimal(1) / (k + 1), _cauchy(_cross, A, W, k)))
                    W.append(tuple(x / i / (k + 1) for x, i in zip(_add(*torque), inertia)))
                    G.append(_scale(Decimal(1) / (k + 1), _cauchy(_cross, G, W, k)))
                rows = list(zip(W, G, A)) if alpha else list(zip(W, G))
                norm = lambda k: max(abs(x) for v in rows[k] for x in v)  # noqa: E731
                h = min(float((tol / norm(k)) ** (Decimal(1) / k)) for k in (order - 1, order) if norm(k) > 0)
                step = min(Fraction(h), t_next - t)
                hd = Decimal(step.numerator) / Decimal(step.denominator)
                y = []
                for series in zip(*rows):  # ω, γ[, α]: Horner
                    for c in range(3):
                        v = Decimal(0)
                        for k in range(order, -1, -1):
                            v = v * hd + series[k][c]
                        y.append(v)
                t += step
            out.append(list(y))
        return out


@pytest.fixture(scope="module")
def chaotic():
    """The chaotic top (the default body and forces, initial=slow_spin), state (ω, γ)."""
    from gyrolab.kernels import series_dd

    scene = compose_scene(["initial=slow_spin", "output.euler_angles=false", "integrator=taylor",
                           "integrator.precision=double-double"])
    series_dd.ready(scene.compiled)
    return scene.compiled, scene.system.initial_state()


@pytest.fixture(scope="module")
def reference(chaotic):
    compiled, y0 = chaotic
    t_out = np.array([0.0, 20.0, 40.0, 60.0])
    return t_out, decimal_reference(compiled.built_in, y0, t_out)


def _errors(hi, lo, exact):
    """max-norm errors per row of (hi + lo) against decimal rows, exactly."""
    return [float(max(abs(Fraction(float(h)) + Fraction(float(l)) - Fraction(e)) for h, l, e in zip(rh, rl, re)))
            for rh, rl, re in zip(hi, lo, exact)]


def test_double_double_taylor_matches_a_50_digit_reference_where_double_precision_cannot(chaotic, reference):
    compiled, y0 = chaotic
    t_out, exact = reference
    hi, lo = taylor_dd.propagate(compiled.params, 1e-30, t_out, y0)
    errors = _errors(hi, lo, exact)
    assert max(errors) < 1e-29, errors  # measured 6e-31 at t = 60
    # the dataset's doubles: the double-double state rounded, within half an ulp of the truth (and a little)
    stored = _errors(hi, np.zeros_like(lo), exact)
    assert max(stored) < 2e-16
    # double precision on the same scene: its error has grown orders of magnitude above round-off
    double = Taylor(tol=1e-16).integrate(None, t_out, y0, None, compiled).y
    double_errors = _errors(double, np.zeros_like(double), exact)
    assert double_errors[-1] > 1e12 * errors[-1]  # measured 2e-15
    # and double-double's error follows its tolerance (Jorba & Zou's step: error ∝ tol)
    coarse = _errors(*taylor_dd.propagate(compiled.params, 1e-24, t_out, y0), exact)
    assert 1e-28 < coarse[-1] < 1e-21


def test_the_traced_equations_match_the_50_digit_reference_too(reference):
    """The same scene's equations traced from the system's numpy ``euler_poisson`` run the generated series
    (``series_dd``: products merged, numbers factored out of them) to the same accuracy."""
    from gyrolab.plugins.systems.fixed_point import traced_model

    system = compose_scene(["initial=slow_spin", "output.euler_angles=false"]).system
    traced = traced_model(system.inertia, system.forces, False)
    _ready_for_double_double(traced)
    t_out, exact = reference
    errors = _errors(*taylor_dd.propagate(traced.params, 1e-30, t_out, system.initial_state()),
                     exact)
    assert max(errors) < 1e-29, errors  # measured 3.5e-31 at t = 60


def _traced_packed_equations(p):
    """The equations ``decimal_reference`` integrates, written in numpy from the packed parameters p and compiled
    from their trace (a state with α runs the traced form: ``series_dd``)."""
    from gyrolab.kernels import model, series_dd
    from gyrolab.physics.vectors import cross

    inertia = p[INERTIA:INERTIA + 3]
    U = [p[LINEAR[i]:LINEAR[i] + 3] for i in range(3)]
    N = [p[GRADIENT[i]] for i in range(3)]

    def equations(t, y):
        w, g, a = y[0:3], y[3:6], y[6:9]
        b = cross(g, a)
        torque = cross(inertia * w, w)
        for e, u, n in zip((a, b, g), U, N):
            torque = torque + cross(u, e) + n * cross(e, inertia * e)
        return np.concatenate([torque / inertia, cross(g, w), cross(a, w)])

    compiled = model.compile(model.trace(equations, 9, "the packed fixed-point equations with α"))
    assert series_dd.ready(compiled)
    return compiled


def test_the_form_with_alpha_and_every_torque_term_matches_the_decimal_reference():
    p = np.zeros(N_PARAMS)
    p[INERTIA:INERTIA + 3] = (2.0, 1.5, 1.0)
    p[U_X:U_X + 3] = (0.05, -0.02, 0.1)
    p[U_Y:U_Y + 3] = (-0.03, 0.04, 0.07)
    p[U_Z:U_Z + 3] = (0.3, 0.2, 0.9327379053088815)
    p[N_X], p[N_Y], p[N_Z] = 0.2, -0.15, 0.5
    p[CARRIES_ALPHA] = 1.0
    p[INV_INERTIA:INV_INERTIA + 3] = 1.0 / p[INERTIA:INERTIA + 3]
    gamma = np.array([math.sin(1.0), 0.0, math.cos(1.0)])
    alpha = np.array([math.cos(1.0), 0.0, -math.sin(1.0)])
    y0 = np.concatenate([[0.3, -0.2, 1.1], gamma, alpha])
    t_out = np.array([0.0, 1.5, 3.0])
    traced = _traced_packed_equations(p)
    hi, lo = taylor_dd.propagate(traced.params, 1e-30, t_out, y0)
    errors = _errors(hi, lo, decimal_reference(p, y0, t_out, order=40, tol=Decimal("1e-40")))
    assert max(errors) < 1e-30, errors  # measured 2e-32 (hand-written α form), 2.7e-32 (traced)


# --- physics: first integrals over a long run -------------------------------------------------------------------

def _invariants(p, hi, lo):
    """Energy ½ ω·Iω − U_2·γ + ½ N_2 γ·Iγ, area integral Iω·γ and |γ|² of each row, exactly (Fractions), with the
    magnitude of the energy's largest term (its scale)."""
    F = lambda x: Fraction(float(x))  # noqa: E731
    inertia = [F(p[INERTIA + k]) for k in range(3)]
    u, n = [F(p[U_Z + k]) for k in range(3)], F(p[N_Z])
    rows = []
    for rh, rl in zip(hi, lo):
        y = [F(h) + F(l) for h, l in zip(rh, rl)]
        w, g = y[OMEGA:OMEGA + 3], y[GAMMA:GAMMA + 3]
        kinetic = sum(i * x * x for i, x in zip(inertia, w)) / 2
        potential = -sum(a * b for a, b in zip(u, g))
        newton = n * sum(i * x * x for i, x in zip(inertia, g)) / 2
        rows.append((kinetic + potential + newton, sum(i * a * b for i, a, b in zip(inertia, w, g)),
                     sum(x * x for x in g), max(abs(kinetic), abs(potential), abs(newton))))
    return rows


def test_energy_area_integral_and_gamma_norm_are_conserved_to_1e_28_over_a_long_run(chaotic):
    compiled, y0 = chaotic
    p = compiled.built_in
    t_out = np.linspace(0.0, 1000.0, 41)
    hi, lo = taylor_dd.propagate(compiled.params, 1e-30, t_out, y0)
    rows = _invariants(p, hi, lo)
    energy0, area0, norm0, scale = rows[0]
    drift = [(abs(e - energy0) / scale, abs(a - area0), abs(g - norm0)) for e, a, g, _ in rows]
    worst = [float(max(d[i] for d in drift)) for i in range(3)]
    assert max(worst) < 1e-28, worst  # measured ~2e-31 over t = 1000 (~3,000 steps)
    # in double precision the same run drifts by round-off: ~1e-16 … 1e-15
    double = Taylor(tol=1e-16).integrate(None, t_out, y0, None, compiled).y
    e_double = [float(abs(e - energy0) / scale) for e, *_ in _invariants(p, double, np.zeros_like(double))]
    assert max(e_double) > 1e10 * worst[0]


# --- the integrator plugin --------------------------------------------------------------------------------------

def test_precision_is_checked_and_recorded():
    with pytest.raises(ConfigError, match=r"^integrator.precision='quad' is not available; valid choices: double, "
                                          r"double-double$"):
        Taylor(precision="quad")
    with pytest.raises(ConfigError, match="at least 1e-32"):
        Taylor(precision="double-double", tol=1e-33)
    assert Taylor(tol=1e-20).tol == 1e-20  # double precision keeps accepting any positive tolerance
    taylor = Taylor(precision="double-double", tol=1e-30)
    assert taylor.order == 36 and taylor.attributes() == {
        "integrator_order": 36, "integrator_tol": 1e-30, "integrator_precision": "double-double"}
    assert Taylor().attributes()["integrator_precision"] == "double"


def test_a_scene_in_double_double_runs_with_alpha_and_every_builtin_force_and_reports_progress(chaotic):
    overrides = ["initial=slow_spin", "force=[uniform_gravity,newtonian,magnetic]", "force.magnetic.field=0.3",
                 "force.magnetic.direction=[0.6,0.0,0.8]", "time.end=30", "time.n_output=301",
                 "integrator=taylor", "output.figures=false"]
    dd_scene = compose_scene([*overrides, "integrator.precision=double-double", "integrator.tol=1e-28"])
    assert dd_scene.system.state_size == 9
    seen = []
    solution = dd_scene.integrator.integrate(dd_scene.system.rhs, dd_scene.times, dd_scene.system.initial_state(),
                                             seen.append, dd_scene.compiled)
    assert seen and seen[-1] == 30.0 and solution.y.dtype == np.float64
    # the reference for the α form: the same kernel's all digits agree with the stored doubles, and the double
    # kernel agrees to its own round-off
    hi, lo = taylor_dd.propagate(dd_scene.compiled.params, 1e-28, dd_scene.times, dd_scene.system.initial_state())
    np.testing.assert_array_equal(solution.y, hi)
    double = compose_scene([*overrides, "integrator.tol=1e-16"])
    np.testing.assert_allclose(double.run().omega.values, solution.y[:, :3], rtol=0, atol=1e-12)
    ds = dd_scene.run()
    assert ds.attrs["integrator_precision"] == "double-double" and ds.omega.dtype == np.float64
    assert ds.gamma_norm.attrs["max_abs_drift"] < 1e-15


@numba.njit
def _generated_series(address, t, order, Th, Tl, S, p):
    taylor._call_dd_series(address, t, order, Th, Tl, S, p)


def test_the_generated_series_of_products_quotients_powers_and_time_are_exact_to_double_double():
    """``series_dd``'s operations against exact rational series (``Fraction``) at t0 = 1/2: y0' = y0² (a product of
    a series with itself: y0 = a/(1 − a s), s = t − t0), y1' = 1/y1 (a quotient of series: y1 = √(9/4 + 2s)), and
    y2' = 1/(2 − t) + (1 + t)⁻² − 3(2 + t)t + (3t + 7)t (numbers over and times series, a negative power, equal
    products merged: the last two terms are t)."""
    from gyrolab.kernels import model, series_dd

    def equations(t, y):
        return np.array([y[0] * y[0], 1.0 / y[1],
                         1.0 / (2.0 - t) + (1.0 + t) ** -2 - 3.0 * (2.0 + t) * t + (t * 3.0 + 7.0) * t])

    compiled = model.compile(model.trace(equations, 3, "rational functions of time and state"))
    assert series_dd.ready(compiled)
    order, a = 24, 0.3
    p = compiled.params
    Th, Tl = np.zeros((order + 1, 3)), np.zeros((order + 1, 3))
    Th[0] = (a, 1.5, 0.0)
    _generated_series(int(p[-2]), 0.5, order, Th, Tl, np.zeros((order + 1) * 2 * int(p[-1])), p)
    half = Fraction(1, 2)
    binomial = [Fraction(1)]
    for k in range(1, order + 1):
        binomial.append(binomial[-1] * (half - k + 1) / k)
    c = Fraction(3, 2)
    rate = [1 / c ** (k + 1) + (k + 1) * (-1) ** k / c ** (k + 2) + (half if k == 0 else 1 if k == 1 else 0)
            for k in range(order)]
    exact = [[Fraction(a) ** (k + 1), c * binomial[k] * (Fraction(8, 9)) ** k, rate[k - 1] / k if k else 0]
             for k in range(order + 1)]
    errors = [abs(Fraction(float(Th[k, m])) + Fraction(float(Tl[k, m])) - exact[k][m]) / abs(exact[k][m])
              for k in range(1, order + 1) for m in range(3)]
    assert max(errors) < 1e-30, float(max(errors))  # measured 1.7e-31


def test_a_traced_plugin_torque_runs_in_double_double_and_a_transcendental_one_is_refused_naming_it():
    """The double-double series is generated from the traced equations (``series_dd``): a rational torque runs
    (same trajectory as double precision, to its accuracy); a function of the state without a double-double series
    here is refused in one sentence naming it."""
    from gyrolab.contracts import Force
    from gyrolab.plugins.systems.fixed_point import traced_model

    class Drag(Force):
        name = "my_drag"
        required_axes = frozenset()
        preserves_area_integral = False

        def torque(self, omega, axes):
            return -0.1 * omega * (1.0 + omega[2] ** 2)

    class Wobble(Drag):
        name = "my_wobble"

        def torque(self, omega, axes):
            return -0.1 * np.sin(omega)

    inertia, y0 = np.array([2.0, 1.5, 1.0]), np.array([0.3, -0.2, 2.0, 0.0, 0.6, 0.8])
    t_out = np.linspace(0.0, 5.0, 11)
    drag = traced_model(inertia, [Drag()], False)
    dd = Taylor(precision="double-double", tol=1e-28)
    assert dd.refusal(drag) is None
    np.testing.assert_allclose(dd.integrate(None, t_out, y0, None, drag).y,
                               Taylor(tol=1e-16).integrate(None, t_out, y0, None, drag).y, rtol=0, atol=1e-13)
    wobble = traced_model(inertia, [Wobble()], False)
    clause = dd.refusal(wobble)
    assert clause.startswith("in double-double precision cannot run this model: ") and "'sin'" in clause
    with pytest.raises(ConfigError, match=r"^integrator 'taylor' in double-double precision cannot run .*'sin'"):
        dd.integrate(None, t_out, y0, None, wobble)


def test_capabilities_batch_points_and_the_error_estimates_companion():
    from gyrolab.batch.integrate import integrate_arrays, integrate_batch
    from gyrolab.contracts.integrator import BATCH_KERNEL, COMPILED_MODEL, TIME_DEPENDENT
    from gyrolab.plugins.integrators.compiled_solvers import TaylorDoubleDouble

    taylor = Taylor(precision="double-double", tol=1e-24)
    assert isinstance(taylor, TaylorDoubleDouble) and type(Taylor()) is Taylor and taylor.name == "taylor"
    assert taylor.supports(COMPILED_MODEL) and not taylor.supports(BATCH_KERNEL)
    assert taylor.supports(TIME_DEPENDENT) and Taylor().supports(BATCH_KERNEL)
    # the error estimate's companion stays in double-double, 1000x tighter, down to the floor
    companion, factor, _ = taylor.more_accurate(1000.0)
    assert (type(companion), companion.order, factor) == (TaylorDoubleDouble, taylor.order, 1.0)
    assert companion.tol == pytest.approx(1e-27, rel=1e-12)
    assert Taylor(precision="double-double", tol=1e-30).more_accurate(1000.0) is None
    # --batch: one integrate() per point, each exactly a single run (no double-precision batch kernel)
    scene = compose_scene(["initial=slow_spin", "output.euler_angles=false", "time.end=20", "time.n_output=21",
                           "integrator=taylor", "integrator.precision=double-double", "integrator.tol=1e-24"])
    y0s = np.array([scene.system.initial_state(), scene.system.initial_state() * [1.01, 1, 1, 1, 1, 1]])
    batch = integrate_batch(scene, y0s)
    for j in range(2):
        single = scene.integrator.integrate(None, scene.times, y0s[j], None, scene.compiled).y
        np.testing.assert_array_equal(batch.y[j], single)
    with pytest.raises(ConfigError, match="not taylor"):
        integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)


def test_a_parameter_array_of_no_traced_model_is_refused_in_one_sentence(chaotic):
    model, y0 = chaotic
    with pytest.raises(ConfigError, match="names no traced model"):
        Taylor(precision="double-double", tol=1e-26).integrate(None, np.linspace(0.0, 1.0, 3), y0, None,
                                                               CompiledModel(model.built_in))


def test_a_plugin_torque_runs_in_double_double_from_the_scene(tmp_path):
    """The viscous-drag example (a linear torque) in double-double from a scene: its series generated from the
    traced equations; the trajectory is the double-precision one to that precision's accuracy, and the energy it
    dissipates follows dE/dt = −c |ω|² (a law: E(t) − E(0) = −c ∫ |ω|² dt, checked by the trapezoid rule)."""

    from tests.conftest import installed_distribution

    common = ["force=[uniform_gravity,viscous_drag]", "integrator=taylor", "time.end=5", "time.n_output=2001",
              "output.figures=false"]
    with installed_distribution(tmp_path, "gyrolab-viscous-drag", "0.1",
                                {"viscous_drag": "gyrolab_viscous_drag:ViscousDrag"}, paths=[VISCOUS_DRAG]):
        dd = compose_scene([*common, "integrator.precision=double-double", "integrator.tol=1e-28"]).run()
        double = compose_scene(common).run()
    np.testing.assert_allclose(dd.omega, double.omega, rtol=0, atol=1e-12)
    scene = compose_scene(["force=[uniform_gravity]"])  # the same body: kinetic + gravity potential
    energy = scene.system.invariant_values(np.concatenate([dd.omega, dd.gamma, dd.alpha], axis=1))["energy"]
    c = float(dd.attrs["force_viscous_drag_coefficient"])
    power = -c * np.sum(dd.omega.values ** 2, axis=1)
    dissipated = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(dd.time.values))])
    np.testing.assert_allclose(energy - energy[0], dissipated, rtol=0, atol=1e-6)


def test_the_batch_plan_asks_the_double_double_class_for_capabilities():
    from gyrolab.batch.plan import Plan
    from gyrolab.batch.runner import path_attributes
    from gyrolab.plugins.integrators.compiled_solvers import TaylorDoubleDouble

    for precision, cls in (("double", Taylor), ("double-double", TaylorDoubleDouble)):
        plan = Plan.__new__(Plan)
        plan.plain = {"integrator": {"_target_": "gyrolab.plugins.integrators.compiled_solvers.Taylor", "order": None,
                                     "tol": 1e-20, "precision": precision}}
        assert plan.integrator_class is cls
    from types import SimpleNamespace

    assert path_attributes(TaylorDoubleDouble, SimpleNamespace(output="final")) == {
        "batch_path": "one integrate() call per point"}


def test_a_model_whose_double_double_series_was_never_compiled_stops_instead_of_crashing():
    """``taylor_dd.propagate`` on the parameters of a model ``series_dd.ready`` never saw: the kernel reads the series'
    address as 0 and stops with a status (it called address 0 before, a segmentation fault)."""
    system = compose_scene(["experiment=gyrostat"]).system
    params = system.compiled_model().params.copy()
    params[-2:] = 0.0  # (layout: the double-double series' address and scratch columns, 0 until ready)
    with pytest.raises(RuntimeError, match="stopped near t=0 "):
        taylor_dd.propagate(params, 1e-26, np.linspace(0.0, 1.0, 3), system.initial_state())


def test_a_double_double_head_reaches_the_50_digit_reference_where_double_precision_cannot(chaotic, reference):
    """``Taylor(head=...)`` (the error estimate's companion near double precision's floor): the series' first ``head``
    orders and the state's update in double-double, the rest in double. Its round-off is that of the terms beyond the
    head, so on the chaotic scene it ends within an ulp of the state of the 50-digit reference where double Taylor
    ends ~two orders of magnitude farther; the one pass measures it as it measures a double run."""
    from gyrolab.accuracy.calibration import HEAD_ORDERS

    compiled, y0 = chaotic
    t_out, exact = reference
    ulp = float(np.spacing(np.max(np.abs(y0))))
    run = Taylor(tol=1e-18, head=HEAD_ORDERS)
    assert run.attributes()["integrator_double_double_head"] == HEAD_ORDERS and run.precision == "double"
    y = run.integrate(None, t_out, y0, None, compiled).y
    head = _errors(y, np.zeros_like(y), exact)
    assert head[-1] < ulp, head  # measured 2.5e-17 at t = 60: the output's own rounding
    double = Taylor(tol=1e-16).integrate(None, t_out, y0, None, compiled).y
    double_errors = _errors(double, np.zeros_like(double), exact)
    assert double_errors[-1] > 20 * head[-1], (double_errors, head)  # 3.2e-15
    # measured in the same pass, the steps are the same and the states within an ulp of the bare run's
    measured = run.integrate(None, t_out, y0, None, compiled, estimate=True)
    assert np.max(np.abs(measured.y - y)) <= ulp and measured.estimate.error is not None
    # the head is validated: one sentence naming the value and what is valid
    with pytest.raises(ConfigError, match=r"integrator.head=-1 must be an integer from 0 to integrator.order"):
        Taylor(tol=1e-18, head=-1)
    with pytest.raises(ConfigError, match=r"integrator.head=4 is for integrator.precision=double"):
        Taylor(tol=1e-24, precision="double-double", head=4)
