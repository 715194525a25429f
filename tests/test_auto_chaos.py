"""``integrator=auto accuracy=ε`` on chaotic scenes (issue 22): refuse in one sentence naming the horizon, or end
below both ε and the recorded bound.

References made without gyrolab's kernels: ``gyrolab.physics.reference.fixed_point_reference`` — a Taylor method
in long double (eps 1.1e-19) written from the equations in plain numpy — over spans where its own error, amplified
by the chaos (e^{λt} ≲ 1e5 here), stays far below the accuracies checked.
"""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.physics.reference import fixed_point_reference
from gyrolab.plugins.compiled import layout

SLOW_SPIN = ["initial=slow_spin"]
CHAOTIC_TOP = ["initial.theta0=1", "initial.r0=2", "initial.p0=0.3", "initial.q0=-0.2"]


def _reference(overrides):
    scene = compose_scene(["integrator=taylor", "time.n_output=2", *overrides])
    p = scene.system.compiled_model().params
    return fixed_point_reference(p[layout.INERTIA:layout.INERTIA + 3], p[layout.U_Z:layout.U_Z + 3], p[layout.N_Z],
                                 scene.system.initial_state()[:6], scene.times[[0, -1]])[-1].astype(float)


@pytest.mark.parametrize("scene, end, accuracy", [
    (SLOW_SPIN, 150.0, 1e-6), (SLOW_SPIN, 150.0, 1e-9), (CHAOTIC_TOP, 110.0, 1e-7), (CHAOTIC_TOP, 110.0, 1e-9),
])
def test_auto_on_a_chaotic_scene_keeps_its_promise_or_refuses(scene, end, accuracy):
    overrides = [*scene, f"time.end={end}"]
    truth = _reference(overrides)
    try:
        ds = compose_scene(["integrator=auto", f"accuracy={accuracy}", "time.n_output=2", *overrides]).run()
    except ConfigError as error:
        assert "cannot be reached in double precision on this chaotic scene" in str(error)
        assert "double-double" in str(error) and "t ≈" in str(error)
        return
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    actual = float(np.max(np.abs(final - truth)))
    assert actual <= accuracy and actual <= ds.attrs["auto_predicted_error"], (actual, ds.attrs["auto_predicted_error"])
    assert ds.attrs["auto_lyapunov_exponent"] > 0.01  # the finite-time exponent over the span: growth is seen
    if ds.attrs["auto_chaotic"]:
        assert ds.attrs["auto_precision_horizon"] > end  # it ran, so double precision holds ε past the end


def test_the_issue_scene_is_refused_with_its_horizon():
    # issue 22: slow_spin over the papers' span t = 300 asked 1e-8 ended with an error of 4.8e-3, recorded as 1e-8
    with pytest.raises(ConfigError) as refused:
        compose_scene(["integrator=auto", "accuracy=1e-8", "initial=slow_spin", "time.end=300"]).run()
    message = str(refused.value)
    assert message.count(";") <= 1 and "\n" not in message  # one sentence
    assert "λ ≈ 0.0" in message and "keeps 1e-08 only to t ≈" in message and "of 300" in message


def test_a_regular_scene_is_not_called_chaotic_and_records_its_growth():
    ds = compose_scene(["experiment=perf_reference", "time.n_output=2"]).run()
    assert ds.attrs["auto_chaotic"] == 0
    assert 0 < ds.attrs["auto_lyapunov_exponent"] < 0.03  # ln(growth)/t of a shear: small, and shrinking with t
    assert "auto_precision_horizon" not in ds.attrs
    assert "max-norm error of the final state" in ds.attrs["auto_predicted_error_bounds"]


def test_extended_precision_meets_what_double_precision_refuses():
    # the chaotic top to t = 110 at 1e-9 is refused in double precision (above); allowed to, auto runs the
    # double-double Taylor method and ends below ε and its bound (long-double reference: error ~1e-12 here)
    overrides = [*CHAOTIC_TOP, "time.end=110"]
    truth = _reference(overrides)
    with pytest.raises(ConfigError, match="integrator.extended_precision=true"):
        compose_scene(["integrator=auto", "accuracy=1e-9", "time.n_output=2", *overrides]).run()
    ds = compose_scene(["integrator=auto", "accuracy=1e-9", "integrator.extended_precision=true", "time.n_output=2",
                        *overrides]).run()
    assert ds.attrs["auto_precision"] == "double-double"
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    actual = float(np.max(np.abs(final - truth)))
    assert actual <= 1e-9 and actual <= ds.attrs["auto_predicted_error"]
