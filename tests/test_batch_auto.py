"""integrate_batch with integrator=auto: one choice for the batch, the vectorised kernel, and auto's error promise."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_batch
from gyrolab.accuracy.auto import Auto
from gyrolab.plugins.integrators.step_guard import compiled_rhs

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
