"""The work-precision experiment: a dataset and figures whose errors are judged against the reference; the process's
CPU time, repeated, the minimum kept, and said so."""

from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

from gyrolab.engine.config import compose_config
from gyrolab.experiments import run_task, work_precision
from gyrolab.figures import redraw


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


class _Stop(Exception):
    pass


def _clock(durations):
    """A clock whose successive (start, end) pairs are `durations` apart."""
    ticks, now = [], 0.0
    for d in durations:
        ticks += [now, now + d]
        now += d + 100.0
    it = iter(ticks)
    return lambda: next(it)


def test_cpu_time_is_the_minimum_of_the_repeats_and_the_timing_is_recorded(tmp_path, monkeypatch):
    cpu = [0.5, 0.2, 0.7]    # the second repeat is the fastest in CPU time
    wall = [0.9, 3.0, 0.4]   # and the third in wall time (a preempted repeat: wall ≫ CPU)
    monkeypatch.setattr(work_precision, "time", SimpleNamespace(process_time=_clock(cpu), perf_counter=_clock(wall)))
    captured = []

    def capture(ds, path):
        captured.append(ds)
        raise _Stop

    monkeypatch.setattr(redraw, "write_dataset", capture)  # work_precision writes through redraw.write_and_draw
    cfg = compose_config(["experiment=work_precision", "time.end=1", "work_precision.repeats=3",
                          "~work_precision.methods", "+work_precision.methods={dop853_numba: {rtol: [1e-6]}}"])
    with pytest.raises(_Stop):
        work_precision.run(cfg, tmp_path)
    ds = captured[0]
    assert ds.cpu_time.values.tolist() == [pytest.approx(0.2)]
    assert ds.wall_time.values.tolist() == [pytest.approx(0.4)]
    assert ds.cpu_time.attrs["units"] == "s"
    assert "process_time" in ds.attrs["timing"] and "minimum over 3 repeats" in ds.attrs["timing"]
    assert ds.attrs["repeats"] == 3
