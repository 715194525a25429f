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
