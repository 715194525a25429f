"""Sweeps from the command line: one sweep.nc per multirun, failures recorded, launchers, resume, reproduce.

Every expectation comes from outside the aggregator: the jobs' own run.nc files, Hydra's own record of
each job's overrides (.hydra/overrides.yaml), the single-run error for the same config, a sweep run
under another launcher, or a perturbation the test makes itself.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

from tests.helpers import (
    CODE_DEPENDENT_ATTRS,
    CODE_DEPENDENT_VARIABLES,
    VOLATILE_ATTRS,
    VOLATILE_VARIABLES,
    gyrolab,
    load,
)

# A 2 × 2 sweep of tiny scenes; a = 3 breaks the triangle inequality (3 > 1.5 + 1), so 2 jobs fail.
SWEEP = ["integrator=rk4,dop853", "body.a=1.5,3", "time.end=1", "time.n_output=11", "output.figures=false"]


def code_versions(sweep_dir):
    return {json.loads(p.read_text())["code_version"] for p in Path(sweep_dir).glob("*/job.json")}


def comparable(ds, *, code_changed=False):
    # (a sweep whose jobs ran under two code versions has the provenance as variables, not attributes)
    drop = list(VOLATILE_VARIABLES) + (list(CODE_DEPENDENT_VARIABLES + CODE_DEPENDENT_ATTRS) if code_changed else [])
    ds = ds.drop_vars([v for v in drop if v in ds.variables])
    for key in VOLATILE_ATTRS + (CODE_DEPENDENT_ATTRS if code_changed else ()):
        ds.attrs.pop(key, None)
    return ds


def assert_same_sweep(dir_a, dir_b):
    """sweep.nc of two runs of the same sweep are identical up to what legitimately differs."""
    a, b = load(Path(dir_a) / "sweep.nc"), load(Path(dir_b) / "sweep.nc")
    code_changed = code_versions(dir_a) != code_versions(dir_b)
    if code_changed:  # another edit landed between the two runs: ids must follow the code
        assert (a.job_id.values != b.job_id.values).any()
    xr.testing.assert_identical(comparable(a, code_changed=code_changed), comparable(b, code_changed=code_changed))


def jobs_by_overrides(sweep_dir):
    """Hydra's own record of each job's overrides -> that job's directory."""
    out = {}
    for saved in Path(sweep_dir).glob("*/.hydra/overrides.yaml"):
        overrides = yaml.safe_load(saved.read_text())
        out[tuple(overrides)] = saved.parent.parent
    return out


@pytest.fixture(scope="module")
def basic(tmp_path_factory):
    """The sweep under Hydra's basic launcher (jobs one after another in one process)."""
    cwd = tmp_path_factory.mktemp("basic")
    done = gyrolab("-m", *SWEEP, "hydra.sweep.dir=sweep", cwd=cwd)
    return cwd / "sweep", done


def test_sweep_nc_has_one_dimension_per_swept_parameter(basic):
    sweep_dir, _ = basic
    ds = load(sweep_dir / "sweep.nc")
    assert ds.omega.dims == ("integrator", "a", "time", "axis")
    assert ds.energy.dims == ("integrator", "a", "time")
    assert list(ds.integrator.values) == ["rk4", "dop853"]          # as typed on the command line
    np.testing.assert_array_equal(ds.a.values, [1.5, 3.0])
    assert ds.a.attrs["override_key"] == "body.a"
    assert ds.integrator_nfev.dims == ("integrator", "a")


def test_every_finished_job_is_in_sweep_nc_bit_for_bit(basic):
    sweep_dir, _ = basic
    ds = load(sweep_dir / "sweep.nc")
    jobs = jobs_by_overrides(sweep_dir)
    assert len(jobs) == 4
    compared = 0
    for integrator in ("rk4", "dop853"):
        for a in ("1.5",):
            job_dir = jobs[(f"integrator={integrator}", f"body.a={a}", *SWEEP[2:4], "output.figures=False")]
            run = load(job_dir / "run.nc")
            cell = ds.sel(integrator=integrator, a=float(a))
            for name in run.data_vars:
                np.testing.assert_array_equal(cell[name].values, run[name].values, err_msg=name)
                if "max_abs_drift" in run[name].attrs:
                    assert cell[f"{name}_max_abs_drift"].item() == run[name].attrs["max_abs_drift"]
            np.testing.assert_array_equal(ds.time.values, run.time.values)
            assert cell.integrator_nfev.item() == run.attrs["integrator_nfev"]
            assert cell.config.item() == run.attrs["config"]
            assert cell.job_id.item() == run.attrs["job_id"]
            assert cell.job_status.item() == 1
            compared += 1
    assert compared == 2


def test_failing_jobs_are_recorded_not_fatal(basic):
    from gyrolab import compose_scene
    from gyrolab.errors import ConfigError

    sweep_dir, done = basic
    # The sweep ran to its end and says that some jobs failed.
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines()[-1].startswith("gyrolab: 2 of 4 jobs failed")
    ds = load(sweep_dir / "sweep.nc")
    np.testing.assert_array_equal(ds.job_status.values, [[1, 2], [1, 2]])
    assert np.isnan(ds.omega.sel(a=3.0).values).all()
    # The error recorded is the one a single run of the same config gives.
    with pytest.raises(ConfigError) as single:
        compose_scene(["body.a=3"])
    assert list(ds.failed_job_error.values) == [str(single.value)] * 2
    assert list(ds.failed_job_exit_code.values) == [2, 2]
    assert sorted(ds.failed_job_overrides.values) == sorted(
        " ".join(o) for o in jobs_by_overrides(sweep_dir) if "body.a=3" in o)
    for overrides, job_dir in jobs_by_overrides(sweep_dir).items():
        assert (job_dir / "run.nc").exists() == ("body.a=3" not in overrides)


@pytest.mark.slow
def test_joblib_launcher_gives_the_same_sweep_nc(basic, tmp_path):
    done = gyrolab("-m", *SWEEP, "hydra.sweep.dir=sweep", "hydra/launcher=joblib", "hydra.launcher.n_jobs=2",
                   cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert load(tmp_path / "sweep" / "sweep.nc").attrs["sweep_launcher"] == "JoblibLauncher"
    assert_same_sweep(basic[0], tmp_path / "sweep")


@pytest.mark.slow
def test_submitit_launcher_gives_the_same_sweep_nc(basic, tmp_path):
    done = gyrolab("-m", *SWEEP, "hydra.sweep.dir=sweep", "hydra/launcher=submitit_local", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert load(tmp_path / "sweep" / "sweep.nc").attrs["sweep_launcher"] == "LocalLauncher"
    assert_same_sweep(basic[0], tmp_path / "sweep")


def test_resume_skips_finished_jobs_and_recomputes_the_rest(basic, tmp_path):
    """Crash points simulated on a copy of a finished sweep: each leaves its job unfinished."""
    sweep_dir = tmp_path / "sweep"
    shutil.copytree(basic[0], sweep_dir)
    job = {(o[0].split("=")[1], o[1].split("=")[1]): d for o, d in jobs_by_overrides(sweep_dir).items()}
    (sweep_dir / "sweep.nc").unlink()
    # rk4, a=1.5: killed after writing run.nc, before its record, with a temporary file left behind
    (job["rk4", "1.5"] / "job.json").unlink()
    shutil.copy(job["rk4", "1.5"] / "run.nc", job["rk4", "1.5"] / ".run.nc.crash.tmp")
    # rk4, a=3: a failing job killed before it recorded its failure
    (job["rk4", "3"] / "job.json").unlink()
    # dop853, a=1.5 (finished) and dop853, a=3 (failed) are settled and must not run again
    done = gyrolab("-m", *SWEEP, f"hydra.sweep.dir={sweep_dir}", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    log = done.stdout + done.stderr
    if code_versions(basic[0]) == code_versions(sweep_dir):
        assert "skipped 2 finished jobs" in log, log
        assert log.count("integrating body") == 1, log   # rk4 a=1.5 only; rk4 a=3 fails before integrating
    assert not list(job["rk4", "1.5"].glob(".*.tmp"))
    assert_same_sweep(basic[0], sweep_dir)


@pytest.mark.slow
def test_resume_after_kill_9(basic, tmp_path):
    args = [sys.executable, "-m", "gyrolab", "-m", *SWEEP, "hydra.sweep.dir=sweep"]
    process = subprocess.Popen(args, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               start_new_session=True)
    deadline = time.monotonic() + 120
    while not list((tmp_path / "sweep").glob("*/job.json")) and time.monotonic() < deadline:
        if process.poll() is not None:
            break
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait()
    settled = len(list((tmp_path / "sweep").glob("*/job.json")))
    assert settled >= 1 and not (tmp_path / "sweep" / "sweep.nc").exists()
    done = gyrolab("-m", *SWEEP, "hydra.sweep.dir=sweep", cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    if code_versions(basic[0]) == code_versions(tmp_path / "sweep"):
        assert f"skipped {settled} finished jobs" in done.stdout + done.stderr
    assert_same_sweep(basic[0], tmp_path / "sweep")


def test_reproduce_round_trip(basic, tmp_path, monkeypatch, capsys):
    from gyrolab import app

    run_nc = next(d for o, d in jobs_by_overrides(basic[0]).items() if "integrator=dop853" in o
                  and "body.a=1.5" in o) / "run.nc"
    monkeypatch.setattr(sys, "argv", ["gyrolab", "--reproduce", str(run_nc)])
    with pytest.raises(SystemExit) as stop:
        app.main()
    out = capsys.readouterr().out
    assert stop.value.code == 0, out
    assert "identical" in out and "NOT" not in out

    # The same dataset with one value moved by 1e-9: reproduce must notice and say by how much.
    tampered = load(run_nc)
    tampered["omega"].values[5, 2] += 1e-9
    expected = abs(tampered["omega"].values[5, 2] - load(run_nc)["omega"].values[5, 2])
    tampered.to_netcdf(tmp_path / "tampered.nc")
    monkeypatch.setattr(sys, "argv", ["gyrolab", "--reproduce", str(tmp_path / "tampered.nc")])
    with pytest.raises(SystemExit) as stop:
        app.main()
    out = capsys.readouterr().out
    assert stop.value.code == 1, out
    line = next(line for line in out.splitlines() if "variable omega" in line)
    assert f"max |Δ| = {expected:.3g}" in line and "1 of 33 values differ" in line
    assert "NOT identical: 1 of" in out


def test_reproduce_a_multirun_sweep_nc_reruns_its_finished_jobs(basic, tmp_path, monkeypatch, capsys):
    from gyrolab import app

    # (integrator, a) = (rk4, 1.5), (rk4, 3), (dop853, 1.5), (dop853, 3): a = 3 failed
    monkeypatch.setattr(sys, "argv", ["gyrolab", "reproduce", str(basic[0] / "sweep.nc")])
    with pytest.raises(SystemExit) as stop:
        app.main()
    out = capsys.readouterr().out
    assert stop.value.code == 0, out
    assert "job 1: failed in the sweep; no run.nc to rerun" in out and "job 3: failed in the sweep" in out
    assert "identical: 2 jobs' datasets equal bit for bit (job 0, job 2)" in out

    # a job's run.nc moved by 1e-9: that job, and only it, differs; --points 2 reruns that job alone
    sweep_dir = tmp_path / "sweep"
    shutil.copytree(basic[0], sweep_dir)
    job = sweep_dir / str(load(sweep_dir / "sweep.nc").job_dir.values.ravel()[2]) / "run.nc"
    tampered = load(job)
    tampered["omega"].values[5, 2] += 1e-9
    tampered.to_netcdf(job)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "reproduce", str(sweep_dir / "sweep.nc"), "--points", "2"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    out = capsys.readouterr().out
    assert stop.value.code == 1, out
    assert "1 of them" in out and "job 0" not in out and "job 2: variable omega: max |Δ|" in out
    assert "NOT identical: 1 of 1 jobs' datasets differ" in out


def test_aggregate_command_rewrites_the_same_sweep_nc(basic, tmp_path):
    sweep_dir = tmp_path / "sweep"
    shutil.copytree(basic[0], sweep_dir)
    (sweep_dir / "sweep.nc").unlink()
    done = gyrolab("--aggregate", str(sweep_dir), cwd=tmp_path)
    assert done.returncode == 1, done.stderr   # two jobs failed
    assert_same_sweep(basic[0], sweep_dir)
