"""Rule 11 of the integrator contract: ``auto`` checks its prediction against the measured error estimate
(``output.error_estimate``, on by default for auto) and runs its method again, more accurately, or refuses.

References made without gyrolab's kernels: ``gyrolab.physics.reference.fixed_point_reference`` (a Taylor method in
long double written from the equations in plain numpy).
"""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.errors import ConfigError
from tests.helpers.accuracy import CHAOTIC_TOP, long_double_final, long_double_states, no_growth


@pytest.mark.parametrize("estimate", ["true", "false"])
@pytest.mark.parametrize("accuracy", [1e-6, 1e-9, 1e-12])
def test_a_pilot_of_a_few_clipped_steps_no_longer_breaks_the_promise(accuracy, estimate):
    # found 2026-11-27: a span of a few dozen steps (r0 = 32 over t = 0.25) leaves the pilot's stretch one or two
    # steps clipped by its end, so its runs at τ and τ_t took the same step; at 1e-9 auto chose tol 1e-5,
    # predicted 2e-14 and ended 5.7e-5 away. The pilot now takes the prior for such a stretch (and the measured
    # estimate would have sent it back): the promise holds with and without the estimate.
    theta0 = float(np.arccos(0.5 / 32.0))
    overrides = ["body.a=2.0", "body.b=1.5", "force.newtonian.k=0.3", "initial.r0=32.0", f"initial.theta0={theta0!r}",
                 "initial.p0=0.3", "initial.q0=0.0", "time.end=0.25", "time.n_output=6"]
    truth = long_double_final(overrides)
    ds = compose_scene(["integrator=auto", f"accuracy={accuracy}", f"output.error_estimate={estimate}",
                        *overrides]).run()
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    actual = float(np.max(np.abs(final - truth)))
    assert actual <= accuracy and actual <= ds.attrs["auto_predicted_error"], (actual, ds.attrs["auto_predicted_error"])
    assert "auto_measured_error_before_recheck" not in ds.attrs  # the first run kept it


def test_a_run_whose_measured_error_breaks_the_prediction_is_run_again_more_accurately(monkeypatch):
    # rule 11: with no amplification the chaotic top at t = 110 ends with 2e-6 where 1e-6 is asked and predicted;
    # the error estimate measures it and auto runs its method again, more accurately, keeping the promise against
    # the long-double reference
    no_growth(monkeypatch)
    overrides = [*CHAOTIC_TOP, "time.end=110"]
    truth = long_double_final(overrides)
    ds = compose_scene(["integrator=auto", "accuracy=1e-6", "time.n_output=2", *overrides]).run()
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    actual = float(np.max(np.abs(final - truth)))
    assert actual <= 1e-6 and actual <= ds.attrs["auto_predicted_error"], (actual, ds.attrs["auto_predicted_error"])
    assert ds.attrs["accuracy"] == 1e-6
    assert ds.attrs["auto_measured_error_before_recheck"][0] > 1e-6  # the first run did break it
    assert ds.attrs["error_estimate_max_omega"] <= ds.attrs["auto_predicted_error"]


def test_without_the_error_estimate_nothing_catches_a_prediction_that_misses(monkeypatch):
    # the same scene with output.error_estimate=false: the safety net above is the measurement, so the broken
    # prediction stands (what this test shows is why the estimate is on by default for auto)
    no_growth(monkeypatch)
    overrides = [*CHAOTIC_TOP, "time.end=110"]
    truth = long_double_final(overrides)
    ds = compose_scene(["integrator=auto", "accuracy=1e-6", "time.n_output=2", "output.error_estimate=false",
                        *overrides]).run()
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    assert float(np.max(np.abs(final - truth))) > 1e-6
    assert "auto_measured_error_before_recheck" not in ds.attrs


def test_a_promise_the_reruns_cannot_keep_is_one_sentence(monkeypatch):
    import gyrolab.accuracy.promise as promise_module

    no_growth(monkeypatch)
    monkeypatch.setattr(promise_module, "MAX_RECHECKS", 0)
    with pytest.raises(ConfigError) as refused:
        compose_scene(["integrator=auto", "accuracy=1e-6", "time.n_output=2", *CHAOTIC_TOP, "time.end=110"]).run()
    message = str(refused.value)
    assert message.startswith("accuracy=1e-06 is not met on this scene") and "\n" not in message
    assert "a shorter time.end" in message and "extended_precision" not in message  # (the climb is the default)
    with pytest.raises(ConfigError, match=r"integrator.extended_precision=true \(auto then climbs to double-double\)$"):
        compose_scene(["integrator=auto", "accuracy=1e-6", "time.n_output=2", "integrator.extended_precision=false",
                       *CHAOTIC_TOP, "time.end=110"]).run()


def test_the_recheck_compares_every_output_time(monkeypatch):
    # the promise covers the trajectory, not the final state alone: with the measured error of the final state hidden
    # (set to 0), what the estimate measures at the output times before it (t = 109, 108, …) still breaks the prediction
    # and sends the run again; the answer is then within ε at every output time against the double-double reference
    import gyrolab.accuracy.promise as promise

    no_growth(monkeypatch)
    compare = promise.estimate.compare

    def final_hidden(*args, **kwargs):
        comparison = compare(*args, **kwargs)
        if comparison.difference is not None:
            comparison.difference[-1] = 0.0
        return comparison

    monkeypatch.setattr(promise.estimate, "compare", final_hidden)
    overrides = [*CHAOTIC_TOP, "time.end=110", "time.n_output=111"]
    ds = compose_scene(["integrator=auto", "accuracy=1e-6", *overrides]).run()
    assert ds.attrs["auto_measured_error_before_recheck"][0] > 1e-6  # measured before the end
    assert "auto_recheck" in ds.attrs
    truth = compose_scene(["integrator=taylor", "integrator.precision=double-double", "integrator.tol=1e-28",
                           *overrides]).run()
    error = max(float(np.max(np.abs(ds[v].values - truth[v].values))) for v in ("omega", "gamma"))
    assert error <= 1e-6 and error <= ds.attrs["auto_predicted_error"], error


def test_a_run_measured_within_the_estimates_own_accuracy_of_the_target_is_run_again():
    # benchmarks/promise_audit.py --seed 2026, scene 61 (a fast asymmetric top, 2026-11-29): auto predicted 1e-11, the
    # estimate measured 0.98e-11 (within 3 % of the truth), and the run was kept 1.0e-11 from heyoka's real128. A run
    # is now kept only when measured ESTIMATE_SLACK (2) times below the target: this one runs again, more accurately
    overrides = ["output.euler_angles=true", "body.a=0.8847", "body.b=1.0936",
                 "body.com_direction=[-0.473612166952938,-0.4498028639174732,0.7572112643944102]",
                 "force=[uniform_gravity]", "initial.theta0=1.50345", "initial.phi0=1.83601", "initial.psi0=1.09935",
                 "initial.r0=7.55533", "initial.p0=0.2653", "initial.q0=-0.07868", "time.end=23.332",
                 "time.n_output=101"]
    scene = compose_scene(["integrator=auto", "accuracy=1e-11", *overrides])
    ds = scene.run()
    truth = long_double_states(scene, scene.times)
    actual = float(np.max(np.abs(np.hstack([ds.omega.values, ds.gamma.values]) - truth)))
    assert ds.attrs["auto_measured_error_before_recheck"][0] > 0.5e-11  # the first run sat at the target's edge
    assert actual <= 0.5e-11 and ds.attrs["auto_predicted_error"] <= 0.5e-11, actual


def test_a_kept_run_promises_at_least_twice_what_its_estimate_measured():
    # benchmarks/promise_audit.py --seed 5, scene 6 (a fast top near double precision's floor, 2026-11-30): the run
    # measured 2.2e-12 against 1e-12, ran again with a double-double head, measured 4.73e-13 and promised
    # accuracy/ESTIMATE_SLACK = 5e-13; it ended 5.02e-13 from heyoka's real128. The estimate is accurate to within
    # ESTIMATE_SLACK, so a kept run promises at least that much times the error it measured (here 9.5e-13 < 1e-12).
    # (Since the companion near the floor keeps the run's order, that scene's rerun lands elsewhere, 2.4e-13 away and
    # measured 2.3e-13: the rule is checked on its numbers, and the scene for the promise it keeps.)
    from gyrolab.accuracy.calibration import ESTIMATE_SLACK
    from gyrolab.accuracy.promise import _bounded
    from gyrolab.contracts.integrator import Choice

    rerun = Choice(None, {"auto_predicted_error": 5e-13}, target=1e-12, promised=5e-13)
    kept = _bounded(rerun, 4.73e-13)
    assert kept.promised == kept.attributes["auto_predicted_error"] == ESTIMATE_SLACK * 4.73e-13
    assert "estimate's own accuracy" in kept.attributes["auto_predicted_error_raised_by"]
    assert _bounded(rerun, 2e-13) is rerun  # a measurement 2x below the promise leaves it

    overrides = ["output.euler_angles=true", "body.a=1.0", "body.b=0.6666",
                 "body.com_direction=[-0.7200623378476575,0.693777963848114,0.013504313834144271]",
                 "force=[uniform_gravity]", "initial.theta0=1.65642", "initial.phi0=5.39572", "initial.psi0=2.1193",
                 "initial.r0=15.9943", "initial.p0=-0.0117", "initial.q0=-0.02714", "time.end=76.733",
                 "time.n_output=101"]
    ds = compose_scene(["integrator=auto", "accuracy=1e-12", *overrides]).run()
    measured = max(ds.attrs["error_estimate_max_omega"], ds.attrs["error_estimate_max_attitude"])
    assert ds.attrs["auto_measured_error_before_recheck"]  # the rerun is the case
    assert ESTIMATE_SLACK * measured <= ds.attrs["auto_predicted_error"] <= 1e-12


#: a regular top (promise_audit.random_scene, seed 7, scene 14) whose growth of perturbations after the pilot, 13.6×,
#: is above the t² law the pilot fits (10×): the run's own growth raises the prediction above ε
RAISED_BY_GROWTH = ["body.a=0.6357", "body.b=1.0",
                    "body.com_direction=[-0.5241254131267719,0.8464446108716233,-0.09393653198344645]",
                    "force=[uniform_gravity]", "initial.theta0=2.5762", "initial.phi0=1.55452", "initial.psi0=2.07252",
                    "initial.r0=0.85805", "initial.p0=-0.07697", "initial.q0=0.02371", "time.end=12.061",
                    "time.n_output=101"]


@pytest.mark.parametrize("accuracy", [1e-6, 1e-9])
def test_a_run_whose_own_growth_raises_its_prediction_is_kept_where_its_estimate_meets_the_target(accuracy):
    # kept on its measurement (the recorded prediction: ε / ESTIMATE_SLACK), not run again after a tangent run, pilot
    # and run (5–15 ms on such scenes); and the independent reference agrees that it meets ε at every output time
    overrides = ["integrator=auto", f"accuracy={accuracy}", *RAISED_BY_GROWTH]
    scene = compose_scene(overrides)
    ds = scene.run()
    assert ds.attrs["auto_predicted_error_by_growth"] > accuracy
    assert ds.attrs["auto_amplification_method"].startswith("a tangent vector carried by the chosen run itself")
    assert ds.attrs["auto_predicted_error"] == accuracy / 2
    y = np.concatenate([ds.omega.values, ds.gamma.values], axis=1)
    actual = np.abs(y - long_double_states(scene, scene.times)).max()
    assert actual <= accuracy / 2
    estimate = max(ds.attrs["error_estimate_max_omega"], ds.attrs["error_estimate_max_attitude"])
    assert 0.5 <= estimate / actual <= 2.0
