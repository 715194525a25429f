"""gyrolab's sweeper leaves settled jobs out before launching anything, and a resumed sweep is the same sweep.

What each job did is read from outside the sweeper: Hydra's job log (``gyrolab.log``, appended by
every job Hydra launches in that directory), the run.nc files and job records the jobs wrote, and
``sweep.nc`` of the uninterrupted run.
"""

import json
import shutil
from pathlib import Path

import xarray as xr

from gyrolab.sweep.sweeper import launch_runs
from tests.helpers import VISCOUS_DRAG, gyrolab_in_process, load

# 2 × 2 tiny scenes: a config-group dimension (integrator) and a value dimension (body.a); all finish.
SWEEP = ["integrator=rk4,dop853", "body.a=1.5,1.2", "time.end=1", "time.n_output=11", "output.figures=false"]


def comparable(path):
    ds = load(path)
    for key in ("date_created", "history"):
        ds.attrs.pop(key, None)
    return ds.drop_vars(["integrator_wall_time"])


def job_logs(sweep_dir):
    return {d.name: (d / "gyrolab.log").read_text() for d in sorted(Path(sweep_dir).iterdir())
            if (d / "gyrolab.log").is_file()}


def test_resume_launches_only_the_unsettled_jobs_and_writes_the_same_sweep_nc(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sweep = tmp_path / "sweep"
    code = gyrolab_in_process(monkeypatch, "-m", *SWEEP, f"hydra.sweep.dir={sweep}")
    assert code in (0, None)
    shutil.copy(sweep / "sweep.nc", tmp_path / "uninterrupted.nc")
    records = {n: json.loads((sweep / str(n) / "job.json").read_text()) for n in range(4)}
    assert [r["status"] for r in records.values()] == ["finished"] * 4

    # job 1 lost its dataset, job 2 its record (killed before writing it); job 3's record belongs to
    # another config (another identity): those three must run again, job 0 must not even be launched
    (sweep / "1" / "run.nc").unlink()
    (sweep / "2" / "job.json").unlink()
    (sweep / "3" / "job.json").write_text(json.dumps({**records[3], "job_id": "0" * 20}))
    (sweep / "sweep.nc").unlink()
    logs_before = job_logs(sweep)

    code = gyrolab_in_process(monkeypatch, "-m", *SWEEP, f"hydra.sweep.dir={sweep}")
    assert code in (0, None)
    logs_after = job_logs(sweep)
    assert logs_after["0"] == logs_before["0"]                      # never launched
    for n in ("1", "2", "3"):
        assert len(logs_after[n]) > len(logs_before[n]), n          # launched again
        assert "integrating body" in logs_after[n][len(logs_before[n]):], n
    again = {n: json.loads((sweep / str(n) / "job.json").read_text()) for n in range(4)}
    assert again[0]["skipped"] and not any(again[n]["skipped"] for n in (1, 2, 3))
    assert [again[n]["job_id"] for n in range(4)] == [records[n]["job_id"] for n in range(4)]
    assert [again[n]["job_num"] for n in range(4)] == [0, 1, 2, 3]
    xr.testing.assert_identical(comparable(sweep / "sweep.nc"), comparable(tmp_path / "uninterrupted.nc"))


def test_remaining_jobs_keep_their_numbers():
    jobs = [[f"x={n}"] for n in range(10)]
    # one launch per run of consecutive remaining jobs, starting at the first one's number
    assert launch_runs([3, 4, 7], jobs, None, merge_gap=0) == [(3, [["x=3"], ["x=4"]]), (7, [["x=7"]])]
    # across a gap of at most merge_gap settled jobs, the run goes on (those jobs skip themselves)
    assert launch_runs([3, 4, 7], jobs, None, merge_gap=2) == [(3, [[f"x={n}"] for n in range(3, 8)])]
    # max_batch_size cuts a run into batches, each numbered from its own first job
    assert launch_runs([0, 1, 2, 9], jobs, 2, merge_gap=0) == [(0, [["x=0"], ["x=1"]]), (2, [["x=2"]]),
                                                                (9, [["x=9"]])]
    assert launch_runs([], jobs, None) == []


def test_a_finished_sweep_and_batch_resume_after_an_unrelated_plugin_is_installed(tmp_path, monkeypatch):
    from gyrolab.batch.sweep import run_batch_sweep
    from gyrolab.output import provenance
    from gyrolab.sweep import identity
    from tests.conftest import installed_distribution

    monkeypatch.chdir(tmp_path)
    sweep, two = tmp_path / "sweep", ["body.a=1.5,1.2", "time.end=1", "time.n_output=11", "output.figures=false"]
    batch = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=1", "time.n_output=11",
             "output.figures=false", "initial.r0=1,2"]
    assert gyrolab_in_process(monkeypatch, "-m", *two, f"hydra.sweep.dir={sweep}") in (0, None)
    run_batch_sweep(batch, tmp_path / "batch")
    records = {n: json.loads((sweep / str(n) / "job.json").read_text()) for n in range(2)}
    logs_before = job_logs(sweep)
    batch_before = (tmp_path / "batch" / "sweep.nc").read_bytes()

    # `pip install gyrolab-viscous-drag` between the run and its resume: a plugin no job names
    site = tmp_path / "site"
    site.mkdir()
    with installed_distribution(site, "gyrolab-viscous-drag", "0.1.0",
                                {"viscous_drag": "gyrolab_viscous_drag:ViscousDrag"}, [VISCOUS_DRAG]):
        provenance.provenance.cache_clear()   # what a new process sees
        identity._plugin_code.cache_clear()
        assert "gyrolab-viscous-drag==0.1.0" in provenance.provenance()["plugin_packages"]
        assert gyrolab_in_process(monkeypatch, "-m", *two, f"hydra.sweep.dir={sweep}") in (0, None)
        run_batch_sweep(batch, tmp_path / "batch")   # not "holds another batch": the same batch, finished
    provenance.provenance.cache_clear()
    assert job_logs(sweep) == logs_before            # no job launched again
    again = {n: json.loads((sweep / str(n) / "job.json").read_text()) for n in range(2)}
    assert all(again[n]["skipped"] and again[n]["job_id"] == records[n]["job_id"] for n in range(2))
    assert (tmp_path / "batch" / "sweep.nc").read_bytes() == batch_before
