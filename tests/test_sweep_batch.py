"""gyrolab --batch: the same sweep.nc as a multirun of the same grid, computed in one batch."""

import numpy as np
import xarray as xr

GRID = ["integrator=rk4_numba", "integrator.step=0.01", "output.euler_angles=false", "output.figures=false",
        "time.end=2", "time.n_output=5", "initial.r0=2,5", "body.a=1.5,3"]  # a = 3 is non-physical


def test_batch_sweep_equals_the_multirun(cli, tmp_path):
    multi = cli("-m", *GRID, "hydra.sweep.dir=multi")
    batch = cli("--batch", *GRID, "batch.output=trajectory", "hydra.sweep.dir=batch")
    assert batch.returncode == multi.returncode == 1, batch.stderr[-2000:]  # the non-physical points fail in
    assert "2 of 4 points failed" in batch.stderr                             # both, without stopping the sweep
    with xr.open_dataset(tmp_path / "multi" / "sweep.nc") as m, xr.open_dataset(tmp_path / "batch" / "sweep.nc") as b:
        assert m.omega.dims == b.omega.dims == ("r0", "a", "time", "axis")
        np.testing.assert_array_equal(m.job_status.values, b.job_status.values)
        np.testing.assert_array_equal(m.time.values, b.time.values)
        # the batch kernel sums the torque terms in another order: equal to rounding
        np.testing.assert_allclose(b.omega.values, m.omega.values, rtol=0, atol=1e-12, equal_nan=True)
        np.testing.assert_allclose(b.gamma.values, m.gamma.values, rtol=0, atol=1e-12, equal_nan=True)
        assert int(b.n_failed) == int(m.n_failed) == 2
        errors = b.error_message.values[b.job_error.values[b.job_status.values == 2]]
        assert all("triangle inequality" in str(e) for e in errors) and len(errors) == 2


def test_batch_refuses_to_vary_the_integrator(cli):
    done = cli("--batch", "integrator=rk4,rk4_numba", "hydra.sweep.dir=x")
    assert done.returncode == 2
    assert "varies body, initial and force parameters only" in done.stderr
