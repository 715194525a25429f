"""``taylor`` on plugin torques: Taylor coefficients propagated through the traced torque (taylor_series).

Every expected number is independent of the code under test: each operation's series, generated
for a function of time and summed, must reproduce the function itself evaluated by the math
library a step away (and the first coefficients match the textbook series at 0); trajectories are
checked against the exact solution of drag, against scipy's DOP853 on the plugin's Python torque,
and against the built-in torques' own Taylor coefficients for plugins that repeat their arithmetic.
"""

import ctypes
import math
import textwrap
from fractions import Fraction

import numpy as np
from scipy.integrate import solve_ivp
import pytest

from gyrolab.contracts import Force
from gyrolab.engine.scene import compose_scene, run
from gyrolab.kernels import expression, model as traced, taylor_series
from gyrolab.plugins.systems.fixed_point import traced_model
from gyrolab.plugins.integrators.compiled_solvers import Taylor
from tests.conftest import installed_distribution
from tests.helpers import VISCOUS_DRAG

ORDER = 24
_KERNEL = ctypes.CFUNCTYPE(None, ctypes.c_double, ctypes.c_int64, *[ctypes.POINTER(ctypes.c_double)] * 3)


class OfTime(Force):
    """Three functions of time as a 'torque' (the state is not read): their series come out of the kernel."""

    name = "of_time"
    required_axes = frozenset()
    time_dependent = True
    preserves_area_integral = False

    def __init__(self, f):
        self.f = f

    def torque(self, omega, axes, t):
        return np.array(self.f(t), dtype=object)


def series(f, t0, order=ORDER):
    """The generated kernel's coefficients 0..order of the three functions f(t) about t0 (rows).

    The kernel fills the state's series: with the functions as ω's rates, ω's coefficient k + 1 is the functions'
    coefficient k over k + 1.
    """
    m = traced.trace(lambda t, y: np.concatenate([OfTime(f).torque(None, None, t), np.zeros(3)]), 6, "of_time")
    program = taylor_series.plan(m)
    columns = taylor_series.layout(program)[1]
    module = expression.generated_module(taylor_series.source(program), "gyrolab_taylor", "of_time (Taylor)")
    address = module.kernel.address
    call = _KERNEL(int(address))
    p = np.zeros(traced.TRACED_FIRST_CONSTANT + len(m.constants) + 4)
    p[traced.TRACED_FIRST_CONSTANT:-4] = m.constants
    Y = np.zeros((order + 2, 6))
    W = np.empty((order + 1) * int(columns))
    call(t0, order + 1, *[a.ctypes.data_as(ctypes.POINTER(ctypes.c_double)) for a in (Y, W, p)])
    return Y[1:, :3] * np.arange(1, order + 2)[:, None]


def _sum(coefficients, h):
    return np.polynomial.polynomial.polyval(h, coefficients)


# (numpy form for the trace, math form for the check); every operation the tracer records appears
CASES = {
    "exp, sin, cos": (lambda t: [np.exp(np.sin(t)), np.cos(3.0 * t) - t, np.sin(t) * np.cos(t)],
                      lambda t: [math.exp(math.sin(t)), math.cos(3 * t) - t, math.sin(t) * math.cos(t)]),
    "quotients, sqrt, log": (lambda t: [1.0 / (2.0 - t), np.sqrt(1.0 + t * t) / (2.0 + np.cos(t)), np.log(2.0 + t)],
                             lambda t: [1 / (2 - t), math.sqrt(1 + t * t) / (2 + math.cos(t)), math.log(2 + t)]),
    "tan, tanh, arctan": (lambda t: [np.tan(t), np.tanh(2.0 * t) * t, np.arctan(t) - t ** 3],
                          lambda t: [math.tan(t), math.tanh(2 * t) * t, math.atan(t) - t ** 3]),
    "powers": (lambda t: [(1.0 + t) ** 0.3, 2.0 ** t + (1.5 + t) ** t, (1.0 + t) ** -2 + (2.0 - t) ** 5],
               lambda t: [(1 + t) ** 0.3, 2 ** t + (1.5 + t) ** t, (1 + t) ** -2 + (2 - t) ** 5]),
    "arctan2, abs, neg": (lambda t: [np.arctan2(np.sin(t), np.cos(t) + 2.0), abs(t - 2.0), -np.exp(-t)],
                          lambda t: [math.atan2(math.sin(t), math.cos(t) + 2), abs(t - 2), -math.exp(-t)]),
}


@pytest.mark.parametrize("case", CASES)
def test_each_operations_series_sums_to_the_function(case):
    traced, exact = CASES[case]
    t0 = 0.3
    c = series(traced, t0)
    for h in (-0.15, 0.05, 0.2):  # every function is analytic within 0.8 of t0: the tail is below 1e-15
        np.testing.assert_allclose(_sum(c, h), exact(t0 + h), rtol=0, atol=2e-14)
    np.testing.assert_allclose(c[0], exact(t0), rtol=1e-15, atol=1e-16)


def test_series_at_zero_are_the_textbook_ones():
    c = series(lambda t: [np.tan(t), np.tanh(t), np.arctan(t)], 0.0, 9)
    tan = [0, 1, 0, Fraction(1, 3), 0, Fraction(2, 15), 0, Fraction(17, 315), 0, Fraction(62, 2835)]
    tanh = [(-1) ** (k // 2) * v for k, v in enumerate(tan)]
    atan = [0 if k % 2 == 0 else Fraction((-1) ** (k // 2), k) for k in range(10)]
    np.testing.assert_allclose(c, np.array([tan, tanh, atan], dtype=float).T, rtol=1e-14, atol=1e-16)
    # x_0 = 0 for an integer power: products, no division; exp and 1/(1 − t)
    c = series(lambda t: [t ** 3, np.exp(t), 1.0 / (1.0 - t)], 0.0, 8)
    np.testing.assert_array_equal(c[:, 0], [0, 0, 0, 1, 0, 0, 0, 0, 0])
    np.testing.assert_allclose(c[:, 1], [1 / math.factorial(k) for k in range(9)], rtol=1e-15)
    np.testing.assert_array_equal(c[:, 2], np.ones(9))
    c = series(lambda t: [np.sqrt(t), np.log(t), t / t], 0.0, 3)  # singular where the argument is 0
    assert not np.all(np.isfinite(c[1:]))


SHORT = ["time.end=4", "time.n_output=9", "output.euler_angles=false"]

CENTRE = textwrap.dedent('''
    import numpy as np
    from gyrolab.contracts import Force
    from gyrolab.physics.vectors import cross


    class Centre(Force):
        """An attracting centre off the vertical at c (fixed frame, in γ's components), plus a little drag on ω."""
        name = "centre"
        required_axes = frozenset({2})
        preserves_area_integral = False

        def __init__(self, body, *, k=0.6):
            self.k = float(k)

        def torque(self, omega, axes):
            d = axes[2] - np.array([0.2, -0.1, 1.6])
            r = np.sqrt(np.sum(d * d))
            return self.k * cross(axes[2], d) / r ** 3 - 0.02 * np.sin(omega) * np.exp(-omega[2] ** 2)
''')


@pytest.fixture(scope="module")
def centre(tmp_path_factory):
    site = tmp_path_factory.mktemp("site")
    (site / "taylor_centre.py").write_text(CENTRE)
    with installed_distribution(site, "taylor-centre", "0.1", {"centre": "taylor_centre:Centre"}):
        yield


def _integrate(overrides):
    scene = compose_scene([*overrides, *SHORT])
    return scene, scene.integrator.integrate(scene.system.rhs, scene.times, scene.system.initial_state(), None,
                                             scene.compiled).y


def test_off_axis_centre_under_taylor_matches_scipy(centre):
    scene, taylor = _integrate(["force=[uniform_gravity,centre]", "integrator=taylor", "integrator.tol=1e-15"])
    assert scene.compiled is not None  # the traced torque, not scipy
    _, scipy = _integrate(["force=[uniform_gravity,centre]", "integrator=dop853", "integrator.rtol=1e-12",
                           "integrator.atol=1e-12"])
    np.testing.assert_allclose(taylor, scipy, rtol=0, atol=1e-10)


def test_drag_under_taylor_and_auto_is_the_exact_decay():
    import sys

    sys.path.insert(0, str(VISCOUS_DRAG))
    try:
        from gyrolab_viscous_drag import ViscousDrag
    finally:
        sys.path.pop(0)
    # A = B = C = 1: ω̇ = −c ω, ω(t) = ω0 exp(−c t) (the README's example plugin)
    model = traced_model(np.ones(3), [ViscousDrag(None, coefficient=0.3)], False)
    assert taylor_series.ready(model)  # compiles the Taylor kernel (a scene does this when taylor is chosen)
    y0 = np.array([0.1, -0.05, 5.0, 0.0, 0.6, 0.8])
    t = np.linspace(0.0, 5.0, 11)
    y = Taylor(tol=1e-15).integrate(None, t, y0, None, model).y
    np.testing.assert_allclose(y[:, :3], y0[:3] * np.exp(-0.3 * t)[:, None], rtol=1e-13, atol=1e-15)


class Traced(Force):
    """A built-in force's torque with its compiled form withheld: gyrolab traces it as it would a plugin's."""

    preserves_area_integral = False

    def __init__(self, force):
        self.force = force
        self.name = f"traced_{force.name}"
        self.required_axes = force.required_axes

    def torque(self, omega, axes):
        return self.force.torque(omega, axes)


def test_plugins_repeating_the_builtin_arithmetic_follow_the_builtin_trajectory():
    scene = compose_scene(["force=[uniform_gravity,newtonian,magnetic]", "force.magnetic.direction=[0.6,0.48,0.64]",
                           "force.magnetic.moment=[0.3,0.2,1.0]", "integrator=taylor", *SHORT])
    system = scene.system
    beta = next(f for f in system.forces if f.name == "newtonian")
    beta.axis, beta.required_axes = 1, frozenset({1})  # the gradient torque about β = γ × α: every packed form
    builtin = system.compiled_model()  # with α: the built-in forms' numpy equations, traced
    plugin = traced_model(system.inertia, [Traced(f) for f in system.forces], system.carries_alpha)
    assert builtin is not None and plugin is not None and system.state_size == 9
    assert builtin.built_in is not None and plugin.built_in is None
    assert taylor_series.ready(plugin)
    y0 = system.initial_state()
    runs = [Taylor(order=20, tol=1e-14).integrate(None, scene.times, y0, None, m).y for m in (builtin, plugin)]
    np.testing.assert_allclose(runs[1], runs[0], rtol=0, atol=1e-12)


def test_batch_taylor_with_a_plugin_matches_single_runs(centre):
    from gyrolab.batch.integrate import integrate_batch

    scene = compose_scene(["force=[centre]", "integrator=taylor", "integrator.tol=1e-13", *SHORT])
    y0 = scene.system.initial_state()
    y0s = np.stack([y0, y0 + np.r_[0.2, -0.1, 0.3, np.zeros(y0.size - 3)]])
    batch = integrate_batch(scene, y0s)
    for row, start in enumerate(y0s):
        alone = scene.integrator.integrate(scene.system.rhs, scene.times, start, None, scene.compiled)
        np.testing.assert_allclose(batch.y[row], alone.y, rtol=0, atol=1e-14)
    auto = compose_scene(["force=[centre]", "integrator=auto", "integrator.accuracy=1e-8", *SHORT])
    assert auto.run().attrs["auto_method"] == "taylor"


def test_a_plugin_run_near_the_taylor_floor_keeps_its_error_estimate(centre):
    # the double-double companion evaluates the built-in torques only; near the floor the two double companions
    # (another order, 1/I moved by its rounding) measure the error where they agree far better than that, instead of
    # the estimate being "not available" for every plugin torque
    ds = run(["force=[centre]", "integrator=taylor", "integrator.tol=1e-13", "output.error_estimate=true", *SHORT])
    assert "second double companion" in ds.attrs["error_estimate_method"]
    assert 0 < ds.attrs["error_estimate_max_omega"] < 1e-10
    # where they do not, the dataset says why, naming the plugin the double-double kernel cannot evaluate
    floor = run(["force=[centre]", "integrator=taylor", "integrator.tol=1e-16", "output.error_estimate=true", *SHORT])
    method = floor.attrs["error_estimate_method"]
    assert method.startswith("not available") and "'centre'" in method and "error_estimate_omega" not in floor


def test_time_dependent_expression_under_taylor_against_the_equations_by_hand():
    """A torque that reads time, −0.1 sin(t) ω, under taylor: the series get the step's start time. Reference:
    Euler's equations I ω̇ = Iω × ω + T(t), γ̇ = γ × ω written out here, scipy DOP853 at rtol = atol = 1e-13."""
    class Pulse(Force):
        name = "pulse"
        time_dependent = True
        preserves_area_integral = False
        required_axes = frozenset()

        def torque(self, omega, axes, t):
            return -0.1 * np.sin(t) * omega

    inertia = np.array([1.0, 2.0, 3.0])
    model = traced_model(inertia, [Pulse()], False)
    from gyrolab.kernels import taylor

    # the kernel called directly before ``ready`` compiled the Taylor kernel: a non-finite status, not a jump to 0
    status, _ = taylor.run(model.params, 8, 1e-10, np.linspace(0.0, 1.0, 3), np.empty((3, 6)), 1, 3,
                           np.zeros(1), np.ones(6), np.zeros(6), np.zeros(2, dtype=np.int64))
    assert status == taylor.NOT_FINITE
    assert taylor_series.ready(model)

    def by_hand(t, y):
        w, g = y[:3], y[3:]
        return np.concatenate([(np.cross(inertia * w, w) - 0.1 * np.sin(t) * w) / inertia, np.cross(g, w)])

    times = np.linspace(0.0, 6.0, 13)
    y0 = np.array([0.3, -0.2, 1.5, 0.0, 0.6, 0.8])
    from gyrolab.batch.integrate import integrate_arrays

    got = integrate_arrays(model, Taylor(tol=1e-14), times, y0[None, :]).y[0]
    ref = solve_ivp(by_hand, (0.0, 6.0), y0, method="DOP853", t_eval=times, rtol=1e-13, atol=1e-13).y.T
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10)


def test_batch_sweep_of_a_plugin_parameter_under_taylor_is_the_exact_decay(cli, tmp_path, tmp_path_factory):
    """``gyrolab --batch`` over the README's drag plugin: ω(t) = ω0 exp(−c t) on a spherical body, for every c."""
    import tomllib

    import xarray as xr

    example = VISCOUS_DRAG
    project = tomllib.loads((example / "pyproject.toml").read_text())["project"]
    with installed_distribution(tmp_path_factory.mktemp("site"), project["name"], project["version"],
                                project["entry-points"]["gyrolab.forces"], [example]) as site:
        done = cli("--batch", "force=[viscous_drag]", "force.viscous_drag.coefficient=0.2,0.5", "body.a=1", "body.b=1",
                   "integrator=taylor", "integrator.tol=1e-14", "time.end=2", "time.n_output=5",
                   "output.euler_angles=false", "output.figures=false", "batch.output=trajectory",
                   "hydra.sweep.dir=batch", env_extra={"PYTHONPATH": f"{site}:{example}"})
    assert done.returncode == 0, done.stderr[-2000:]
    with xr.open_dataset(tmp_path / "batch" / "sweep.nc") as ds:
        omega = ds.omega.transpose(..., "time", "axis")
        assert omega.shape[:-2] == (2,) and int(ds.n_failed) == 0
        c = np.asarray(omega[omega.dims[0]].values, dtype=float)
        expected = omega.values[:, :1, :] * np.exp(-c[:, None, None] * ds.time.values[None, :, None])
        np.testing.assert_allclose(omega.values, expected, rtol=1e-12, atol=1e-15)


REFERENCE = ["experiment=perf_reference", "integrator=taylor", "time.end=30", "time.n_output=31"]


def test_the_fixed_points_traced_torques_give_the_same_trajectory_as_a_plugins_and_the_reference():
    """Gravity + Newtonian centre (the built-in torques traced into the generated kernels) and the same torques traced
    as a plugin's: the same trajectory to round-off, ending on the extended-precision reference (the coefficients
    against extended-precision Cauchy products: tests/kernels/test_taylor_step.py)."""
    from gyrolab.physics.reference import fixed_point_reference

    scene = compose_scene(REFERENCE)
    system = scene.system
    builtin = system.compiled_model()
    plugin = traced_model(system.inertia, [Traced(f) for f in system.forces], system.carries_alpha)
    y0 = system.initial_state()
    runs = [Taylor(tol=1e-14).integrate(None, scene.times, y0, None, m).y for m in (builtin, plugin)]
    np.testing.assert_allclose(runs[1], runs[0], rtol=0, atol=1e-12)
    exact = fixed_point_reference(system.inertia, system.body.weight_moment, 0.5, y0, [0.0, 30.0])[-1].astype(float)
    np.testing.assert_allclose(runs[0][-1], exact, rtol=0, atol=1e-11)


def test_traced_products_are_shared_as_the_builtin_shares_them():
    """The lowering pulls numbers out of products and merges equal ones: the traced gravity + Newtonian centre
    need the built-in's twelve Cauchy products per order (ω_y ω_z … for (Iω) × ω, γ_y γ_z … for γ × Iγ, six for
    γ × ω), not the plugin's fourteen as written (I_z γ_z · γ_y and I_y γ_y · γ_z are one product)."""
    scene = compose_scene(REFERENCE)
    plugin = traced_model(scene.system.inertia, [Traced(f) for f in scene.system.forces], False)
    program = taylor_series._Program(traced.MODELS[int(plugin.params[0])])
    products = {tuple(sorted(program.operands[u].terms[0][0] for u in s.args)) for s in program.series if s.op == "mul"}
    state = {s.extra: i for i, s in enumerate(program.series) if s.op == "y"}
    w, g = [state[m] for m in range(3)], [state[m] for m in range(3, 6)]
    pairs = {tuple(sorted((a[i], a[j]))) for a in (w, g) for i, j in ((1, 2), (2, 0), (0, 1))}
    cross = {tuple(sorted((g[i], w[j]))) for i in range(3) for j in range(3) if i != j}
    assert products == pairs | cross and len(products) == 12


_HEAP_CHILD = '''
import math
import sys
import numba
import numpy as np
from numba.core.runtime import rtsys
from gyrolab.kernels import taylor_series
from gyrolab.plugins.systems.fixed_point import traced_model
taylor_series._STACK_DOUBLES = 0  # before anything compiles (a fresh kernel cache): W always on the heap
sys.path.insert(0, sys.argv[1])
from gyrolab_viscous_drag import ViscousDrag
model = traced_model(np.ones(3), [ViscousDrag(None, coefficient=0.3)], False)
assert taylor_series.ready(model)


@numba.njit
def series(p, y, order, times):
    T = np.zeros((order + 1, y.size))
    for _ in range(times):
        T[0] = y
        taylor_series.coefficients(p, T, order, 0.0)
    return T


y0 = np.array([0.1, -0.05, 5.0, 0.0, 0.6, 0.8])
def allocations(times):
    before = rtsys.get_allocation_stats()
    T = series(model.params, y0, 20, times)
    after = rtsys.get_allocation_stats()
    return T, np.array([after.alloc - before.alloc, after.free - before.free])


series(model.params, y0, 20, 1)
T, calls = allocations(5)
calls -= allocations(0)[1]  # the arrays around the calls
exact = np.array([y0[:3] * (-0.3) ** k / math.factorial(k) for k in range(21)])  # ω = ω0 exp(−0.3 t)
print(*calls, float(np.max(np.abs(T[:, :3] - exact))))
'''


def test_series_work_array_on_the_heap_gives_the_exact_decay(tmp_path):
    """Above taylor_series._STACK_DOUBLES the kernel's scratch rows live on numba's heap (allocated and freed per
    call): forced here for every size (in a fresh kernel cache, so the stack path's cached code is not loaded),
    the series of drag on a spherical body are still those of ω0 exp(−c t), and every allocation is freed."""
    import os
    import subprocess
    import sys

    example = VISCOUS_DRAG
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), NUMBA_NRT_STATS="1")
    done = subprocess.run([sys.executable, "-c", _HEAP_CHILD, str(example)], env=env, capture_output=True, text=True,
                          timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    allocated, freed, error = done.stdout.split()[-3:]
    assert (int(allocated), int(freed)) == (5, 5)  # one W per call, each freed
    assert float(error) < 1e-15


class ManyProducts(Force):
    """Σ_i a_i (ω + b_i γ) × γ: 150 distinct Cauchy products of one depth (several groups of the Cauchy sums' loops)."""

    name = "many_products"
    required_axes = frozenset({2})
    preserves_area_integral = False

    def torque(self, omega, axes):
        from gyrolab.physics.vectors import cross

        total = np.zeros(3, dtype=object)
        for i in range(25):
            total = total + (0.01 * (i + 1)) * cross(omega + (0.1 * i - 1.0) * axes[2], axes[2])
        return total


def test_many_products_of_one_depth_under_taylor_match_scipy():
    """More products than one loop of the Cauchy sums takes (GROUP) and vector lengths that are not powers of two:
    the trajectory against scipy's DOP853 on the Python torque."""
    scene = compose_scene(["integrator=taylor", *SHORT])
    system = scene.system
    model = traced_model(system.inertia, [ManyProducts()], False)
    program = taylor_series._Program(traced.MODELS[int(model.params[0])])
    assert sum(s.op == "mul" and s.depth == 1 for s in program.series) > 2 * taylor_series.GROUP
    assert taylor_series.ready(model)
    y0 = system.initial_state()
    got = Taylor(tol=1e-15).integrate(None, scene.times, y0, None, model).y
    force, inertia = ManyProducts(), system.inertia

    def rhs(t, y):
        w, g = y[:3], y[3:]
        torque = np.asarray(force.torque(w, (None, None, g)), dtype=float)
        return np.concatenate([(np.cross(inertia * w, w) + torque) / inertia, np.cross(g, w)])

    ref = solve_ivp(rhs, (scene.times[0], scene.times[-1]), y0, method="DOP853", t_eval=scene.times, rtol=1e-12,
                    atol=1e-12).y.T
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-10)  # (measured 4e-12; the state moves by ~3)
