"""The kernels' call of a compiled model, and their cache: a second process compiles nothing."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np

import pytest

from gyrolab import compose_scene
from gyrolab.kernels import models
from gyrolab.kernels.model import python_rhs


def test_the_compiled_right_hand_side_is_the_systems_own():
    """``models.evaluate`` (the call every kernel inlines: the generated kernel through the address in p) against
    the system's numpy ``rhs``, which it was traced from."""
    scene = compose_scene(["experiment=perf_reference"])
    y = np.array([0.3, -1.1, 2.2, 0.48, 0.6, 0.64])
    compiled = np.empty(6)
    models.evaluate(0.0, y, scene.compiled.params, compiled)
    np.testing.assert_allclose(compiled, scene.system.rhs(0.0, y), rtol=1e-14, atol=1e-15)
    assert np.all(compiled != 0.0)  # every component computed


@pytest.mark.parametrize("overrides", [["force=[uniform_gravity,newtonian,magnetic]"], ["output.euler_angles=false"],
                                       ["experiment=gyrostat"]])
def test_the_python_right_hand_side_is_the_systems_own_bit_for_bit(overrides):
    """``python_rhs`` (what scipy's solvers call) against the numpy ``rhs`` it was traced from, at random states and
    times: the same operations in the same order, so the same numbers to the last bit."""
    system = compose_scene(overrides).system
    fast = python_rhs(system)
    assert fast is not system.rhs
    states = system.initial_state() + np.random.default_rng(7).normal(size=(500, system.state_size))
    for i, y in enumerate(states):
        np.testing.assert_array_equal(fast(0.37 * i, y), system.rhs(0.37 * i, y))


class _Toy:
    name, state_size = "toy", 3

    def rhs(self, t, y):
        return np.array([1.0 / y[0], np.sqrt(y[1]) * t, y[0] ** y[1]])


def test_the_python_right_hand_side_answers_as_numpy_where_python_raises():
    """1/0 and √−1 raise in Python and (−8) ** (1/3) is complex, where numpy gives inf and nan: the numpy right-hand
    side answers there."""
    toy = _Toy()
    fast = python_rhs(toy)
    np.testing.assert_array_equal(fast(2.0, np.array([4.0, 9.0, 0.5])), [0.25, 6.0, 4.0 ** 9.0])
    with np.errstate(all="ignore"):
        for y in ([0.0, -1.0, 2.0], [-8.0, 1 / 3, 0.0]):
            ours, numpy = fast(2.0, np.array(y)), toy.rhs(2.0, np.array(y))
            assert ours.dtype == float and not np.isfinite(ours).all()
            np.testing.assert_array_equal(ours, numpy)
    toy.rhs = lambda t, y: np.array([y[0] if y[1] > 0 else -y[0], 0.0])  # a branch on the state: not traceable
    assert python_rhs(toy) == toy.rhs


_CHILD = r'''
import json, sys
import numpy as np
from numba.core import event
from gyrolab import compose_scene
from gyrolab.kernels import models, taylor_series, rk4
import numba

compiled = compose_scene(["experiment=perf_reference"]).compiled
p = compiled.params
y0 = np.array([0.3, -1.1, 2.2, 0.48, 0.6, 0.64])
with event.install_recorder("numba:compile") as rec:
    y, Y, f = y0.copy(), np.zeros((3, 6)), np.empty(6)
    rk4.run(p, np.array([0.0, 0.1, 0.2]), np.array([5, 5]), y, Y, 1, 3)
    models.evaluate(0.0, y0, p, f)
compiled = sorted({ev.data["dispatcher"].py_func.__qualname__ for _, ev in rec.buffer if "dispatcher" in ev.data})
print(json.dumps({"compiled": compiled, "Y": Y.tolist(), "unused": [len(taylor_series.coefficients.signatures)]}))
'''


def test_fresh_cache_compiles_the_form_only_and_a_second_process_loads_it(tmp_path):
    """In a fresh kernel cache an RK4 run does not compile the Taylor code; a second process on that cache compiles
    nothing (numba loads every kernel from disk) and gives the same numbers."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def child(which: str) -> dict:
        out = subprocess.run([sys.executable, "-c", _CHILD, which], env=env, capture_output=True, text=True,
                             check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    first = child("first")
    assert "run" in first["compiled"] and first["unused"] == [0]
    second = child("second")
    assert second["compiled"] == []
    assert second["Y"] == first["Y"]


def test_the_companions_model_moves_rounded_numbers_by_one_ulp_and_exact_ones_not():
    """``rounding_moved``: the reference scene's inertias 2, 1.5, 1 are exact doubles (nothing rounded them) and stay;
    its torque's numbers (from the decimal centre-of-mass direction) move by exactly one unit in the last place."""
    from gyrolab.kernels.layout import TRACED_FIRST_CONSTANT, TRACED_TAIL
    from gyrolab.kernels.model import rounding_moved

    compiled = compose_scene(["experiment=perf_reference"]).compiled
    before = compiled.params[TRACED_FIRST_CONSTANT:-TRACED_TAIL]
    after = rounding_moved(compiled).params[TRACED_FIRST_CONSTANT:-TRACED_TAIL]
    exact = np.isin(before, [2.0, 1.5, 1.0, 0.5, 0.0, -1.0])
    assert exact.any() and (~exact).any()
    np.testing.assert_array_equal(after[exact], before[exact])
    ulps = np.abs(after[~exact] - before[~exact]) / np.spacing(np.abs(before[~exact]))
    assert np.all((ulps >= 0.5) & (ulps <= 1.0))  # one ulp (half an ulp below a power of two)
