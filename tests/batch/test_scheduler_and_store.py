"""Issue 23, items 1 and 3: whom a batch trusts (the Dask scheduler's address never comes from a config) and a
full disk that loses no finished chunk; ``--batch`` exits non-zero when points failed.

Every command-line case checks the exit status, a single ``gyrolab: error:`` line, no traceback and no new file.
The expected datasets are those of the same batch run uninterrupted (each trajectory is integrated
independently by a deterministic kernel, so an interrupted and resumed batch must equal it bit for bit).
"""

import errno
import os
import resource
import signal
import socket
import threading

import numpy as np
import pytest
import xarray as xr

from gyrolab.batch import executors, scheduler, store
from gyrolab.batch.runner import Settings, run_chunk
from gyrolab.batch.sweep import run_batch_sweep
from gyrolab.errors import ConfigError, OutputError
from tests.conftest import mounted_tmpfs
from tests.helpers import files_under, gyrolab, one_error_line

pytestmark = pytest.mark.slow  # subprocesses under file-size limits, silent peers with their 10 s deadline

SMALL = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=2", "time.n_output=41", "output.euler_angles=false",
         "output.figures=false"]
GRID = [*SMALL, "batch.output=trajectory", "batch.chunk=10", "initial.theta0=0.3,0.5,0.7,0.9",
        "initial.r0=range(2,4,0.2)"]


def cli(args, cwd, limit=None, env=None):
    def limited():   # SIGXFSZ ignored, so that Python sees the write fail with EFBIG
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, resource.RLIM_INFINITY))

    return gyrolab(*args, cwd=cwd, timeout=600, preexec_fn=limited if limit else None,
                   env={**os.environ, **(env or {})})


def data_of(path):
    with xr.open_dataset(path) as ds:
        return {name: ds[name].values.copy() for name in ds.data_vars}


def equal(a, b):
    """Bit-for-bit equality; NaN (a padded or failed entry) equals NaN."""
    return np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def assert_same_data(a, b):
    assert set(a) == set(b) and {"omega", "job_status"} <= set(a)
    for name in a:
        assert equal(a[name], b[name]), name


@pytest.fixture(autouse=True)
def no_command_line_scheduler():
    scheduler.use_command_line_scheduler(None)
    yield
    scheduler.use_command_line_scheduler(None)


# ----------------------------------------------------------------------------- item 1: the trust model


@pytest.mark.parametrize("value", ["tcp://127.0.0.1:8786", "tls://evil.example:8786", "evil:8786"])
def test_an_address_in_a_config_is_refused_in_one_sentence_naming_the_key_and_the_places(value):
    with pytest.raises(ConfigError) as caught:
        Settings.from_config({"scheduler": value})
    message = str(caught.value)
    assert message.startswith("batch.scheduler=") and "run code" in message and "--scheduler" in message
    assert "DASK_SCHEDULER_ADDRESS" in message and "\n" not in message and caught.value.exit_code == 2


def test_process_and_local_may_still_be_configured():
    assert Settings.from_config({"scheduler": "process"}).scheduler is None
    assert Settings.from_config({"scheduler": "local"}).scheduler == "local"
    assert Settings.from_config({"scheduler": "local"}).scheduler_source == "batch.scheduler"


def test_where_the_address_comes_from(monkeypatch):
    import dask

    monkeypatch.delenv(scheduler.ENVIRONMENT, raising=False)
    with dask.config.set({"scheduler-address": None}):
        assert scheduler.choose_scheduler(None) == scheduler.Choice(None, "the default")
    with dask.config.set({"scheduler-address": "tcp://10.0.0.3:8786"}):
        assert scheduler.choose_scheduler(None) == scheduler.Choice("tcp://10.0.0.3:8786",
                                                                    "Dask's configuration (scheduler-address)")
        monkeypatch.setenv(scheduler.ENVIRONMENT, "tcp://10.0.0.2:8786")
        assert scheduler.choose_scheduler(None) == scheduler.Choice("tcp://10.0.0.2:8786",
                                                                    "the environment (DASK_SCHEDULER_ADDRESS)")
        assert scheduler.choose_scheduler("local").scheduler == "local"   # an explicit harmless choice
        scheduler.use_command_line_scheduler("tcp://10.0.0.1:8786")
        try:
            assert scheduler.choose_scheduler(None) == scheduler.Choice("tcp://10.0.0.1:8786",
                                                                        "the command line (--scheduler)")
            with pytest.raises(ConfigError, match="not read from a config"):   # the command line does not excuse it
                scheduler.choose_scheduler("tcp://10.0.0.9:8786")
        finally:
            scheduler.use_command_line_scheduler(None)


def test_a_config_with_an_address_is_refused_on_the_command_line_before_anything_is_written(tmp_path):
    done = cli(["--batch", *SMALL, "batch.scheduler=tcp://127.0.0.1:8786", "initial.r0=2,3", "hydra.sweep.dir=out"],
               tmp_path)
    one_error_line(done, "batch.scheduler=", "--scheduler", code=2)
    assert files_under(tmp_path) == []


class FakePeer:
    """A TCP server on 127.0.0.1 that accepts and then stays silent, or sends garbage."""

    def __init__(self, garbage: bool):
        self.server = socket.socket()
        self.server.bind(("127.0.0.1", 0))
        self.server.listen(8)
        self.address = f"tcp://127.0.0.1:{self.server.getsockname()[1]}"
        self.garbage, self.accepted = garbage, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        while True:
            try:
                connection, _ = self.server.accept()
            except OSError:
                return
            self.accepted.append(connection)
            if self.garbage:   # a length prefix of 3 EiB, then noise: distributed itself tries to allocate it
                connection.sendall(b"\xff" * 64 + b"not a scheduler" * 50)

    def close(self):
        for connection in self.accepted:
            connection.close()
        self.server.close()


def free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.parametrize("peer", ["silent", "garbage", "refused"])
def test_a_peer_that_is_not_a_scheduler_is_one_sentence_within_the_timeout(peer, monkeypatch):
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1)
    fake = FakePeer(garbage=peer == "garbage") if peer != "refused" else None
    address = fake.address if fake else f"tcp://127.0.0.1:{free_port()}"
    try:
        with pytest.raises(ConfigError) as caught:
            executors.map_chunks(run_chunk, [], lambda i, r: None, scheduler=address, source="the test")
    finally:
        if fake:
            fake.close()
    message = str(caught.value)
    assert address in message and "the test" in message and "\n" not in message and caught.value.exit_code == 2
    expected = {"silent": "sent nothing within 1 s", "garbage": "is not a Dask scheduler",
                "refused": "no Dask scheduler answers"}[peer]
    assert expected in message


@pytest.mark.parametrize("peer", ["silent", "garbage", "refused"])
def test_the_command_line_names_a_bad_peer_in_one_line_and_writes_nothing(peer, tmp_path):
    fake = FakePeer(garbage=peer == "garbage") if peer != "refused" else None
    address = fake.address if fake else f"tcp://127.0.0.1:{free_port()}"
    try:
        done = cli(["--batch", "--scheduler", address, *SMALL, "initial.r0=2,3", "hydra.sweep.dir=out"], tmp_path)
    finally:
        if fake:
            fake.close()
    line = one_error_line(done, address, "the command line (--scheduler)", code=2)
    assert peer != "silent" or "sent nothing within 10 s" in line   # the timeout the sentence promises
    assert files_under(tmp_path) == []   # refused before the sweep directory is made


def test_the_environment_is_a_source_too(tmp_path):
    address = f"tcp://127.0.0.1:{free_port()}"
    done = cli(["--batch", *SMALL, "initial.r0=2,3", "hydra.sweep.dir=out"], tmp_path,
               env={"DASK_SCHEDULER_ADDRESS": address})
    one_error_line(done, address, "the environment (DASK_SCHEDULER_ADDRESS)", code=2)
    assert files_under(tmp_path) == []


# ----------------------------------------------------------------------------- item 3: a full disk


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole")
    done = cli(["--batch", *GRID, "hydra.sweep.dir=out"], out)
    assert done.returncode == 0, done.stderr[-2000:]
    return data_of(out / "out" / "sweep.nc")


def test_a_file_size_limit_in_a_batch_is_one_sentence_exit_3_and_the_rerun_completes_identically(tmp_path,
                                                                                                  uninterrupted):
    done = cli(["--batch", *GRID, "hydra.sweep.dir=out"], tmp_path, limit=60_000)
    one_error_line(done, "sweep.nc.part", "file-size limit", "rerun the same command", code=3)
    again = cli(["--batch", *GRID, "hydra.sweep.dir=out"], tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    assert_same_data(data_of(tmp_path / "out" / "sweep.nc"), uninterrupted)
    assert not (tmp_path / "out" / "sweep.nc.part").exists() and not (tmp_path / "out" / "sweep.nc.chunks").exists()


def test_a_full_disk_after_some_chunks_keeps_them_and_the_rerun_continues(tmp_path, monkeypatch, uninterrupted,
                                                                         caplog):
    written = store.Store._write
    calls = {"n": 0}

    def fill_up(self, name, chunk, data):
        calls["n"] += 1
        if chunk.start >= 20:   # chunks 0 and 1 are stored, then the disk is full
            raise OSError(errno.ENOSPC, "No space left on device")
        written(self, name, chunk, data)

    monkeypatch.setattr(store.Store, "_write", fill_up)
    with pytest.raises(OutputError) as caught:
        run_batch_sweep(GRID, tmp_path)
    message = str(caught.value)
    assert "no space left on device" in message and "the 2 chunks already stored are kept" in message
    assert caught.value.exit_code == 3 and "\n" not in message
    journal = (tmp_path / "sweep.nc.chunks").read_text().splitlines()
    assert journal[1:] == ["0", "1"]
    monkeypatch.setattr(store.Store, "_write", written)
    calls["n"] = 0
    with caplog.at_level("INFO", logger="gyrolab.batch"):
        path = run_batch_sweep(GRID, tmp_path)
    assert "2 stored already, 2 to run" in caplog.text
    assert_same_data(data_of(path), uninterrupted)


def test_a_torn_journal_line_is_not_a_chunk_and_is_cut_before_appending(tmp_path):
    journal = tmp_path / "sweep.nc.chunks"
    journal.write_text("identity abc\n0\n1")   # "1" of "12\n": the write failed half-way
    assert store._read_journal(journal, "abc") == {0}
    store._cut_torn_line(journal)
    assert journal.read_text() == "identity abc\n0\n"


def test_an_unreadable_part_is_replaced_not_a_dead_end(tmp_path, uninterrupted):
    out = tmp_path / "out"
    out.mkdir()
    (out / "sweep.nc.part").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))   # a creation cut short
    done = cli(["--batch", *GRID, "hydra.sweep.dir=out"], tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    assert_same_data(data_of(out / "sweep.nc"), uninterrupted)


def test_a_stability_map_under_a_file_size_limit_is_one_sentence_and_resumes_identically(tmp_path):
    args = ["experiment=stability_map", "stability_map.n_theta0=12", "stability_map.n_r0=12", "time.end=5",
            "output.figures=false", "hydra.run.dir=map"]
    whole = cli([*args[:-1], "hydra.run.dir=whole"], tmp_path)
    assert whole.returncode == 0, whole.stderr[-2000:]
    done = cli(args, tmp_path, limit=12_000)
    one_error_line(done, "stability_map.nc.part", "file-size limit", code=3)
    again = cli(args, tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    a, b = data_of(tmp_path / "whole" / "stability_map.nc"), data_of(tmp_path / "map" / "stability_map.nc")
    assert set(a) == set(b) and "indicator" in a
    for name in a:
        assert equal(a[name], b[name]), name


# ----------------------------------------------------------------------------- --batch exit status


def test_a_batch_with_failed_points_exits_1_saying_how_many(tmp_path):
    done = cli(["--batch", *SMALL, "body.a=1.5,-1", "initial.r0=2,3", "hydra.sweep.dir=out"], tmp_path)
    assert done.returncode == 1, done.stderr[-2000:]
    lines = [line for line in done.stderr.splitlines() if line.startswith("gyrolab:")]
    assert len(lines) == 1 and "2 of 4 points failed" in lines[0] and "Traceback" not in done.stderr
    assert (tmp_path / "out" / "sweep.nc").is_file()


# ----------------------------------------------------------------------------- a multirun on a full disk


def test_a_multirun_whose_job_results_cannot_be_written_exits_3_and_the_rerun_completes_identically(tmp_path):
    sweep = ["-m", *SMALL, "time.n_output=2001", "initial.r0=2,3"]
    whole = cli([*sweep, "hydra.sweep.dir=whole"], tmp_path)
    assert whole.returncode == 0, whole.stderr[-2000:]
    done = cli([*sweep, "hydra.sweep.dir=full"], tmp_path, limit=150_000)   # above Hydra's files, below run.nc
    one_error_line(done, "2 of 2 jobs failed", "could not be written", "rerun the same command", code=3)
    again = cli([*sweep, "hydra.sweep.dir=full"], tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    a, b = data_of(tmp_path / "whole" / "sweep.nc"), data_of(tmp_path / "full" / "sweep.nc")
    for name in ("omega", "gamma", "job_status"):
        assert equal(a[name], b[name]), name


@pytest.fixture
def small_tmpfs(tmp_path):
    """A 512 KiB tmpfs (conftest.mounted_tmpfs); skipped where it cannot be mounted."""
    with mounted_tmpfs(tmp_path / "small", "512k") as mount_point:
        yield mount_point


def test_a_really_full_disk_in_a_batch_is_one_sentence_and_the_rerun_with_room_completes(small_tmpfs, tmp_path,
                                                                                         uninterrupted):
    stats = os.statvfs(small_tmpfs)
    free = stats.f_bavail * stats.f_frsize
    filler = small_tmpfs / "filler"
    filler.write_bytes(bytes(max(0, free - 64 * 1024)))   # 64 KiB left: the batch's file needs ~170 KiB
    before = files_under(small_tmpfs)
    done = cli(["--batch", *GRID, f"hydra.sweep.dir={small_tmpfs}"], tmp_path)
    one_error_line(done, "sweep.nc.part", "no space left on device", "rerun the same command", code=3)
    assert [f for f in files_under(small_tmpfs) if f not in before and f != ".gyrolab.lock"] == []
    filler.unlink()   # room again
    again = cli(["--batch", *GRID, f"hydra.sweep.dir={small_tmpfs}"], tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    assert_same_data(data_of(small_tmpfs / "sweep.nc"), uninterrupted)


def test_an_experiment_with_an_address_is_refused_before_its_run_directory_exists(tmp_path):
    done = cli(["experiment=stability_map", "batch.scheduler=tcp://127.0.0.1:8786", "hydra.run.dir=map"], tmp_path)
    one_error_line(done, "batch.scheduler=", "run code", "--scheduler", code=2)
    assert files_under(tmp_path) == []


def test_the_option_reaches_an_experiment_run_by_hydra(tmp_path):
    address = f"tcp://127.0.0.1:{free_port()}"
    done = cli(["--scheduler", address, "experiment=stability_map", "stability_map.n_theta0=2",
                "stability_map.n_r0=2", "time.end=1", "output.figures=false", "hydra.run.dir=map"], tmp_path)
    one_error_line(done, address, "the command line (--scheduler)", "no Dask scheduler answers", code=2)


# ----------------------------------------------------------------------------- follow-ups (harden-batch2)


def test_a_chunk_that_cannot_write_its_own_files_is_exit_3_and_the_rerun_completes(tmp_path, monkeypatch,
                                                                                   uninterrupted):
    """A chunk whose own write fails for want of space (numba writing its cache in a worker, say) is a full disk,
    not a bug: one OutputError sentence, exit 3, the finished chunks kept for the rerun."""
    from gyrolab.batch import runner

    real = runner.run_chunk

    def cache_write_fails(task):
        if task.index == 2:
            raise OSError(errno.EFBIG, "File too large")
        return real(task)

    monkeypatch.setattr(runner, "run_chunk", cache_write_fails)
    with pytest.raises(OutputError) as caught:
        run_batch_sweep(GRID, tmp_path)
    assert caught.value.exit_code == 3 and "chunk 2" in str(caught.value) and "\n" not in str(caught.value)
    monkeypatch.setattr(runner, "run_chunk", real)
    assert_same_data(data_of(run_batch_sweep(GRID, tmp_path)), uninterrupted)


def test_the_last_sync_failing_keeps_every_chunk(tmp_path, monkeypatch, uninterrupted):
    """The finish (counts written, file synced) fails on a full disk: every chunk stays journaled and the rerun
    only finishes the file, running no chunk again."""
    from gyrolab.batch import runner

    real_fsync, calls = store._fsync, []

    def full_at_the_end(path):
        calls.append(path)
        if len(calls) == 6:   # the creation, four chunks, then the finish
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(path)

    monkeypatch.setattr(store, "_fsync", full_at_the_end)
    with pytest.raises(OutputError) as caught:
        run_batch_sweep(GRID, tmp_path)
    assert caught.value.exit_code == 3 and "no space left on device" in str(caught.value)
    monkeypatch.setattr(store, "_fsync", real_fsync)
    monkeypatch.setattr(runner, "run_chunk", lambda task: pytest.fail("a finished chunk ran again"))
    assert_same_data(data_of(run_batch_sweep(GRID, tmp_path)), uninterrupted)


def test_a_stability_map_whose_sections_cannot_be_added_keeps_the_map_and_resumes_identically(tmp_path):
    """A limit above the map's store but below the file with its Poincaré sections: exit 3 in one sentence; the
    rerun adds the sections and ends with the uninterrupted map, bit for bit."""
    args = ["experiment=stability_map", "batch.points=16", "output.figures=false", "hydra.run.dir=map"]
    whole = cli([*args[:-1], "hydra.run.dir=whole"], tmp_path)
    assert whole.returncode == 0, whole.stderr[-2000:]
    final = tmp_path / "whole" / "stability_map.nc"
    done = cli(args, tmp_path, limit=int(0.7 * final.stat().st_size))
    one_error_line(done, "stability_map.nc", "file-size limit", "the map itself is kept", code=3)
    again = cli(args, tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    a, b = data_of(final), data_of(tmp_path / "map" / "stability_map.nc")
    assert set(a) == set(b) and "section_phi" in a
    for name in a:
        assert equal(a[name], b[name]), name


def test_an_old_run_whose_config_records_an_address_still_reproduces(tmp_path):
    """The key stays readable: a dataset written before the trust model, whose stored config names a scheduler's
    address in batch.scheduler, reproduces (a single run never connects to it)."""
    import netCDF4
    import yaml

    done = cli([*SMALL, "time.end=1", "time.n_output=11", "hydra.run.dir=old"], tmp_path)
    assert done.returncode == 0, done.stderr[-2000:]
    with netCDF4.Dataset(tmp_path / "old" / "run.nc", "a") as nc:
        config = yaml.safe_load(nc.getncattr("config"))
        config.setdefault("batch", {})["scheduler"] = "tcp://127.0.0.1:9"
        nc.setncattr("config", yaml.safe_dump(config))
    again = cli(["--reproduce", "old/run.nc"], tmp_path)
    assert again.returncode == 0, again.stderr[-2000:]
    assert "identical" in again.stdout + again.stderr
