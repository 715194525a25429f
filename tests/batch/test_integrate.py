"""Batch mode gives, trajectory by trajectory, the single-run results."""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_batch
from gyrolab.errors import ConfigError

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
