"""Integrator plugins: accuracy, convergence order, work statistics, agreement with scipy."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene, run
from gyrolab.errors import IntegrationError
from gyrolab.contracts.registry import load, names

SHORT = ["time.end=5", "time.n_output=11"]


@pytest.fixture(scope="module")
def reference():
    return run(["integrator.rtol=1e-13", "integrator.atol=1e-13", *SHORT])


@pytest.mark.parametrize("name", ["rk45", "dop853", "lsoda", "radau", "bdf"])
def test_adaptive_methods_reach_their_tolerance(name, reference):
    ds = run([f"integrator={name}", "integrator.rtol=1e-9", "integrator.atol=1e-9", *SHORT])
    error = np.max(np.abs(ds.omega.values - reference.omega.values))
    # The global error of a tolerance-controlled method grows with time; 1e-9 → below ~1e-5 at t = 5.
    assert error < 1e-5, (name, error)
    assert ds.attrs["integrator_nfev"] > 0 and ds.attrs["integrator_n_steps"] > 0
    assert np.all(np.isfinite(ds.omega.values))


def test_rk4_is_fourth_order(reference):
    errors = []
    steps = [0.02, 0.01, 0.005]
    for h in steps:
        ds = run(["integrator=rk4", f"integrator.step={h}", *SHORT])
        errors.append(np.max(np.abs(ds.omega.values[-1] - reference.omega.values[-1])))
        assert ds.attrs["integrator_nfev"] == 4 * ds.attrs["integrator_n_steps"]
        assert ds.attrs["integrator_n_steps"] == round(5 / h)
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope == pytest.approx(4.0, abs=0.2)


def test_gyrolab_dop853_takes_scipys_steps():
    scene = compose_scene(["integrator.rtol=1e-8", "integrator.atol=1e-8", *SHORT])
    ds = scene.run()
    y0 = scene.system.initial_state()
    ref = solve_ivp(scene.system.rhs, (0, 5), y0, method="DOP853", rtol=1e-8, atol=1e-8, t_eval=scene.times)
    np.testing.assert_allclose(ds.omega.values, ref.y[0:3].T, rtol=0, atol=1e-13)
    # Same steps, same dense output; solve_ivp also interpolates t0 itself (3 more evaluations in DOP853's
    # dense output), gyrolab stores y0 as given.
    assert ds.attrs["integrator_nfev"] == ref.nfev - 3


def test_rejected_steps_are_counted():
    # A huge first step is rejected: scipy's own count of evaluations must split into attempts.
    ds = run(["integrator=rk45", "integrator.rtol=1e-10", "integrator.atol=1e-10", *SHORT])
    steps, rejected, nfev = (ds.attrs[f"integrator_{k}"] for k in ("n_steps", "n_rejected", "nfev"))
    # each RK45 attempt costs 6 evaluations; 2 evaluations for the initial step guess; 0 for dense output
    assert nfev == 2 + 6 * (steps + rejected)


def test_unknown_rejections_are_not_invented():
    ds = run(["integrator=radau", *SHORT])
    assert "integrator_n_rejected" not in ds.attrs


@pytest.mark.parametrize("name", ["rk4", "dop853", "radau", "lsoda"])
def test_failure_is_an_error_not_garbage(name, monkeypatch):
    # A torque growing like |ω|ω (a broken plugin): ω̇3 ≈ 10 ω3² blows up at t ≈ 1/(10 r0) = 0.02.
    # The run must stop and say when, not return NaN or inf.
    from gyrolab.plugins.forces.uniform_gravity import UniformGravity

    monkeypatch.setattr(UniformGravity, "torque", lambda self, omega, axes: 10.0 * np.linalg.norm(omega) * omega)
    monkeypatch.setattr(UniformGravity, "compiled_terms", lambda self: None)
    scene = compose_scene([f"integrator={name}", "integrator.step=1e-4" if name == "rk4" else "integrator.rtol=1e-8",
                           "initial.r0=5", "time.end=0.1", "time.n_output=11"])
    with pytest.raises(IntegrationError, match="t="):
        scene.run()


def test_every_registered_integrator_loads():
    for name in names("integrator"):
        cls = load("integrator", name)
        assert cls.name == name


@pytest.mark.parametrize("name", ["rk4", "dop853"])
def test_progress_reaches_the_end(name):
    scene = compose_scene([f"integrator={name}", *SHORT])
    seen = []
    scene.integrator.integrate(scene.system.rhs, scene.times, scene.system.initial_state(), seen.append)
    assert seen and seen[-1] == pytest.approx(5.0) and seen == sorted(seen)


def test_a_tolerance_below_scipys_floor_is_stored_as_used(caplog):
    # scipy raises rtol below 100 machine epsilons to that floor (scipy.integrate._ivp.common.validate_tol): the
    # dataset must store the tolerance the method ran with, and keep the request beside it (issue 22)
    from gyrolab import run

    with caplog.at_level("WARNING"):
        ds = run(["integrator=dop853", "integrator.rtol=1e-20", "time.end=0.5", "time.n_output=11"])
    assert ds.attrs["integrator_rtol"] == pytest.approx(100 * np.finfo(float).eps)
    assert ds.attrs["integrator_rtol_requested"] == 1e-20
    assert sum("not the requested rtol" in r.getMessage() for r in caplog.records) == 1
    plain = run(["integrator=dop853", "integrator.rtol=1e-9", "time.end=0.5", "time.n_output=11"])
    assert plain.attrs["integrator_rtol"] == 1e-9 and "integrator_rtol_requested" not in plain.attrs
