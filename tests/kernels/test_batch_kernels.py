"""The adaptive batch kernels (dop853_numba, taylor, auto behind integrate_arrays) against single runs and scipy."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels import batch_dop853, batch_taylor
from tests.helpers.taylor import fixed_point_rows, single_kernel_runs

SHORT = ["experiment=perf_reference", "time.end=2", "time.n_output=11"]
SETTINGS = {"dop853_numba": ["integrator.rtol=1e-10", "integrator.atol=1e-10"], "taylor": ["integrator.tol=1e-10"]}
LANE_KERNELS = {"dop853_numba": batch_dop853, "taylor": batch_taylor}  # the kernels advancing (ω, γ) lanes


def _scene(integrator, euler_angles=False, extra=()):
    return compose_scene([*SHORT, f"integrator={integrator}", *SETTINGS.get(integrator, []),
                          f"output.euler_angles={str(euler_angles).lower()}", *extra])


def _starts(scene, count, seed=0, scale=0.1):
    rng = np.random.default_rng(seed)
    y0s = np.tile(scene.system.initial_state(), (count, 1))
    y0s[:, 0:3] += rng.normal(scale=scale, size=(count, 3))
    return y0s


@pytest.mark.parametrize("integrator", ["dop853_numba", "taylor"])
@pytest.mark.parametrize("euler_angles", [False, True])  # (ω, γ): DOP853 by lanes; (ω, γ, α): one per thread
def test_batch_equals_the_single_trajectory_kernel(integrator, euler_angles):
    scene = _scene(integrator, euler_angles)
    y0s = _starts(scene, 5)
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
    assert not batch.failed.any() and batch.y.shape == (5, 11, scene.system.state_size)
    for j, y0 in enumerate(y0s):
        single = scene.integrator.integrate(scene.system.rhs, scene.times, y0, None, scene.compiled)
        # the single Taylor run stops its steps at the ends of its progress chunks, the batch only at the
        # last time: both meet the tolerance 1e-10 and agree to it, not to rounding
        np.testing.assert_allclose(batch.y[j], single.y, rtol=0, atol=1e-13 if integrator == "dop853_numba" else 1e-10)
        if integrator == "dop853_numba":  # same controller: the same accepted steps
            assert batch.steps[j] == single.stats.n_steps


@pytest.mark.parametrize("integrator", ["dop853_numba", "taylor"])
def test_a_lane_does_not_depend_on_its_neighbours(integrator):
    """One trajectory alone, among easy ones and among hard ones (fast spins, many more steps), in the first lane
    and in a lane refilled after another trajectory finished: bit for bit the same result and steps."""
    import numba

    scene = _scene(integrator)
    lanes = LANE_KERNELS[integrator]
    count = 8 * lanes.LANES * numba.get_num_threads()  # tasks of more trajectories than lanes: refills
    refilled = lanes.LANES + 1
    assert batch_dop853.task_size(count, lanes.LANES) > refilled
    probe = _starts(scene, 1, seed=1)
    easy = _starts(scene, count - 1, seed=2, scale=0.01)
    hard = _starts(scene, count - 1, seed=3)
    hard[:, 0:3] *= 4.0
    alone = integrate_arrays(scene.compiled, scene.integrator, scene.times, probe)
    for neighbours in (easy, hard):
        for row in (0, refilled):
            y0s = np.insert(neighbours, row, probe[0], axis=0)
            mixed = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
            np.testing.assert_array_equal(mixed.y[row], alone.y[0])
            assert mixed.steps[row] == alone.steps[0]
    assert integrate_arrays(scene.compiled, scene.integrator, scene.times, hard).steps.min() > alone.steps[0]


def test_taylor_lanes_take_the_steps_of_the_single_trajectory_kernel():
    """The lane kernel against ``taylor.run`` on each trajectory alone (``single_kernel_runs``), easy and hard
    trajectories mixed, each with its own A and Newtonian coefficient: the same number of steps, and the same
    outputs to rounding (its vector sums fuse multiply and add in another order; 1e-13 is a thousand
    tolerances below the 1e-10 asked)."""
    scene = _scene("taylor")
    y0s = _starts(scene, 11, seed=7)
    y0s[::3, 0:3] *= 4.0
    P, _ = fixed_point_rows([*SHORT, "integrator=taylor", *SETTINGS["taylor"], "output.euler_angles=false"],
                            2.0 * np.linspace(0.9, 1.1, len(y0s)), 0.5 * np.linspace(0.0, 2.0, len(y0s)))
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, P)
    out, steps = single_kernel_runs(scene.compiled, P, scene.integrator, scene.times, y0s)
    assert steps.min() < steps.max() / 2  # the mix: some take twice the steps of others
    np.testing.assert_array_equal(batch.steps, steps)
    np.testing.assert_allclose(batch.y, out, rtol=0, atol=1e-13)


def test_taylor_batch_reaches_1e_10_at_the_benchmark_setting():
    """Issue 14's accuracy target at the benchmark's setting (``benchmarks/batch_heyoka.py``: perturbed ω0,
    t ∈ [0, 10], tol 1e-10, order 13): every final state within 1e-10 of scipy's DOP853 at rtol = atol = 1e-13."""
    scene = compose_scene(["experiment=perf_reference", "time.end=10", "time.n_output=11", "integrator=taylor",
                           "integrator.tol=1e-10", "integrator.order=13"])
    y0s = _starts(scene, 3, seed=8)
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
    assert batch.steps.min() > 50
    assert np.max(np.abs(batch.y[:, -1] - _scipy_reference(scene, y0s))) <= 1e-10


def _scipy_reference(scene, y0s):
    """Final states from scipy's DOP853 at rtol = atol = 1e-13 on the Python right-hand side (independent code)."""
    span = (scene.times[0], scene.times[-1])
    return np.array([solve_ivp(scene.system.rhs, span, y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
                     for y0 in y0s])


@pytest.mark.parametrize("euler_angles", [False, True])
def test_auto_reaches_the_accuracy_asked_on_every_trajectory(euler_angles):
    scene = _scene("auto", euler_angles, ["accuracy=1e-8"])
    y0s = _starts(scene, 4, seed=4)
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
    assert batch.settings["auto_method"] == "taylor" and batch.settings["accuracy"] == 1e-8
    assert scene.integrator.attributes() == {"accuracy": 1e-8}  # the choice is the batch's record, not auto's state
    error = np.max(np.abs(batch.y[:, -1] - _scipy_reference(scene, y0s)))
    assert error <= 1e-8


@pytest.mark.parametrize("integrator", ["dop853_numba", "taylor"])
def test_each_kernel_meets_its_tolerance_against_scipy(integrator):
    """Local tolerance 1e-10 over t ∈ [0, 2] (about 20 steps): the final error stays within a few hundred
    tolerances (the error/tolerance ratios measured for the Taylor method in auto.py span 24 to 470)."""
    scene = _scene(integrator)
    y0s = _starts(scene, 3, seed=5)
    batch = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
    error = np.max(np.abs(batch.y[:, -1] - _scipy_reference(scene, y0s)))
    assert 0 < error <= 500 * 1e-10


@pytest.mark.parametrize("integrator", ["dop853_numba", "taylor"])
def test_a_failing_trajectory_is_marked_and_the_others_are_kept(integrator):
    scene = _scene(integrator)
    y0s = _starts(scene, 6, seed=6)
    bad = y0s.copy()
    bad[1, 0:3] = 1e200  # ω² overflows
    good = integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s)
    marked = integrate_arrays(scene.compiled, scene.integrator, scene.times, bad, failures="mark")
    assert marked.failed.tolist() == [False, True, False, False, False, False]
    assert np.isnan(marked.y[1, 1:]).all()
    kept = [0, 2, 3, 4, 5]  # the failed trajectory's lane takes the fifth and sixth
    np.testing.assert_array_equal(marked.y[kept], good.y[kept])
    with pytest.raises(IntegrationError, match=f"^trajectory 1 of the batch failed with {integrator}: it became "
                                               "non-finite$"):
        integrate_arrays(scene.compiled, scene.integrator, scene.times, bad)


def test_bad_requests_are_one_sentence_config_errors():
    scene = _scene("taylor")
    y0s = _starts(scene, 2)
    # (taylor refuses only a time-dependent plugin torque: tests/test_taylor_series.py)
    with pytest.raises(ConfigError, match="^times must be a non-empty 1-D array of finite, strictly increasing"):
        integrate_arrays(scene.compiled, scene.integrator, np.array([0.0, 1.0, 1.0]), y0s)
    with pytest.raises(ConfigError, match="^failures='skip' must be 'raise' or 'mark'$"):
        integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s, failures="skip")
    scipy_scene = compose_scene([*SHORT, "integrator=dop853"])
    with pytest.raises(ConfigError, match="batch kernels run integrator rk4, rk4_numba, dop853_numba, taylor or auto, "
                                          "not dop853$"):
        integrate_arrays(scene.compiled, scipy_scene.integrator, scene.times, y0s)
