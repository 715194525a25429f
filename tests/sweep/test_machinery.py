"""Pieces of the sweep machinery, in process: grid, identity, job records, assembly, figures, progress."""

import io
import logging
import shutil
import sys

import numpy as np
import pytest
from hydra._internal.core_plugins.basic_sweeper import BasicSweeper
from hydra.core.override_parser.overrides_parser import OverridesParser

from gyrolab import app, run
from gyrolab.engine import progress
from gyrolab.engine.config import compose_config
from gyrolab.errors import IntegrationError
from gyrolab.sweep.aggregate import FINISHED, JobResult, assemble
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import job_identity
from gyrolab.sweep.job import run_sweep_job
from gyrolab.sweep.record import FAILED, read_record
from gyrolab.sweep.watch import SweepWatcher
from tests.helpers import VISCOUS_DRAG

TINY = ["time.end=1", "time.n_output=11", "output.figures=false"]


@pytest.mark.parametrize("overrides", [
    ["integrator=rk4,dop853", "body.a=1.5,2,3", "time.end=1"],
    ["body.a=range(1,4)", "force=[uniform_gravity],[newtonian]", "initial.r0=2"],
    ["time.end=1", "body.a=2", "time.end=3,4"],            # a key given twice: the last value wins
])
def test_grid_jobs_are_the_jobs_hydra_launches(overrides):
    hydra_jobs = BasicSweeper.split_arguments(OverridesParser.create().parse_overrides(overrides), None)[0]
    grid = Grid.from_overrides(overrides)
    assert [list(job) for job in grid.jobs] == hydra_jobs
    for job, index in zip(grid.jobs, grid.index):   # each job sits at the grid point of its swept values
        for dim, i in zip(grid.dims, index):
            assert f"{dim.key}={dim.labels[i]}" in job


@pytest.mark.parametrize("argv, must_mention", [
    (["-m", "body.a=2,2.0"], ["body.a", "twice"]),
    (["-m", "body.a=interval(1,2)"], ["interval(1,2)", "discrete"]),
])
def test_bad_sweeps_are_one_sentence(argv, must_mention, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", *argv, "hydra.sweep.dir=sweep"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("gyrolab: error: ")
    for text in must_mention:
        assert text in err, err
    assert not (tmp_path / "sweep").exists()


def test_identity_follows_the_resolved_config_and_the_code():
    a = compose_config(["body.a=2", "initial.r0=3"])
    assert job_identity(a) == job_identity(compose_config(["initial.r0=3", "body.a=2"]))
    assert job_identity(a) == job_identity(compose_config(["body.a=2", "initial.r0=3"], return_hydra_config=True))
    assert job_identity(a) != job_identity(compose_config(["body.a=2", "initial.r0=3.5"]))
    assert job_identity(a, "gyrolab 1; git x") != job_identity(a, "gyrolab 1; git y")


def test_gyrolab_code_in_an_identity_is_its_code_trees_not_the_commit(monkeypatch):
    from gyrolab.output import provenance
    from gyrolab.sweep import identity

    prov = provenance.provenance()
    if prov["git_commit"] == "unknown":
        pytest.skip("not a git checkout of gyrolab")
    code = identity.code_version()
    assert f"code {provenance.code_tree()}" in code and prov["git_commit"] not in code
    # a commit that touches only docs or tests: a new commit, the same trees of pipeline/, plugins/, conf/, ...
    monkeypatch.setitem(prov, "git_commit", "0" * 40)
    assert identity.code_version() == code
    listed = provenance._git("ls-tree", "HEAD", "--", *provenance.CODE_PATHS)
    assert {line.split()[-1] for line in listed.splitlines()} == {"pipeline", "plugins", "conf", "hydra_plugins",
                                                                  "pyproject.toml"}


def test_identity_covers_the_plugins_a_job_names_not_every_installed_package(tmp_path, monkeypatch):
    from tests.conftest import installed_distribution

    from gyrolab.output import provenance
    from gyrolab.sweep import identity

    plain = compose_config(["body.a=2"])
    before = job_identity(plain)

    def installed(version):
        site = tmp_path / version
        site.mkdir()
        return installed_distribution(site, "gyrolab-viscous-drag", version,
                                      {"viscous_drag": "gyrolab_viscous_drag:ViscousDrag"}, [VISCOUS_DRAG])

    with installed("0.1.0"):
        provenance.provenance.cache_clear()   # as a new process sees it: the plugin is installed
        identity._plugin_code.cache_clear()
        assert job_identity(plain) == before  # a plugin the job does not name changes nothing
        drag = compose_config(["force=[uniform_gravity,viscous_drag]"])
        code = identity.job_code(drag)
        assert "plugins gyrolab-viscous-drag==0.1.0 gyrolab_viscous_drag@" in code
        assert identity.plugins_named(plain) == ""
        with_drag = job_identity(drag)
    with installed("0.2.0"):                  # an update of the plugin the job names: another identity
        identity._plugin_code.cache_clear()
        assert job_identity(drag) != with_drag
        assert job_identity(plain) == before
    editable = tmp_path / "checkout"            # an editable install's new commit, its version unchanged
    shutil.copytree(VISCOUS_DRAG, editable)
    (tmp_path / "site-e").mkdir()
    with installed_distribution(tmp_path / "site-e", "gyrolab-viscous-drag", "0.1.0",
                                {"viscous_drag": "gyrolab_viscous_drag:ViscousDrag"}, [editable]):
        for name in [m for m in sys.modules if m.startswith("gyrolab_viscous_drag")]:
            monkeypatch.delitem(sys.modules, name)   # a new process: the plugin is imported from the checkout
        identity._plugin_code.cache_clear()
        first = job_identity(drag)
        (editable / "gyrolab_viscous_drag" / "helpers.py").write_text("SCALE = 2.0\n")   # a helper module changed
        identity._plugin_code.cache_clear()
        assert job_identity(drag) != first
    provenance.provenance.cache_clear()
    identity._plugin_code.cache_clear()


def test_job_records_failures_and_is_skipped_once_settled(tmp_path):
    cfg = compose_config(TINY)
    job_dir = tmp_path / "0"
    job_dir.mkdir()   # Hydra makes the job directory before the job starts

    def crash(job_id):
        (job_dir / "run.nc").write_text("partial")
        raise ZeroDivisionError("a bug")

    record = run_sweep_job(cfg, job_dir, ["x=1"], 0, crash)
    assert record.status == FAILED and not record.deterministic and record.error_type == "ZeroDivisionError"
    assert not (job_dir / "run.nc").exists() and read_record(job_dir).error == "a bug"

    calls = []

    def fails(job_id):
        calls.append(job_id)
        raise IntegrationError("step size underflow at t=0.5")

    record = run_sweep_job(cfg, job_dir, ["x=1"], 0, fails)      # an unexpected crash is retried
    assert calls and record.deterministic and record.exit_code == 3
    record = run_sweep_job(cfg, job_dir, ["x=1"], 0, fails)      # a GyrolabError is not: same config, same code
    assert len(calls) == 1 and record.skipped

    other = compose_config(["time.end=2", *TINY[1:]])
    written = []

    def writes(job_id):
        written.append(job_id)
        (job_dir / "run.nc").write_text("result")
        return job_dir / "run.nc"

    assert run_sweep_job(other, job_dir, ["x=1"], 0, writes).status == FINISHED   # another config: it runs
    assert run_sweep_job(other, job_dir, ["x=1"], 0, writes).skipped
    (job_dir / "run.nc").unlink()                                                 # result gone: run again
    assert not run_sweep_job(other, job_dir, ["x=1"], 0, writes).skipped
    assert len(written) == 2 and written[0] == written[1] == job_identity(other)


@pytest.fixture(scope="module")
def uneven():
    """A sweep of time.n_output = 3, 5 and a failed point: jobs with different numbers of samples."""
    grid = Grid.from_overrides(["time.n_output=3,5,7", "time.end=1"])
    runs = [run(["time.n_output=3", "time.end=1", "output.figures=false"]),
            run(["time.n_output=5", "time.end=1", "output.figures=false"])]
    results = [JobResult(FINISHED, r, job_id=f"id{i}", job_dir=str(i)) for i, r in enumerate(runs)]
    results.append(JobResult("failed", job_id="id2", job_dir="2", error="boom", error_type="ConfigError",
                             exit_code=2))
    return assemble(grid, results), runs


def test_jobs_of_different_lengths_share_a_sample_dimension(uneven):
    ds, runs = uneven
    assert ds.time.dims == ("n_output", "sample") and ds.sizes["sample"] == 5
    np.testing.assert_array_equal(ds.time.sel(n_output=3).values[:3], runs[0].time.values)
    assert np.isnan(ds.time.sel(n_output=3).values[3:]).all() and np.isnan(ds.time.sel(n_output=7)).all()
    np.testing.assert_array_equal(ds.omega.sel(n_output=5).values, runs[1].omega.values)
    assert list(ds.job_status.values) == [1, 1, 2]
    assert list(ds.failed_job_error.values) == ["boom"] and list(ds.failed_job_dir.values) == ["2"]


def test_summary_figures_show_final_values(uneven, tmp_path):
    from gyrolab.figures.options import figure_options
    from gyrolab.figures.sweep import final_values, save_figures

    ds, runs = uneven
    final = final_values(ds.omega)
    for i, r in enumerate(runs):
        np.testing.assert_array_equal(final.isel(n_output=i).values, r.omega.isel(time=-1).values)
    paths = save_figures(ds, tmp_path, *figure_options(None))
    assert sorted(p.name for p in paths) == ["sweep_cost.png", "sweep_final_state.png", "sweep_invariant_drift.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_sweep_round_trips_through_netcdf(uneven, tmp_path):
    import xarray as xr

    from gyrolab.output.dataset import write_dataset

    ds, _ = uneven
    back = xr.load_dataset(write_dataset(ds, tmp_path / "sweep.nc"), decode_times=False)
    xr.testing.assert_identical(back, ds)


def test_slurm_launcher_config_composes():
    cfg = compose_config(["hydra/launcher=slurm", "hydra.launcher.partition=compute"], return_hydra_config=True)
    launcher = cfg.hydra.launcher
    assert launcher._target_ == "hydra_plugins.hydra_submitit_launcher.submitit_launcher.SlurmLauncher"
    assert launcher.partition == "compute" and launcher.cpus_per_task == 1 and launcher.max_num_timeout == 0
    assert cfg.hydra.callbacks.sweep._target_ == "gyrolab.sweep.callbacks.SweepCallback"


def test_watcher_counts_jobs_that_ended_since_it_started(tmp_path):
    from gyrolab.sweep.record import JobRecord, write_record

    old = JobRecord("a", FINISHED, ["x=1"], "code", run="run.nc")
    write_record(tmp_path / "0", old)
    write_record(tmp_path / ".hidden" / "1", old)          # .submitit and .hydra are not job directories
    watcher = SweepWatcher(tmp_path, total=3)
    watcher._before = watcher._snapshot()
    assert watcher.done() == 0
    write_record(tmp_path / "1", old)
    write_record(tmp_path / "0", JobRecord("a", FINISHED, ["x=1"], "code", run="run.nc", skipped=True))
    assert watcher.done() == 2


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_progress_bar_on_a_terminal_log_elsewhere(monkeypatch, caplog):
    monkeypatch.setattr(progress, "BAR_DELAY", 0.0)
    monkeypatch.setattr(progress, "_bars_allowed", True)   # as in a single run, whatever ran before in this process
    screen = Terminal()
    bar = progress.Progress("rk4", 0.0, 10.0, stream=screen)
    with caplog.at_level(logging.INFO, logger="gyrolab.progress"):
        for t in np.linspace(0.0, 10.0, 101):
            bar(t)
    assert "rk4:" in screen.getvalue() and bar._bar is None   # drawn, and closed at t_end
    assert not caplog.records

    quiet = io.StringIO()
    logged = progress.Progress("rk4", 0.0, 10.0, every=0.0, stream=quiet)
    with caplog.at_level(logging.INFO, logger="gyrolab.progress"):
        for t in (2.5, 5.0):
            logged(t)
    assert quiet.getvalue() == ""
    assert [r.getMessage().split("%")[0].split(":")[1].strip() for r in caplog.records] == ["25", "50"]

    monkeypatch.setattr(progress, "_bars_allowed", False)   # sweep jobs: the sweep has the bar
    silent = Terminal()
    progress.Progress("rk4", 0.0, 10.0, stream=silent)(10.0)
    assert silent.getvalue() == ""


def test_lines_above_the_bar_are_whole_lines():
    from tqdm import tqdm

    screen = Terminal()
    bar = tqdm(total=3, file=screen, desc="sweep")
    out = progress.LinesAboveBar(screen, bar)
    out.write("first ")
    assert "first" not in screen.getvalue()      # a partial line waits
    out.write("line\nsecond line\n")
    bar.close()
    text = screen.getvalue()
    assert "first line\nsecond line\n" in text


def test_provenance_names_every_declared_dependency_and_the_code_state():
    import re
    from importlib import metadata

    from gyrolab.output.provenance import provenance

    attrs = provenance()
    for requirement in metadata.requires("gyrolab") or []:
        if "extra ==" not in requirement:
            name = re.match(r"[A-Za-z0-9._-]+", requirement).group(0)
            assert attrs[f"version_{name.replace('-', '_')}"] == metadata.version(name)
    assert attrs["python_version"] and attrs["platform"]
    assert attrs["git_dirty"] in (-1, 0, 1)
    if attrs["git_dirty"] >= 0:
        assert re.fullmatch(r"[0-9a-f]{40}", attrs["git_commit"])
    # a digest only for uncommitted code (a tree dirty in its documentation or tests only has none)
    assert attrs["git_diff_sha256"] == "" or (re.fullmatch(r"[0-9a-f]{64}", attrs["git_diff_sha256"])
                                              and attrs["git_dirty"] == 1)


def test_first_progress_line_gives_no_estimate_only_a_measured_stretch_does(caplog):
    """Issue 24 item 5: the time before the first report includes compilation, so no ETA from it."""
    quiet = io.StringIO()
    logged = progress.Progress("taylor", 0.0, 10.0, every=0.0, stream=quiet)
    with caplog.at_level(logging.INFO, logger="gyrolab.progress"):
        for t in (2.5, 5.0, 7.5):
            logged(t)
    first, *later = [r.getMessage() for r in caplog.records]
    assert "to go" not in first and "compilation included" in first and "measuring the pace" in first
    assert len(later) == 2 and all("to go" in line and "compilation" not in line for line in later)


def test_compile_notes_reach_the_console_before_logging_is_configured(monkeypatch):
    """Issue 24 item 5: the preflight compiles a force plugin's torque before Hydra configures logging; its note
    "compiling force NAME, once" is shown then (Python would drop the INFO record), and only while unconfigured."""
    from gyrolab.kernels import expression

    assert expression.log.name in progress.COMPILE_LOGGERS   # the logger that writes the note
    monkeypatch.setattr(logging.getLogger(), "handlers", [])     # as before Hydra configures logging
    screen = io.StringIO()
    with progress.compile_notes_on_console(screen):
        expression.log.info("compiling %s, once (cached for later runs)", "force spin_damping")
        logging.getLogger("gyrolab.sweep").info("not a compile note")
    expression.log.info("after the preflight: Hydra's handlers")
    assert screen.getvalue() == "gyrolab: compiling force spin_damping, once (cached for later runs)\n"
    assert not expression.log.handlers

    monkeypatch.setattr(logging.getLogger(), "handlers", [logging.NullHandler()])   # configured: left alone
    configured = io.StringIO()
    with progress.compile_notes_on_console(configured):
        expression.log.info("compiling force x, once")
    assert configured.getvalue() == ""
