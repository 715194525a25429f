"""integrator=auto on a fast-spin regime scene: the analytic series when it suffices, Taylor when not.

The scene starts on the periodic orbit of the small_parameter regime (seed 000 read consistently,
body I of the verification report); errors are judged against the extended-precision reference.
"""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.physics.reference import fixed_point_reference
from gyrolab.plugins.regimes.small_parameter import SmallParameter

MU, GAMMA = 32.0, 0.5
RC = [0.5, 0.3, float(np.sqrt(1 - 0.34))]
BASE = ["body.a=2.0", "body.b=1.5", f"body.com_direction=[{RC[0]},{RC[1]},{RC[2]!r}]", "force.newtonian.k=0.3",
        "initial.phi0=1.5707963267948966", "initial.psi0=0.0", f"initial.r0={MU!r}",
        f"initial.theta0={float(np.arccos(GAMMA / MU))!r}", "time.end=1.0", "time.n_output=21",
        "integrator=auto"]


@pytest.fixture(scope="module")
def on_orbit():
    """Overrides that start the scene on the regime's periodic orbit (p0, q0 of the analytic orbit)."""
    scene = compose_scene([*BASE, "accuracy=1e-3"])
    p0, q0 = SmallParameter().initial_state(scene.system)[:2]
    return [*BASE, f"initial.p0={float(p0)!r}", f"initial.q0={float(q0)!r}"]


def _error(ds):
    scene_y0 = np.concatenate([ds.omega.values[0], ds.gamma.values[0]])
    ref = fixed_point_reference([2.0, 1.5, 1.0], RC, 0.3, scene_y0, ds.time.values).astype(float)
    return np.max(np.abs(np.concatenate([ds.omega.values, ds.gamma.values], axis=1) - ref))


@pytest.mark.parametrize("accuracy, method", [(1e-3, "regime small_parameter"), (1e-10, "taylor")])
def test_auto_picks_the_series_only_when_it_suffices(on_orbit, accuracy, method):
    ds = compose_scene([*on_orbit, f"accuracy={accuracy}"]).run()
    assert ds.attrs["auto_method"] == method
    assert _error(ds) <= accuracy
    assert ds.attrs["auto_predicted_error"] <= accuracy


def test_auto_ignores_the_series_off_its_orbit():
    ds = compose_scene([*BASE, "initial.p0=0.3", "initial.q0=0.0", "accuracy=1e-3"]).run()
    assert ds.attrs["auto_method"] == "taylor"
