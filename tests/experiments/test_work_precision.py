"""The work-precision experiment: a dataset and figures whose errors are judged against the reference."""

import numpy as np
import xarray as xr

from gyrolab.engine.config import compose_config
from gyrolab.experiments import run_task


def test_work_precision_task(tmp_path):
    cfg = compose_config(["experiment=work_precision", "time.end=10", "work_precision.repeats=1",
                          "~work_precision.methods",
                          "+work_precision.methods={taylor: {tol: [1e-8, 1e-14]}, rk4_numba: {step: [0.02, 0.01]}}"])
    written = run_task("work_precision", cfg, tmp_path)
    assert {p.name for p in written} == {"work_precision.nc", "error_vs_wall_time.png", "error_vs_nfev.png"}
    with xr.open_dataset(tmp_path / "work_precision.nc") as ds:
        assert list(ds.method.values) == ["taylor", "taylor", "rk4_numba", "rk4_numba"]
        assert "extended-precision" in ds.attrs["reference"]
        errors = ds.error.values
        assert errors[1] < errors[0] < 1e-6  # tighter Taylor tolerance, smaller error
        # RK4 is fourth order: halving the step divides the error by about 16
        assert np.log2(errors[2] / errors[3]) == np.clip(np.log2(errors[2] / errors[3]), 3.8, 4.2)
        for name in ("error", "wall_time", "nfev", "energy_drift"):
            assert ds[name].attrs["units"] and ds[name].attrs["long_name"]
