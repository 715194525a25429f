"""The lean paths of a run (issue 12, item 4) give the same results as the plain ones.

* The run dataset's values are those of an independent recomputation from the integrated states (the formulas
  written out here, not the system's code).
* ``integrator=auto`` rules out a regime whose orbit the scene misses from the scene's own motion over the
  orbit's period range, before any series start is evaluated; over a span too short for that, it skips the
  other series orders once the first order's start is missed by far. It must still take the series on the
  orbit (``tests/accuracy/test_auto_regime.py``, ``tests/plugins/regimes/test_small_parameter.py``).
"""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.output import dataset

FIXED_POINT = ["time.end=2", "time.n_output=21"]  # the default scene: gravity + Newtonian centre, Euler angles


def _built(overrides):
    """(scene, solution, dataset) of one integration of the scene."""
    scene = compose_scene(overrides)
    solution = scene.integrator.integrate(scene.system.rhs, scene.times, scene.system.initial_state(), None,
                                          scene.compiled)
    return scene, solution, dataset.build_dataset(scene, solution)


def test_dataset_values_match_an_independent_recomputation():
    scene, solution, ds = _built(FIXED_POINT)
    y = solution.y
    omega, gamma, alpha = y[:, 0:3], y[:, 3:6], y[:, 6:9]
    inertia = np.array([2.0, 1.5, 1.0])  # body.a, body.b of the default config, C = 1
    weight = np.array([0.3, 0.2, np.sqrt(1 - 0.3**2 - 0.2**2)])  # body.com_direction, |U| = 1 (c² = 1)
    n = 0.5  # force.newtonian.k · c²
    np.testing.assert_array_equal(ds.time.values, scene.times)
    np.testing.assert_array_equal(ds.omega.values, omega)
    np.testing.assert_array_equal(ds.gamma.values, gamma)
    np.testing.assert_array_equal(ds.alpha.values, alpha)
    # Euler–Poisson energy ½ω·Iω − U·γ + ½N γ·Iγ, area integral Iω·γ, |γ|, (α, γ) orthonormality
    energy = 0.5 * (inertia * omega**2).sum(1) - gamma @ weight + 0.5 * n * (inertia * gamma**2).sum(1)
    tight = {"rtol": 0, "atol": 1e-14}
    np.testing.assert_allclose(ds.energy.values, energy, **tight)
    np.testing.assert_allclose(ds.area_integral.values, (inertia * omega * gamma).sum(1), **tight)
    np.testing.assert_allclose(ds.gamma_norm.values, np.sqrt((gamma**2).sum(1)), **tight)
    frame = np.maximum(np.abs(np.sqrt((alpha**2).sum(1)) - 1), np.abs((alpha * gamma).sum(1)))
    np.testing.assert_allclose(ds.frame_error.values, frame, **tight)
    drift = np.max(np.abs(energy - energy[0]))
    assert ds.energy.attrs["max_abs_drift"] == pytest.approx(drift, abs=1e-14)
    # γ/|γ| = (sin θ sin φ, sin θ cos φ, cos θ); α_z = sin ψ sin θ, β_z = −cos ψ sin θ (β = γ × α), to within
    # the integrated frame's departure from orthonormality (DOP853 keeps |γ| = 1 to ~1e-10 here)
    theta, phi, psi = ds.theta.values, ds.phi.values, ds.psi.values
    unit = gamma / np.sqrt((gamma**2).sum(1))[:, None]
    np.testing.assert_allclose(np.cos(theta), unit[:, 2], **tight)
    np.testing.assert_allclose(np.sin(theta) * np.sin(phi), unit[:, 0], **tight)
    np.testing.assert_allclose(np.sin(theta) * np.cos(phi), unit[:, 1], **tight)
    beta_z = gamma[:, 0] * alpha[:, 1] - gamma[:, 1] * alpha[:, 0]
    loose = {"rtol": 0, "atol": 1e-14 + 10 * max(frame.max(), np.abs(ds.gamma_norm.values - 1).max())}
    np.testing.assert_allclose(np.sin(psi) * np.sin(theta), alpha[:, 2], **loose)
    np.testing.assert_allclose(-np.cos(psi) * np.sin(theta), beta_z, **loose)
    assert np.all(np.abs(np.diff(phi)) < np.pi) and np.all(np.abs(np.diff(psi)) < np.pi)  # unwrapped
    for name, variable in {**ds.data_vars, **ds.coords}.items():
        assert variable.attrs.get("units") and variable.attrs.get("long_name"), name


@pytest.mark.parametrize("end, evaluated", [(0.5, 0), (0.25, 1)])
def test_auto_evaluates_at_most_one_series_order_off_the_orbit(monkeypatch, end, evaluated):
    """Off the orbit by ~0.1 with accuracy 1e-9. A span of at least twice the orbit's period (0.196 here, the
    screen's period range reaching 0.39): the scene's own motion over that range rules the regime out before
    any series start is evaluated. A shorter span: the first order's start rules out the others."""
    from gyrolab.plugins.regimes.small_parameter import SmallParameter

    theta0 = float(np.arccos(0.5 / 32.0))
    scene = compose_scene(["body.a=2.0", "body.b=1.5", "force.newtonian.k=0.3", "initial.r0=32.0",
                           f"initial.theta0={theta0!r}", "initial.p0=0.3", "initial.q0=0.0", f"time.end={end}",
                           "time.n_output=6", "integrator=auto", "accuracy=1e-9", "output.euler_angles=false"])
    assert SmallParameter().period(scene.system) == pytest.approx(0.196, abs=1e-3)
    ladder = SmallParameter().series_candidates(scene.system, 1e-9)
    assert sum(np.isfinite(e) for _, e in ladder) >= 2  # the check below means something
    starts = []
    original = SmallParameter.initial_state

    def counted(self, system):
        starts.append(self.series_order)
        return original(self, system)

    monkeypatch.setattr(SmallParameter, "initial_state", counted)
    ds = scene.run()
    assert ds.attrs["auto_method"] == "taylor"
    assert len([order for order in starts if order is not None]) == evaluated


def test_a_run_does_not_import_dask_array():
    # xarray probes a plain array for chunked duck arrays by importing dask.array (~0.4 s) when dask is installed;
    # gyrolab.output.dataset installs gyrolab.compat's guards, which answer without the import
    pytest.importorskip("dask")
    import subprocess
    import sys

    code = ("import sys\nfrom gyrolab import compose_scene\n"
            "compose_scene(['time.end=1', 'time.n_output=11', 'integrator=rk4', 'integrator.step=0.01']).run()\n"
            "print('dask.array' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "False", result.stdout + result.stderr


def test_the_scene_attributes_are_computed_once_and_shared_read_only():
    scene = compose_scene(FIXED_POINT)
    first, second = scene.run(), scene.run()
    assert list(first.attrs) == list(second.attrs)  # the same attributes in the same order
    assert first.attrs["title"] == second.attrs["title"] and first.attrs["config"] == second.attrs["config"]
    stored = first.attrs["initial_omega"]
    assert stored is not scene.system.initial.omega  # a copy: the system's initial state stays its own
    np.testing.assert_array_equal(stored, scene.system.initial.omega)
    with pytest.raises(ValueError, match="read-only"):
        stored[0] = 1.0  # shared by every run's dataset: not to be changed through one of them


def test_a_scenes_later_datasets_copy_its_first_ones_layout_and_equal_a_fresh_build():
    """The second dataset of a scene copies the first one's layout with its own data, attributes and encodings: what
    a fresh scene builds from the same states, and nothing of the first dataset (changed after it was returned)."""
    from dataclasses import replace

    overrides = [*FIXED_POINT, "force=[uniform_gravity,magnetic]", "force.magnetic.direction=[1.0,0.0,0.0]"]
    scene, solution, first = _built(overrides)
    first.omega.attrs["units"], first.energy.values[:] = "changed", 0.0
    first.time.attrs["units"], first.time.encoding["dtype"] = "changed", "float32"  # a coordinate's too
    other = replace(solution, y=solution.y * np.linspace(1.0, 1.01, len(solution.t))[:, None])  # other states
    again, fresh = dataset.build_dataset(scene, other), dataset.build_dataset(compose_scene(overrides), other)
    assert scene.dataset_layouts and again.energy.attrs["max_abs_drift"] != first.energy.attrs[
        "max_abs_drift"]
    for ds in (again, fresh):
        del ds.attrs["date_created"], ds.attrs["history"]
    assert again.identical(fresh) and list(again.variables) == list(fresh.variables)
    assert all(again.variables[k].encoding == v.encoding for k, v in fresh.variables.items())
    added = dataset.build_dataset(scene, other, lambda stored: ({"copied": stored["energy"].copy()}, {}))
    assert added.variables["copied"].identical(added.variables["energy"]) and list(added.data_vars)[-1] == "copied"  # another layout


def test_a_scene_that_has_run_pickles_and_runs_the_same_after():
    """A scene whose run generated its Python right-hand side (a function made in that process) still pickles, as it
    did when it called the system's own: the unpickled scene generates it again and runs to the same numbers."""
    import pickle

    scene = compose_scene([*FIXED_POINT, "integrator=dop853"])
    first = scene.run()
    again = pickle.loads(pickle.dumps(scene)).run()
    for name in ("omega", "gamma", "energy"):
        np.testing.assert_array_equal(again[name].values, first[name].values)
