"""Batch mode (``integrate_batch``) gives, trajectory by trajectory, the single-run results; with integrator=auto,
one choice for the batch, the vectorised kernel, and auto's error promise."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.accuracy.auto import Auto
from gyrolab.batch.integrate import integrate_batch
from gyrolab.errors import ConfigError
from gyrolab.plugins.integrators.step_guard import compiled_rhs

SHORT = ["time.end=2", "time.n_output=11", "integrator.step=0.01"]


@pytest.mark.parametrize("integrator", ["rk4_numba", "rk4"])
@pytest.mark.parametrize("euler_angles", [False, True])  # (ω, γ) by blocks; (ω, γ, α) one per thread
def test_batch_equals_single_runs(integrator, euler_angles):
    scene = compose_scene([f"integrator={integrator}", f"output.euler_angles={str(euler_angles).lower()}", *SHORT])
    rng = np.random.default_rng(0)
    y0s = np.tile(scene.system.initial_state(), (5, 1))
    y0s[:, 0:3] += rng.normal(scale=0.1, size=(5, 3))
    batch = integrate_batch(scene, y0s)
    for j, y0 in enumerate(y0s):
        single = scene.integrator.integrate(scene.system.rhs, scene.times, y0, None, scene.system.compiled_model())
        np.testing.assert_allclose(batch.y[j], single.y, rtol=0, atol=1e-13)


def test_batch_rejects_wrong_shapes():
    scene = compose_scene(["integrator=rk4_numba", *SHORT])
    with pytest.raises(ConfigError, match="shape"):
        integrate_batch(scene, np.zeros((3, 4)))
    with pytest.raises(ConfigError, match="NaN"):
        integrate_batch(scene, np.full((2, scene.system.state_size), np.nan))


# ---- integrator=auto: one choice for the batch ----------------------------------------------------------------------

ACCURACY = 1e-8


@pytest.fixture(scope="module")
def batch():
    scene = compose_scene(["experiment=perf_reference", "integrator=auto", f"accuracy={ACCURACY}", "time.end=10",
                           "time.n_output=11", "output.euler_angles=false"])
    rng = np.random.default_rng(1)
    y0s = np.tile(scene.system.initial_state(), (9, 1))
    y0s[:, 0:3] += rng.normal(scale=0.1, size=(9, 3))
    return scene, y0s, integrate_batch(scene, y0s)


def test_auto_batch_runs_the_vectorised_kernel_of_one_choice(batch):
    _, y0s, solution = batch
    assert solution.settings["auto_method"] in ("taylor", "dop853_numba")
    assert 1 <= solution.settings["auto_sampled_trajectories"] <= 3
    assert solution.y.shape[0] == len(y0s)


def test_auto_batch_keeps_its_error_promise_against_a_tight_reference(batch):
    """Every trajectory's final state within ε of scipy's DOP853 at rtol = atol = 1e-13 (an independent method)."""
    scene, y0s, solution = batch
    fun = compiled_rhs(scene.system.compiled_model())
    for j in range(len(y0s)):
        ref = solve_ivp(fun, (scene.times[0], scene.times[-1]), y0s[j], method="DOP853", rtol=1e-13, atol=1e-13,
                        t_eval=scene.times).y.T
        assert np.max(np.abs(solution.y[j, -1] - ref[-1])) <= ACCURACY, j


def test_auto_batch_agrees_with_per_point_auto_within_the_promise(batch):
    scene, y0s, solution = batch
    compiled = scene.system.compiled_model()
    for j in (0, 4, 8):
        single = Auto(accuracy=ACCURACY).integrate(compiled_rhs(compiled), scene.times, y0s[j], None, compiled)
        assert np.max(np.abs(solution.y[j, -1] - single.y[-1])) <= 2 * ACCURACY, j
