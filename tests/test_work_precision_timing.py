"""experiment=work_precision times the process's CPU time, repeated, keeps the minimum, and says so."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from gyrolab.engine.config import compose_config
from gyrolab.experiments import work_precision


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

    monkeypatch.setattr(work_precision, "write_dataset", capture)
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
