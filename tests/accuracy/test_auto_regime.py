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


# A scene on the order-N series' orbit, moved off it in p0 by less than auto's start tolerance (below: the series is
# taken, its own predicted error plus the move being far below the accuracy) or by a few times it (above: refused,
# Taylor). The tolerance is the smaller of accuracy/(10·safety) and the 1e-12 beyond which the regime's domain check
# warns that the orbit re-seats the scene's p0 (a warning: no confidence). Far off the orbit, the screen on the
# scene's own motion rules the regime out before any series is built.
ACCURACY = 1e-7
START_TOLERANCE = min(ACCURACY / 10, 1e-12)  # integrator.safety = 1


@pytest.fixture(scope="module")
def on_series_orbit():
    """(overrides starting the scene on an order-N series' orbit but p0, its p0, N, N's predicted final error).

    N is the lowest listed order whose own predicted error (per period, ``series_candidates``), grown linearly
    over the span as auto extrapolates it, is below a quarter of the accuracy.
    """
    scene = compose_scene([*BASE, f"accuracy={ACCURACY}"])
    # the closed forms (listed first, no prediction) start ~1e-5 away from the exact orbit here: refused at 1e-8
    for regime, predicted in SmallParameter().series_candidates(scene.system, ACCURACY)[1:]:
        predicted *= 1.0 / regime.period(scene.system)  # time.end = 1
        if predicted < ACCURACY / 4:
            break
    p0, q0 = regime.initial_state(scene.system)[:2]
    return [*BASE, f"initial.q0={float(q0)!r}"], float(p0), regime.series_order, predicted


@pytest.mark.parametrize("move, taken", [(0.3 * START_TOLERANCE, True), (3 * START_TOLERANCE, False),
                                         (3e-8, False), (0.05, False)])
def test_auto_takes_the_series_only_within_the_start_tolerance_of_its_orbit(on_series_orbit, move, taken):
    from gyrolab.plugins.regimes import small_parameter

    overrides, p0, order, predicted = on_series_orbit
    assert predicted + 2 * move < ACCURACY / 2 if taken else move > START_TOLERANCE  # the premise of each case
    lookups = small_parameter._series.cache_info()
    ds = compose_scene([*overrides, f"initial.p0={p0 + move!r}", f"accuracy={ACCURACY}"]).run()
    assert ds.attrs["auto_method"] == ("regime small_parameter" if taken else "taylor")
    if taken:  # that order, or a lower one if the scene also starts within the tolerance of its orbit and it meets
        assert ds.attrs["regime_order"] <= order
    assert _error(ds) <= ACCURACY
    if move > 1e-2:  # far beyond the screen's margin (~6e-3 here): no series was even looked up
        after = small_parameter._series.cache_info()
        assert (after.hits, after.misses) == (lookups.hits, lookups.misses)


def test_series_orbits_are_periodic_within_the_screen_period_range(on_series_orbit):
    """The screen's premises on this scene: each listed variant returns to its start after its period, and that
    period lies within ``period_spread`` of the closed forms' period."""
    scene = compose_scene([*on_series_orbit[0], f"initial.p0={on_series_orbit[1]!r}", f"accuracy={ACCURACY}"])
    base = SmallParameter()
    for regime, _ in base.series_candidates(scene.system, ACCURACY):
        period = regime.period(scene.system)
        ends = regime.solution(scene.system, np.array([0.0, period]))
        assert np.max(np.abs(ends[1] - ends[0])) < 1e-12
        assert base.period(scene.system) / base.period_spread <= period <= base.period(scene.system) * base.period_spread
