"""The gyrolab command: default scene, figures, multirun."""

import xarray as xr


def test_default_run_writes_dataset_and_figures(cli, tmp_path):
    done = cli("hydra.run.dir=out", "time.end=5", "time.n_output=101")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        assert ds.sizes["time"] == 101
        assert "hydra_overrides" in ds.attrs and "time.end=5" in ds.attrs["hydra_overrides"]
    figures = sorted(p.name for p in (tmp_path / "out" / "figures").iterdir())
    assert figures == ["body_axis_sphere.png", "euler_angles.png", "invariant_drift.png", "state.png"]


def test_multirun_writes_one_dataset_per_job(cli, tmp_path):
    done = cli("-m", "integrator=rk4,dop853", "time.end=1", "time.n_output=11", "output.figures=false",
               "hydra.sweep.dir=sweep")
    assert done.returncode == 0, done.stderr
    names = []
    for job in ("0", "1"):
        with xr.open_dataset(tmp_path / "sweep" / job / "run.nc") as ds:
            names.append(ds.attrs["integrator"])
    assert names == ["rk4", "dop853"]
