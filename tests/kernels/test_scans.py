"""The contract's compiled scans agree with numpy's definitions (``np.isfinite(a).all()``; finite ends and
``np.diff(t) > 0`` everywhere) on arrays with every kind of non-finite value at every position class."""

import numpy as np
import pytest

from gyrolab.kernels import scans


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf, None])
@pytest.mark.parametrize("where", [0, 1, 500, -1])
def test_all_finite_matches_numpy(bad, where):
    a = np.random.default_rng(3).normal(scale=1e300, size=(101, 9))
    a[5, 2] = 5e-324  # a subnormal is finite
    if bad is not None:
        a.reshape(-1)[where] = bad
    assert scans.all_finite(a) == bool(np.isfinite(a).all())
    assert scans.all_finite(np.ascontiguousarray(a[0])) == bool(np.isfinite(a[0]).all())


@pytest.mark.parametrize("change", ["none", "repeat", "decrease", "nan inside", "inf end", "nan start"])
def test_increasing_matches_numpy(change):
    t = np.linspace(0.0, 3.0, 1001)
    if change == "repeat":
        t[400] = t[399]
    elif change == "decrease":
        t[700] = t[698]
    elif change == "nan inside":
        t[500] = np.nan
    elif change == "inf end":
        t[-1] = np.inf
    elif change == "nan start":
        t[0] = np.nan
    expected = bool(np.isfinite(t[[0, -1]]).all() and (np.diff(t) > 0).all())
    assert scans.increasing(t) == expected == (change == "none")
    assert scans.increasing(t[:1]) == bool(np.isfinite(t[0]))
