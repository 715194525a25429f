"""run.nc is self-describing, round-trips through netCDF identically and reproduces its run."""

import numpy as np
import pytest
import xarray as xr
from omegaconf import OmegaConf

from gyrolab import run
from gyrolab.output.dataset import write_dataset
from gyrolab.engine.scene import Scene

SHORT = ["time.end=2", "time.n_output=21"]


@pytest.fixture(scope="module")
def ds():
    return run(SHORT)


def test_every_variable_has_cf_units_and_long_name(ds):
    for name, variable in {**ds.data_vars, **ds.coords}.items():
        assert variable.attrs.get("units"), name
        assert variable.attrs.get("long_name"), name


def test_required_variables_and_provenance(ds):
    for name in ("omega", "gamma", "energy", "area_integral", "gamma_norm", "psi", "theta", "phi"):
        assert name in ds
    assert ds.omega.dims == ("time", "axis") and list(ds.axis.values) == ["x", "y", "z"]
    for key in ("config", "gyrolab_version", "git_commit", "integrator_nfev", "integrator_n_steps",
                "integrator_wall_time", "body_nondim_a"):
        assert key in ds.attrs, key


def test_netcdf_round_trip_is_identical(ds, tmp_path):
    path = write_dataset(ds, tmp_path / "run.nc")
    with xr.open_dataset(path) as loaded:
        assert loaded.load().identical(ds)
    assert [p.name for p in tmp_path.iterdir()] == ["run.nc"]  # no temporary file left


def test_failed_write_leaves_nothing(ds, tmp_path, monkeypatch):
    def broken(self, path, **kwargs):
        open(path, "wb").write(b"partial")
        raise OSError("disk full")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", broken)
    with pytest.raises(OSError):
        write_dataset(ds, tmp_path / "run.nc")
    assert list(tmp_path.iterdir()) == []


def test_dataset_reproduces_its_own_run(ds):
    again = Scene.from_config(OmegaConf.create(ds.attrs["config"])).run()
    np.testing.assert_array_equal(again.omega.values, ds.omega.values)
    np.testing.assert_array_equal(again.gamma.values, ds.gamma.values)


def test_only_requested_output_times_are_stored(ds):
    assert ds.sizes["time"] == 21
    assert ds.attrs["integrator_n_steps"] != 20  # the integrator's own steps are not the output grid


# ----------------------------------------------------------------------------- output sampling (time.n_output)
# The default initial state spins at r0 = 5 (conf/initial/fast_spin.yaml): in body axes the vertical γ turns
# about ω at |ω| ≈ r0, so the fast-spin period is 2π/r0 ≈ 1.257 model time units (the γ panel's fastest motion).
R0 = 5.0
SPIN_PERIOD = 2 * np.pi / R0


def test_auto_output_resolves_the_fast_spin_over_a_long_span():
    """The README's long run (t = 0…12566 = 2000 × 2π): 2001 samples would be 6.28 apart, 0.2 per spin period."""
    from gyrolab.engine.scene import AUTO_MAX_SAMPLES, compose_scene

    scene = compose_scene(["time.end=12566"])
    step = scene.times[1] - scene.times[0]
    assert step <= SPIN_PERIOD / 8 and len(scene.times) <= AUTO_MAX_SAMPLES
    assert np.allclose(np.diff(scene.times), step) and scene.times[-1] == 12566.0
    attrs = scene.sampling_attributes()
    assert "sampling_warning" not in attrs and attrs["sampling_n_output_requested"] == "auto"


def test_explicit_undersampling_is_warned_in_one_sentence_and_recorded(ds, caplog, tmp_path):
    from gyrolab.engine.scene import compose_scene

    with caplog.at_level("WARNING", logger="gyrolab.engine.scene"):
        scene = compose_scene(["time.end=12566", "time.n_output=2001"])
    assert len(scene.times) == 2001                                  # the user's choice is respected
    warning = scene.sampling_attributes()["sampling_warning"]
    assert [r.getMessage() for r in caplog.records if r.name == "gyrolab.engine.scene"] == [warning]
    assert warning.startswith("time.n_output=2001 ") and "alias" in warning and warning.count(". ") == 0
    # a short run that undersamples the same way (2 time units apart, 0.63 samples per spin period) records it
    coarse = run(["time.end=20", "time.n_output=11"])
    assert coarse.attrs["sampling_warning"].startswith("time.n_output=11 ")
    per_spin_period = SPIN_PERIOD / 2.0                                  # spin period / output spacing
    assert coarse.attrs["sampling_samples_per_period"] <= per_spin_period  # ν ≥ r0: fewer per fastest period
    with xr.open_dataset(write_dataset(coarse, tmp_path / "run.nc")) as loaded:
        assert loaded.attrs["sampling_warning"] == coarse.attrs["sampling_warning"]
    assert "sampling_warning" not in ds.attrs                          # SHORT: 0.1 apart, 12.6 per spin period


def test_fastest_rate_bounds_the_motion_it_must_resolve():
    """ν (sampling_fastest_rate) is an upper estimate: above the largest |ω(t)| of the integrated motion and
    above the dominant frequency of γ_x in body axes, which is the spin |ω| ≈ r0 (found by FFT)."""
    ds = run(["time.end=20", "time.n_output=2001"])
    nu = ds.attrs["sampling_fastest_rate"]
    speed = np.linalg.norm(ds.omega.values, axis=1)
    assert speed.max() < nu
    t, x = ds.time.values, ds.gamma.values[:, 0]
    spectrum = np.abs(np.fft.rfft((x - x.mean()) * np.hanning(len(x))))
    freqs = 2 * np.pi * np.fft.rfftfreq(len(x), t[1] - t[0])
    peak = freqs[np.argmax(spectrum)]
    resolution = 2 * np.pi / t[-1]
    assert abs(peak - speed.mean()) < 2 * resolution and peak < nu
    assert abs(peak - R0) < 0.1 * R0


def test_batch_points_share_the_densest_auto_grid():
    from gyrolab.batch.plan import plan_from_overrides
    from gyrolab.engine.config import compose_config

    slow = Scene.from_config(compose_config(["time.end=300", "initial.r0=1"]))
    fast = Scene.from_config(compose_config(["time.end=300", "initial.r0=20"]))
    assert len(fast.times) > len(slow.times)         # a spin 20 times faster needs more samples over the same span
    plan = plan_from_overrides(["time.end=300", "initial.r0=1,20"])
    np.testing.assert_array_equal(plan.times, fast.times)
