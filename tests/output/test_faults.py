"""Faults lose nothing and leave nothing broken: full disks, file-size limits, kill -9, two processes, orphans.

The faults are real where that is cheap and safe (a file-size limit set with setrlimit in a forked
child, a tiny tmpfs when the tests run as root, SIGKILL of a process in the middle of a write, a
second process holding a lock) and simulated otherwise (a writer that raises the errno a full disk
or a read-only file system gives). What each test expects comes from the fault it makes: the
errno's meaning, the file it was writing, the process it killed.
"""

import errno
import fcntl
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from tests.conftest import mounted_tmpfs
import xarray as xr

from gyrolab.errors import OutputError
from gyrolab.output import atomic
from gyrolab.output.atomic import atomic_open, atomic_path
from gyrolab.output.dataset import write_dataset
from gyrolab.output.lock import LOCK_NAME, Busy, writing_in
from gyrolab.sweep.aggregate import wait_for_jobs
from gyrolab.sweep.job import run_sweep_job
from gyrolab.sweep.record import ELSEWHERE, FAILED, FINISHED, read_record

BIG = xr.Dataset({"x": ("n", np.arange(200_000, dtype=float), {"units": "1", "long_name": "ramp"})})  # 1.6 MB


def leftovers(directory):
    return sorted(p.name for p in Path(directory).iterdir())


def assert_one_sentence(error, path, why):
    text = str(error)
    assert "\n" not in text and str(path) in text and why in text, text
    assert error.exit_code == 3


# ----------------------------------------------------------------------------- write failures


@pytest.mark.parametrize("code, why", [
    (errno.ENOSPC, "no space left on device"),
    (errno.EDQUOT, "disk quota exceeded"),
    (errno.EROFS, "read-only file system"),
    (errno.EACCES, "permission denied"),
    (errno.EFBIG, "file too large"),
])
def test_a_failing_write_is_one_sentence_and_leaves_no_file(code, why, tmp_path, monkeypatch):
    (tmp_path / "run.nc").write_bytes(b"the previous result")

    def half_then_fail(self, path, **kwargs):
        Path(path).write_bytes(b"\x89HDF partial")
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(xr.Dataset, "to_netcdf", half_then_fail)
    with pytest.raises(OutputError) as caught:
        write_dataset(BIG, tmp_path / "run.nc")
    assert_one_sentence(caught.value, tmp_path / "run.nc", why)
    assert leftovers(tmp_path) == ["run.nc"] and (tmp_path / "run.nc").read_bytes() == b"the previous result"


def test_netcdf_hdf_error_on_a_full_disk_says_no_space(tmp_path, monkeypatch):
    """netCDF reports a full disk as RuntimeError('NetCDF: HDF error'); the file system says why."""

    def hdf_error(self, path, **kwargs):
        Path(path).write_bytes(b"\x89HDF partial")
        raise RuntimeError("NetCDF: HDF error")

    class Full:  # what statvfs says of a full disk: no free block
        f_bfree = f_bavail = 0
        f_frsize = 4096

    monkeypatch.setattr(xr.Dataset, "to_netcdf", hdf_error)
    monkeypatch.setattr(atomic.os, "statvfs", lambda path: Full)
    with pytest.raises(OutputError) as caught:
        write_dataset(BIG, tmp_path / "run.nc")
    assert_one_sentence(caught.value, tmp_path / "run.nc", "no space left on device")
    assert leftovers(tmp_path) == []


def test_a_file_size_limit_is_named_and_leaves_no_file(tmp_path):
    """A real EFBIG: a forked child with RLIMIT_FSIZE below the dataset's size (SIGXFSZ ignored)."""
    import resource

    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: limit, write, report the error's text through the pipe
        message = "no error"
        try:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (100_000, resource.RLIM_INFINITY))
            write_dataset(BIG, tmp_path / "run.nc")
        except BaseException as error:  # noqa: BLE001 - everything goes back to the parent
            message = f"{type(error).__name__}: {error}"
        os.write(write, message.encode())
        os._exit(0)
    os.close(write)
    os.waitpid(pid, 0)
    with os.fdopen(read) as stream:
        message = stream.read()
    assert message.startswith("OutputError: ") and "\n" not in message, message
    assert str(tmp_path / "run.nc") in message and "file-size limit" in message, message
    assert leftovers(tmp_path) == []


@pytest.fixture
def tiny_tmpfs(tmp_path):
    """A 256 KiB tmpfs (conftest.mounted_tmpfs); skipped where it cannot be mounted."""
    with mounted_tmpfs(tmp_path / "small", "256k") as mount_point:
        yield mount_point


def test_a_really_full_disk_is_one_sentence(tiny_tmpfs):
    with pytest.raises(OutputError) as caught:
        write_dataset(BIG, tiny_tmpfs / "run.nc")   # 1.6 MB into 256 KiB
    assert_one_sentence(caught.value, tiny_tmpfs / "run.nc", "no space left on device")
    assert leftovers(tiny_tmpfs) == []
    small = BIG.isel(n=slice(0, 1000))               # 8 kB fits: the file system itself is fine
    write_dataset(small, tiny_tmpfs / "run.nc")
    assert leftovers(tiny_tmpfs) == ["run.nc"]
    (tiny_tmpfs / "filler").write_bytes(bytes(_free_bytes(tiny_tmpfs)))   # now really full
    with pytest.raises(OutputError, match="no space left on device"):   # netCDF says EACCES here: checked
        write_dataset(small, tiny_tmpfs / "next.nc")
    from hydra.core import utils as hydra_utils

    import gyrolab.sweep.callbacks  # noqa: F401 - makes Hydra's .hydra/*.yaml copies tolerate a full disk

    from omegaconf import OmegaConf

    hydra_utils._save_config(OmegaConf.create({"a": "x" * 10_000}), "config.yaml", tiny_tmpfs)   # a warning, no file
    with writing_in(tiny_tmpfs / "job"):          # a lock needs no data block: a full disk does not stop it
        pass
    assert leftovers(tiny_tmpfs) == ["filler", "job", "run.nc"]


def _free_bytes(directory):
    stats = os.statvfs(directory)
    return stats.f_bavail * stats.f_frsize


def test_other_errors_of_the_writer_are_not_disguised(tmp_path):
    with pytest.raises(ZeroDivisionError):
        with atomic_path(tmp_path / "x.csv") as tmp:
            tmp.write_text("half")
            1 / 0
    assert leftovers(tmp_path) == []


# ----------------------------------------------------------------------------- kill -9 and stale temporaries


def test_kill_9_during_a_write_breaks_nothing_and_the_rerun_cleans_up(tmp_path):
    final = tmp_path / "run.nc"
    final.write_text("finished result of the previous run")
    (tmp_path / "figures").mkdir()
    (tmp_path / "figures" / "energy.png").write_text("a finished figure")
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child writes slowly and is killed in the middle
        try:
            with atomic_open(final, "w") as handle:
                handle.write("half of a new result")
                handle.flush()
                os.write(write, b"writing")
                time.sleep(60)
        finally:
            os._exit(1)
    os.close(write)
    assert os.read(read, 7) == b"writing"
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    os.close(read)
    stray = [name for name in leftovers(tmp_path) if name.endswith(".tmp")]
    assert len(stray) == 1 and stray[0].startswith(".run.nc.")              # the only trace of the kill
    assert final.read_text() == "finished result of the previous run"       # the finished result is intact
    (tmp_path / "figures" / ".energy.png.x1.tmp").write_text("a figure killed mid-write")
    (tmp_path / "notes.tmp").write_text("a user's file, not ours")
    with writing_in(tmp_path):                                               # what the next run does first
        assert leftovers(tmp_path) == [LOCK_NAME, "figures", "notes.tmp", "run.nc"]
        assert leftovers(tmp_path / "figures") == ["energy.png"]
    assert leftovers(tmp_path) == ["figures", "notes.tmp", "run.nc"]        # the lock goes with the run


# ----------------------------------------------------------------------------- two processes, one directory


def hold_like_another_process(directory):
    """An flock on the directory's lock file through a descriptor of its own (what another process holds)."""
    Path(directory).mkdir(parents=True, exist_ok=True)
    fd = os.open(Path(directory) / LOCK_NAME, os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX)
    os.write(fd, b"pid 4242 on elsewhere\n")
    return fd


def test_a_second_run_into_a_directory_in_use_is_refused_before_hydra_writes(tmp_path, monkeypatch, capsys):
    from gyrolab import app

    run_dir = tmp_path / "run"
    fd = hold_like_another_process(run_dir)
    (run_dir / "run.nc").write_text("the first run's result")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "time.end=0.1", "time.n_output=3", "output.figures=false",
                                      f"hydra.run.dir={run_dir}"])
    try:
        with pytest.raises(SystemExit) as stop:
            app.main()
    finally:
        os.close(fd)
    assert stop.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "in use by another gyrolab run" in lines[0] and "pid 4242" in lines[0], lines
    assert leftovers(run_dir) == [LOCK_NAME, "run.nc"]   # no .hydra/ of the refused run, no log, nothing replaced
    assert (run_dir / "run.nc").read_text() == "the first run's result"


def test_a_held_directory_is_refused_in_process_and_free_after_release(tmp_path):
    fd = hold_like_another_process(tmp_path)
    with pytest.raises(Busy, match="in use by another gyrolab run .pid 4242 on elsewhere."):
        with writing_in(tmp_path):
            pass
    os.close(fd)   # the holder dies: the kernel drops its lock, the stale file does not matter
    with writing_in(tmp_path), writing_in(tmp_path):   # and one process may nest its own lock
        assert (tmp_path / LOCK_NAME).read_text().startswith(f"pid {os.getpid()} ")


def test_two_resumes_never_run_a_job_twice(tmp_path):
    """A job another live process holds is left to it; the aggregator waits for it to end."""
    from gyrolab.engine.config import compose_config

    cfg = compose_config(["time.end=0.1", "time.n_output=3", "output.figures=false"])
    job_dir = tmp_path / "sweep" / "0"
    ran = []

    def work(job_id):
        ran.append(job_id)
        return write_dataset(BIG.assign_attrs(job_id=job_id), job_dir / "run.nc")

    fd = hold_like_another_process(job_dir)
    record = run_sweep_job(cfg, job_dir, ["x=1"], 0, work)
    assert record.status == ELSEWHERE and ran == [] and read_record(job_dir) is None

    def other_process_finishes():
        time.sleep(0.2)
        (job_dir / "ended").write_text("")
        os.close(fd)

    finisher = threading.Thread(target=other_process_finishes)
    finisher.start()
    wait_for_jobs(tmp_path / "sweep")   # returns only once the holder let go
    assert (job_dir / "ended").exists()
    finisher.join()
    assert run_sweep_job(cfg, job_dir, ["x=1"], 0, work).status == FINISHED and len(ran) == 1
    assert run_sweep_job(cfg, job_dir, ["x=1"], 0, work).skipped and len(ran) == 1


def test_a_write_failure_fails_the_job_and_is_retried_on_resume(tmp_path, caplog):
    from gyrolab.engine.config import compose_config

    cfg = compose_config(["time.end=0.1", "time.n_output=3", "output.figures=false"])

    def disk_full(job_id):
        raise OutputError(f"cannot write {str(tmp_path / 'run.nc')!r}: no space left on device")

    with caplog.at_level(logging.ERROR, logger="gyrolab.sweep"):
        record = run_sweep_job(cfg, tmp_path, ["x=1"], 0, disk_full)
    assert record.status == FAILED and record.exit_code == 3 and "no space left on device" in record.error
    assert read_record(tmp_path).status == FAILED                      # recorded: sweep.nc's failed-job table
    assert not read_record(tmp_path).deterministic                      # the disk may have room next time
    record = run_sweep_job(cfg, tmp_path, ["x=1"], 0, lambda job_id: write_dataset(BIG, tmp_path / "run.nc"))
    assert record.status == FINISHED and not record.skipped


def test_sweep_nc_on_a_full_disk_is_one_sentence_exit_3(tmp_path, monkeypatch, capsys):
    from gyrolab import app
    from gyrolab.engine import progress
    from gyrolab.sweep import aggregate

    def full(ds, path):
        raise OutputError(f"cannot write {str(path)!r}: no space left on device")

    monkeypatch.setattr(aggregate, "write_dataset", full)   # the jobs' run.nc are written; sweep.nc is not
    monkeypatch.setattr(progress, "_bars_allowed", progress._bars_allowed)   # a multirun job turns bars off
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "-m", "body.a=1.5", "time.end=0.1", "time.n_output=3",
                                      "output.figures=false", "hydra.sweep.dir=sweep"])
    with pytest.raises(SystemExit) as stop:
        app.main()
    assert stop.value.code == 3
    err = capsys.readouterr().err.strip()
    # the log is on stderr too (logs to stderr, results to stdout); the error is its one last sentence
    last = err.splitlines()[-1]
    assert [line for line in err.splitlines() if "error" in line.lower()] == [last] and "Traceback" not in err, err
    assert last.startswith("gyrolab: error:") and "no space left on device" in last and "sweep.nc" in last, err
    assert "gyrolab --aggregate" in last                                   # how to finish once there is room
    assert len(list((tmp_path / "sweep").glob("*/run.nc"))) == 1          # the job's result is there
    assert not (tmp_path / "sweep" / "sweep.nc").exists() and not list((tmp_path / "sweep").glob(".*.tmp"))


# ----------------------------------------------------------------------------- orphans


def process_alive(pid):
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_joblib_workers_die_with_the_killed_launcher(tmp_path):
    sweep = tmp_path / "sweep"
    # a job of minutes (RK4 with a small step) on a joblib worker
    args = [sys.executable, "-m", "gyrolab", "-m", "body.a=1.5", "integrator=rk4", "integrator.step=1e-4",
            "time.end=1000", "time.n_output=3", "output.figures=false", "hydra/launcher=joblib",
            "hydra.launcher.n_jobs=2", f"hydra.sweep.dir={sweep}"]
    launcher = subprocess.Popen(args, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    workers = set()
    try:
        deadline = time.monotonic() + 120
        while not workers and time.monotonic() < deadline and launcher.poll() is None:
            time.sleep(0.1)
            for lock in sweep.glob(f"*/{LOCK_NAME}"):
                text = lock.read_text() if lock.exists() else ""
                if text.startswith("pid "):
                    workers.add(int(text.split()[1]))
        assert len(workers) == 1 and launcher.pid not in workers, (workers, launcher.poll())
    finally:
        launcher.kill()          # kill -9 of the launching process
        launcher.wait()
    deadline = time.monotonic() + 30   # generous; they stop within a second or so
    while any(process_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    survivors = [pid for pid in workers if process_alive(pid)]
    for pid in survivors:
        os.kill(pid, signal.SIGKILL)
    assert not survivors
    assert not list(sweep.glob("*/run.nc"))   # nothing half-written where the jobs were


# ----------------------------------------------------------------------------- progress


def test_rk4_reports_progress_inside_a_long_output_interval():
    from gyrolab.plugins.integrators.rk4 import PROGRESS_STEPS, RK4

    seen = []
    n_steps = 5 * PROGRESS_STEPS
    RK4(step=1.0 / n_steps).integrate(lambda t, y: -y, np.array([0.0, 1.0]), np.array([1.0]), seen.append)
    inside = [t for t in seen if 0.0 < t < 1.0]
    assert len(inside) == 4 and seen[-1] == 1.0   # one report per PROGRESS_STEPS steps, then the output time
    assert np.allclose(inside, [0.2, 0.4, 0.6, 0.8])


@pytest.mark.parametrize("seconds, shown", [
    (42, "42 s"), (450, "7.5 min"), (7000, "117 min"), (3 * 86400, "3.0 days"),
    (9e9, "285 years"),            # 9e9 s / (365.25 × 86400 s)
])
def test_remaining_time_is_in_units_people_read(seconds, shown):
    from gyrolab.engine.progress import duration

    assert duration(seconds) == shown


@pytest.mark.parametrize("name", ["rk4_numba", "lie_poisson"])
def test_compiled_fixed_step_reports_inside_a_long_output_interval(name, monkeypatch):
    from gyrolab.engine.scene import compose_scene
    from gyrolab.plugins.integrators import compiled_solvers

    scene = compose_scene([f"integrator={name}", "integrator.step=1e-4", "time.end=1", "time.n_output=2"])
    args = (scene.system.rhs, scene.times, scene.system.initial_state())
    whole = scene.integrator.integrate(*args, None, scene.compiled)          # 10^4 steps in one call
    monkeypatch.setattr(compiled_solvers._Chunks, "step_budget", 1000)       # pieces of 1000 steps
    seen = []
    pieces = scene.integrator.integrate(*args, seen.append, scene.compiled)
    assert np.allclose([t for t in seen if t < 1.0], np.arange(1, 10) / 10) and seen[-1] == 1.0
    assert pieces.stats.n_steps == whole.stats.n_steps == 10_000
    # the same steps, the piece boundaries rounded: equal to rounding error
    np.testing.assert_allclose(pieces.y, whole.y, rtol=1e-12, atol=1e-12)


def test_a_netcdf_error_about_content_is_not_called_a_write_failure(tmp_path, monkeypatch):
    def bad_content(self, path, **kwargs):
        raise RuntimeError("NetCDF: Not a valid data type or _FillValue type mismatch")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", bad_content)
    with pytest.raises(RuntimeError, match="Not a valid data type"):   # a bug to see, not a full disk
        write_dataset(BIG, tmp_path / "run.nc")
    assert leftovers(tmp_path) == []
