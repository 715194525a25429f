"""``dop853``'s numpy stepper against scipy's own DOP853, side by side: the same steps, the same numbers, bit for bit."""

import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.integrate import DOP853 as ScipyDOP853

from gyrolab import compose_scene
from gyrolab.plugins.integrators.dop853_stepper import DOP853


def _steps(solver_class, fun, t0, y0, t_bound, rtol, atol, max_step=np.inf):
    """Every accepted step's time and state, the dense output at five points of each step, evaluations, status."""
    with warnings.catch_warnings():  # scipy warns when it raises rtol to 100 ε
        warnings.simplefilter("ignore", UserWarning)
        solver = solver_class(fun, t0, y0, t_bound, rtol=rtol, atol=atol, max_step=max_step)
    times, states, dense, messages = [], [], [], []
    while solver.status == "running":
        messages.append(solver.step())
        if solver.status == "failed":
            break
        times.append(solver.t)
        states.append(solver.y.copy())
        dense.append(solver.dense_output()(np.linspace(solver.t_old, solver.t, 5)))
    return np.array(times), np.array(states), np.array(dense), solver.nfev, solver.status, messages[-1]


def _top():
    scene = compose_scene(["time.end=30"])
    return scene.system.rhs, scene.system.initial_state()


def _forced_pendulum(t, y):
    return np.array([y[1], -np.sin(y[0]) + 0.3 * np.cos(1.1 * t)])


CASES = {
    "default top": lambda: (*_top(), 0.0, 30.0, 1e-10, 1e-10, np.inf),
    "loose tolerances": lambda: (*_top(), 0.0, 5.0, 1e-3, 1e-6, np.inf),
    "rtol below scipy's floor": lambda: (*_top(), 0.0, 5.0, 1e-16, 1e-16, np.inf),
    "max_step": lambda: (*_top(), 0.0, 5.0, 1e-8, 1e-8, 0.01),
    "time-dependent": lambda: (_forced_pendulum, np.array([2.0, 0.0]), 0.0, 50.0, 1e-8, 1e-9, np.inf),
    "backward in time": lambda: (_forced_pendulum, np.array([2.0, 0.0]), 10.0, -20.0, 1e-6, 1e-9, np.inf),
    "stiff (rejected steps)": lambda: (lambda t, y: -1000 * (y - np.cos(t)), np.array([0.0]), 0.0, 1.0, 1e-6, 1e-9,
                                       np.inf),
    "blow-up (too small a step)": lambda: (lambda t, y: y ** 2, np.array([1.0]), 0.0, 2.0, 1e-8, 1e-8, np.inf),
}


@pytest.mark.parametrize("case", CASES)
def test_same_steps_and_numbers_as_scipy(case):
    fun, y0, t0, t_bound, rtol, atol, max_step = CASES[case]()
    ours = _steps(DOP853, fun, t0, y0, t_bound, rtol, atol, max_step)
    scipy = _steps(ScipyDOP853, fun, t0, y0, t_bound, rtol, atol, max_step)
    assert len(ours[0]) == len(scipy[0]) > 3
    for mine, theirs in zip(ours[:3], scipy[:3]):
        np.testing.assert_array_equal(mine, theirs)
    assert ours[3:] == scipy[3:]  # evaluations, final status, last message


def test_default_run_does_not_import_scipy_integrate():
    """The reason the stepper exists: ``scipy.integrate`` costs the default run ~0.4 CPU s to import."""
    code = ("import sys; from gyrolab import run; run(['time.end=1', 'time.n_output=11']); "
            "print('scipy.integrate' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip().splitlines()[-1] == "False"
