"""auto's pilot and screen statistics (``_error_growth``, ``_comes_back``): the compiled form and the Python form
(used without a compiled model) agree with each other and with numpy written out independently."""

import numpy as np
import pytest

from gyrolab.plugins.integrators.auto import _comes_back, _error_growth, _fast

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
