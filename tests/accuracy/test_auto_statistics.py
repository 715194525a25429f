"""auto's pilot and screen statistics (``_error_growth``, ``_comes_back``): the compiled form and the Python form
(used without a compiled model) agree with each other and with numpy written out independently; when the
pilot measures again (``RECENTRE``), its recorded prediction still bounds the error; and its order
(``measured_order``) stays between Jorba & Zou's and the cap near the floor."""

import math

import numpy as np
import pytest

from gyrolab.accuracy.auto import _comes_back, _error_growth, _fast, measured_order

TIMES = np.linspace(0.0, 30.0, 361)


def forms(function):
    return [function, _fast(function, compiled=object())]  # any compiled model: the numba form


@pytest.mark.parametrize("q", [2.0, 3.0])
def test_error_growth_is_the_envelope_and_its_log_log_slope(q):
    rng = np.random.default_rng(7)
    tight = rng.normal(size=(len(TIMES), 6))
    # an error growing as t^q whose pointwise value dips through zero (periodic motion), in one component at a time
    error = 1e-9 * TIMES ** q * np.abs(np.cos(TIMES))
    loose = tight.copy()
    loose[np.arange(len(TIMES)), np.arange(len(TIMES)) % 6] += error
    envelope = np.maximum.accumulate(error)
    late = TIMES >= TIMES[-1] / 4
    expected = np.polyfit(np.log(TIMES[late]), np.log(envelope[late]), 1)[0]
    for form in forms(_error_growth):
        final, slope = form(loose, tight, TIMES)
        assert final == pytest.approx(envelope[-1], rel=1e-12)
        assert slope == pytest.approx(expected, rel=1e-10)
        assert abs(slope - q) < 0.3  # the envelope of t^q |cos t| grows as t^q


def test_error_growth_without_a_late_error_or_with_nan():
    tight = np.ones((len(TIMES), 6))
    for form in forms(_error_growth):
        final, slope = form(tight, tight, TIMES)
        assert final == 0.0 and np.isnan(slope)
        broken = tight.copy()
        broken[200, 3] = np.nan
        final, slope = form(broken, tight, TIMES)
        assert np.isnan(final) and np.isnan(slope)


def test_comes_back_within_the_margin_plus_the_grid_step():
    t = np.linspace(5.0, 7.0, 101)  # one return to the start near t = 2π
    y = np.zeros((len(t) + 1, 6))
    y[1:, 0], y[1:, 1] = np.sin(t), np.cos(t) - 1.0
    y0 = np.zeros(6)
    jump = np.max(np.abs(np.diff(y[1:], axis=0)))
    nearest = np.min(np.max(np.abs(y[1:] - y0), axis=1))
    for form in forms(_comes_back):
        assert form(y, y0, 0.0) == (nearest <= jump)
        assert form(y, y0, nearest - jump + 1e-12)
        assert not form(y, y0, nearest - jump - 1e-12)
        shifted = y0 + np.array([0, 0, 0, 0, 0, 0.5])  # far in the sixth component only
        assert not form(y, shifted, 0.1)




#: a slow swing over a short span: the perturbations grow ~3.5× after the pilot (the tangent flow), no more than the
#: pilot's power law already assumes (over t = 20 the swing amplifies them 118×, and the prediction is then tighter)
SHORT_SWING = ["initial.r0=1e-3", "initial.p0=0", "initial.q0=0", "time.end=5", "time.n_output=51"]


@pytest.mark.parametrize("overrides, accuracy, rounds", [
    (SHORT_SWING, 1e-6, 2),  # the first prediction is ~180× looser than the pilot's τ: measured again there
    (["experiment=perf_reference"], 1e-6, 1),  # 13× looser: within RECENTRE, taken from the first round
], ids=["re-measured", "extrapolated"])
def test_a_prediction_far_looser_than_the_pilot_is_measured_again(monkeypatch, overrides, accuracy, rounds):
    from gyrolab import compose_scene
    from gyrolab.accuracy import auto
    from gyrolab.accuracy import calibration as auto_calibration
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    taus, pilot = [], auto.Auto._pilot
    monkeypatch.setattr(auto.Auto, "_pilot", lambda self, *a: taus.append(a[4]) or pilot(self, *a))
    scene = compose_scene([*overrides, "integrator=auto", f"accuracy={accuracy}"])
    y0 = scene.system.initial_state()
    method = auto.Auto(accuracy=accuracy)
    method.prepare(scene.system)
    solution = method.integrate(scene.system.rhs, scene.times, y0, None, scene.compiled)
    assert len(taus) == rounds
    if rounds == 2:
        assert taus[1] > auto_calibration.RECENTRE * taus[0]
    # either way the recorded prediction bounds the actual error (truth: Taylor at tol 1e-17, error ~1e-14)
    truth = Taylor(tol=1e-17).integrate(scene.system.rhs, scene.times[[0, -1]], y0, None, scene.compiled).y[-1]
    error = float(np.max(np.abs(solution.y[-1] - truth)))
    assert error <= solution.choice.promised <= accuracy


def jorba_zou(tol):
    """Jorba & Zou's order ⌈−ln(tol)/2 + 1⌉ (Exp. Math. 14, 2005, §3.2), within the kernel's range 4 … 60."""
    return min(60, max(4, math.ceil(-math.log(tol) / 2 + 1)))


def test_measured_order_is_higher_than_jorba_zou_at_loose_tolerances_and_theirs_near_the_floor():
    """A measured step costs 2–3× a bare one, so ``auto`` takes a higher order than Jorba & Zou's where the run stays
    clear of double precision's floor, and theirs at most from the run tolerance 3e-13 down (where the estimate turns
    to a twin run or companions, and higher orders sent the reference scene's ε = 1e-10 to two companions)."""
    cap = jorba_zou(3e-13)
    for tol in np.logspace(-4, -18, 57):
        order = measured_order(float(tol))
        assert jorba_zou(tol) <= order <= max(cap, jorba_zou(tol)), tol
    assert measured_order(1e-9) > jorba_zou(1e-9)
    assert measured_order(1e-15) == jorba_zou(1e-15)
