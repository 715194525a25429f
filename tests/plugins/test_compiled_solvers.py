"""Compiled integrators: same steps as scipy, orders, accuracy against the extended-precision reference."""

import numpy as np
import pytest

from gyrolab import compose_scene, run
from gyrolab.errors import ConfigError
from gyrolab.physics.reference import fixed_point_reference

INERTIA, R_C, K = [2.0, 1.5, 1.0], [0.3, 0.2, 0.9327379053088815], 0.5
Y0 = [0.1, -0.05, 5.0, np.sin(1.0), 0.0, np.cos(1.0)]
REF_BASE = ["experiment=perf_reference", "time.n_output=11"]


@pytest.fixture(scope="module")
def reference20():
    """The perf reference problem on [0, 20] in extended precision (independent of the kernels)."""
    return fixed_point_reference(INERTIA, R_C, K, Y0, np.linspace(0, 20, 11)).astype(float)


def _state(ds):
    return np.concatenate([ds.omega.values, ds.gamma.values], axis=1)


def test_compiled_dop853_takes_scipys_steps():
    common = ["integrator.rtol=1e-9", "integrator.atol=1e-9", "time.end=20", "time.n_output=41"]
    py, nb = run(["integrator=dop853", *common]), run(["integrator=dop853_numba", *common])
    for key in ("integrator_nfev", "integrator_n_steps", "integrator_n_rejected"):
        assert py.attrs[key] == nb.attrs[key], key
    np.testing.assert_allclose(_state(nb), _state(py), rtol=0, atol=1e-12)


def test_compiled_rk4_takes_the_python_rk4_steps():
    common = ["integrator.step=0.01", "time.end=5", "time.n_output=11"]
    py, nb = run(["integrator=rk4", *common]), run(["integrator=rk4_numba", *common])
    assert py.attrs["integrator_n_steps"] == nb.attrs["integrator_n_steps"]
    np.testing.assert_allclose(_state(nb), _state(py), rtol=0, atol=1e-12)


def test_taylor_against_extended_precision(reference20):
    ds = run([*REF_BASE, "integrator=taylor", "integrator.tol=1e-16", "time.end=20"])
    assert np.max(np.abs(_state(ds) - reference20)) < 1e-13


@pytest.mark.parametrize("order", [2, 4, 6])
def test_lie_poisson_order(order, reference20):
    errors, steps = [], [0.02, 0.01]
    for h in steps:
        ds = run([*REF_BASE, "integrator=lie_poisson", f"integrator.order={order}", f"integrator.step={h}",
                  "time.end=20"])
        errors.append(np.max(np.abs(_state(ds) - reference20)))
    assert np.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.2)


def test_lie_poisson_keeps_the_casimirs_and_bounds_energy_over_ten_thousand_spins():
    # 10^4 spin periods of the reference body (r0 = 5: period 2π/5).
    end = 1e4 * 2 * np.pi / 5
    common = [*REF_BASE, f"time.end={end}", "time.n_output=2001"]
    lp = run([*common, "integrator=lie_poisson", "integrator.step=0.02", "integrator.order=4"])
    assert lp.gamma_norm.attrs["max_abs_drift"] < 1e-12
    assert lp.area_integral.attrs["max_abs_drift"] < 1e-11
    energy_error = np.abs(lp.energy.values - lp.energy.values[0])
    early, late = energy_error[:200].max(), energy_error[-200:].max()
    assert late < 3 * early  # bounded oscillation, no secular drift
    rk = run([*common, "integrator=dop853_numba", "integrator.rtol=1e-8", "integrator.atol=1e-8"])
    rk_error = np.abs(rk.energy.values - rk.energy.values[0])
    assert rk_error[-200:].max() > 10 * rk_error[:200].max()  # the non-symplectic method drifts


@pytest.fixture(scope="module")
def reference60():
    """The perf reference problem on [0, 60] (61 times) in extended precision."""
    return fixed_point_reference(INERTIA, R_C, K, Y0, np.linspace(0, 60, 61)).astype(float)


@pytest.mark.parametrize("accuracy", [1e-6, 1e-9, 1e-11, 1e-13])
def test_auto_meets_its_accuracy(accuracy, reference60):
    ds = run(["experiment=perf_reference", "time.n_output=61", "time.end=60", "integrator=auto",
              f"accuracy={accuracy}"])
    errors = np.max(np.abs(_state(ds) - reference60), axis=1)
    assert errors[-1] <= accuracy
    assert ds.attrs["auto_method"] == "taylor" and ds.attrs["accuracy"] == accuracy
    # the recorded prediction meets the target and bounds the actual error
    assert errors[-1] <= ds.attrs["auto_predicted_error"] <= accuracy
    # the pilot's tight run is the first tenth of the trajectory: outputs there are as accurate as the rest
    assert np.max(errors[:7]) <= accuracy


def test_taylor_order_follows_the_tolerance_and_error_is_proportional_to_it(reference20):
    # Jorba & Zou's optimal order ⌈−ln(tol)/2 + 1⌉ (Exp. Math. 14, 2005, §3.2): 11 at 1e-8, 20 at 1e-16, kept in
    # double-double; in double the order of least work counting the step's overhead (tests/kernels/test_taylor_step.py)
    from gyrolab.kernels.taylor import order_for
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    assert [Taylor(tol=tol, precision="double-double").order for tol in (1e-8, 1e-12, 1e-16)] == [11, 15, 20]
    assert [Taylor(tol=tol).order for tol in (1e-8, 1e-12, 1e-16)] == [order_for(tol) for tol in (1e-8, 1e-12, 1e-16)]
    # at a fixed order the step is ∝ tol^(1/p) and the local error ∝ h^(p+1): the global error is ∝ tol
    # (what integrator=auto's extrapolation from its pilot rests on)
    errors = []
    for tol in (1e-9, 1e-11):
        ds = run([*REF_BASE, "integrator=taylor", "integrator.order=12", f"integrator.tol={tol}", "time.end=20"])
        errors.append(np.max(np.abs(_state(ds) - reference20)))
    assert np.log10(errors[0] / errors[1]) == pytest.approx(2.0, abs=0.3)


def test_taylor_compensated_update_reaches_the_double_precision_floor(reference60):
    # ~600 steps of order 20: an uncompensated update loses about one ulp of |y| = 5 per step
    # (2e-13 here, 2e-12 over t = 300); the Kahan-compensated one stays near a few ulps, at every
    # output time of the dense output (Horner on the step's polynomial) as at the end.
    ds = run(["experiment=perf_reference", "time.n_output=61", "time.end=60", "integrator=taylor",
              "integrator.tol=1e-17"])
    assert np.max(np.abs(_state(ds) - reference60)) < 2e-14


def _untraceable_newtonian(monkeypatch):
    """Newtonian without its compiled form, its torque unchanged but computed through float(): not traceable."""
    from gyrolab.plugins.forces.newtonian import Newtonian

    torque = Newtonian.torque
    monkeypatch.setattr(Newtonian, "compiled_terms", lambda self: None)
    monkeypatch.setattr(Newtonian, "torque",
                        lambda self, omega, axes: np.array([float(v) for v in torque(self, omega, axes)]))


def test_auto_falls_back_to_scipy_without_compiled_forms(monkeypatch):
    _untraceable_newtonian(monkeypatch)
    ds = run(["integrator=auto", "accuracy=1e-7", "time.end=5", "time.n_output=11"])
    assert ds.attrs["auto_method"] == "dop853"


def test_compiled_integrator_refuses_a_force_without_compiled_form(monkeypatch):
    _untraceable_newtonian(monkeypatch)
    with pytest.raises(ConfigError, match="the torque of force 'newtonian' cannot be compiled: it converts the state "
                                          "to a Python float"):
        compose_scene(["integrator=taylor"])


def test_auto_refuses_an_accuracy_beyond_double_precision_when_it_may_not_climb():
    no_climb = "integrator.extended_precision=false"
    with pytest.raises(ConfigError, match="accuracy=1e-15 is below"):
        run(["integrator=auto", "accuracy=1e-15", "time.end=1", "time.n_output=3", no_climb])
    # 300 time units at spin 5: ~3000 steps; compensated round-off ~eps·|y|·√steps = 6e-14 (measured: 2e-14)
    with pytest.raises(ConfigError, match=r"cannot be reached in double precision on this scene \(error about"):
        run(["experiment=perf_reference", "time.n_output=2", "accuracy=1e-14", no_climb])
    # by default it climbs: the same target in double-double (32 digits), and a 1e-31 target is below even that
    ds = run(["integrator=auto", "accuracy=1e-15", "time.end=1", "time.n_output=3"])
    assert ds.attrs["auto_precision"] == "double-double"
    with pytest.raises(ConfigError, match="accuracy=1e-31 is below what double-double reaches"):
        run(["integrator=auto", "accuracy=1e-31", "time.end=1", "time.n_output=3"])


def test_taylor_steps_do_not_depend_on_how_the_run_is_cut_into_kernel_calls():
    """The integrator cuts a run into kernel calls by measured wall time (for progress), so where a call stops
    must not change a single step: one call over all outputs and calls stopping at arbitrary outputs give the
    same bits."""
    from gyrolab.kernels import taylor, taylor_series

    scene = compose_scene(["experiment=perf_reference", "integrator=taylor", "integrator.tol=1e-9", "time.end=20",
                           "time.n_output=201"])
    compiled, order, tol = scene.system.compiled_model(), scene.integrator.order, scene.integrator.tol
    assert taylor_series.ready(compiled)
    t_out = scene.times

    def cut_at(stops):
        out = np.empty((t_out.size, scene.system.state_size))
        y = scene.system.initial_state().copy()
        out[0] = y
        state, carry, stats, reached = np.array([t_out[0]]), np.zeros_like(y), np.zeros(2, dtype=np.int64), 1
        for stop in stops:
            if reached < stop:
                status, reached = taylor.run(compiled.params, order, tol, t_out, out, reached, stop,
                                             state, y, carry, stats)
                assert status == taylor.OK
        return out, int(stats[1])

    whole, steps = cut_at([t_out.size])
    for stops in ([2, 3, 50, 51, 137, t_out.size], list(range(2, t_out.size + 1))):
        pieces, pieces_steps = cut_at(stops)
        assert pieces_steps == steps
        np.testing.assert_array_equal(pieces, whole)


@pytest.mark.parametrize("name", ["lie_poisson", "rk4_numba"])
def test_a_fixed_step_run_does_not_depend_on_the_machines_speed(name, monkeypatch):
    """Where a fixed-step run is cut between calls into its kernel is counted in steps, not timed: lie_poisson
    rebuilds its momentum Iω from ω at each call, so a slower machine (here a clock at 10 s a reading) cutting it
    elsewhere gave other last bits (two runs of one config differed at 1e-14)."""
    from gyrolab.engine.progress import Progress
    from gyrolab.plugins.integrators import compiled_solvers

    scene = compose_scene([f"integrator={name}", "time.end=20", "time.n_output=401"])
    args = (scene.rhs, scene.times, scene.system.initial_state(), Progress(name, 0.0, 20.0), scene.compiled)
    usual = scene.integrator.integrate(*args).y

    class SlowClock:
        now = 0.0

        @classmethod
        def perf_counter(cls):
            cls.now += 10.0
            return cls.now

    monkeypatch.setattr(compiled_solvers, "time", SlowClock)
    np.testing.assert_array_equal(scene.integrator.integrate(*args).y, usual)


@pytest.mark.parametrize("direction, size", [("[0.0,0.0,1.0]", 6), ("[0.6,0.0,0.8]", 9)])  # (α: fixed X needed)
def test_a_scene_with_a_plugin_traces_every_force_and_its_compiled_rhs_is_the_python_rhs(monkeypatch, direction,
                                                                                          size):
    """A plugin (here magnetic without its built-in form) makes the scene trace its whole right-hand side, built-in
    torques too; the traced model's right-hand side (for the states ω, γ and ω, γ, α) must equal the Python one."""
    from gyrolab.kernels import models
    from gyrolab.plugins.forces.magnetic import Magnetic

    monkeypatch.setattr(Magnetic, "compiled_terms", lambda self: None)
    scene = compose_scene(["integrator=dop853_numba", "force=[uniform_gravity,newtonian,magnetic]",
                           "force.magnetic.moment=[0.3,-0.2,0.5]", f"force.magnetic.direction={direction}", "output.euler_angles=false"])
    assert scene.system.initial_state().size == size
    compiled = scene.compiled
    rng = np.random.default_rng(12)
    for k in range(5):
        y = scene.system.initial_state() + 0.3 * rng.standard_normal(size)
        out = np.empty(size)
        models.evaluate(0.1 * k, y, compiled.params, out)
        np.testing.assert_allclose(out, scene.system.rhs(0.1 * k, y), rtol=1e-13, atol=1e-13)


def test_taylor_stops_with_one_sentence_when_its_step_cannot_advance_time():
    """A step below the spacing of floating-point numbers at t (here forced by tol = 1e-300 at t = 1, where the
    spacing is 2.2e-16 and the step ~1e-100) used to leave the kernel looping forever; it is a failure now,
    with dop853's status code, and the integrator says so in one sentence."""
    from gyrolab.errors import IntegrationError
    from gyrolab.kernels import taylor
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    scene = compose_scene(["integrator=taylor", "time.end=2", "time.n_output=3"])
    compiled, y0 = scene.compiled, scene.system.initial_state()
    t_out = np.array([1.0, 1.5, 2.0])
    out = np.empty((3, y0.size))
    out[0] = y0
    state, stats = np.array([1.0]), np.zeros(2, dtype=np.int64)
    code, reached = taylor.run(compiled.params, 4, 1e-300, t_out, out, 1, 3, state,
                               y0.copy(), np.zeros(y0.size), stats)
    assert (code, reached, state[0], stats[1]) == (taylor.TOO_SMALL_STEP, 1, 1.0, 0)
    with pytest.raises(IntegrationError, match="^taylor's step fell below the spacing of floating-point numbers "
                                               "near t=1 "):
        Taylor(order=4, tol=1e-300).integrate(None, t_out, y0, None, compiled)
    from gyrolab.plugins.integrators.compiled_solvers import taylor_samples  # auto's screen: a failure is one sentence too

    with pytest.raises(IntegrationError, match=r"^taylor produced a non-finite state near t=1$"):
        taylor_samples(compiled, 1e-9, t_out, np.where(np.arange(y0.size) == 0, np.nan, y0))
