"""Issue 23, items 1 and 3: whom a batch trusts, and what a full disk costs.

- A Dask scheduler's address comes only from the command line, the environment or Dask's configuration, never
  from a config, an experiment or an override of ``batch.scheduler`` (connecting trusts the peer with code
  execution). A silent peer, a peer that is not a scheduler and a refused port are one sentence each, within
  the promised time.
- A failed write (a file-size limit, ENOSPC) in ``--batch``, a multirun sweep or a stability map is one sentence,
  exit 3, and loses no finished chunk: the next run completes bit-identical to an uninterrupted one.
- ``--batch`` exits non-zero when points failed, saying how many.
"""

from __future__ import annotations

import os
import socket
import sys
import threading
from pathlib import Path

import pytest

from gyrolab.batch import executors, scheduler
from gyrolab.errors import ConfigError

TINY = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=1", "time.n_output=11",
        "output.euler_angles=false", "output.figures=false"]


def last_line(done) -> str:
    return done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ""


def one_sentence(done, *fragments) -> str:
    line = last_line(done)
    assert line.startswith("gyrolab: error: "), done.stderr[-3000:]
    assert "Traceback" not in done.stderr, done.stderr[-3000:]
    for fragment in fragments:
        assert fragment in line, line
    return line


# ---- 1. the trust model ---------------------------------------------------------------------------------------------

@pytest.fixture
def clean_sources(monkeypatch):
    """No scheduler from the environment, Dask's configuration or an earlier command line."""
    monkeypatch.delenv(scheduler.SCHEDULER_ENV, raising=False)
    monkeypatch.setattr(scheduler, "_dask_config_address", lambda: None)
    scheduler.use_command_line_scheduler(None)
    yield
    scheduler.use_command_line_scheduler(None)


def test_an_address_from_a_config_is_refused_in_one_sentence(clean_sources):
    for address in ("tcp://127.0.0.1:8786", "tls://head:8786", "localhost:8786"):
        with pytest.raises(ConfigError) as caught:
            scheduler.resolve(address)
        message = str(caught.value)
        assert "batch.scheduler=" in message and "--scheduler" in message and "DASK_SCHEDULER_ADDRESS" in message
        assert "\n" not in message


def test_the_sources_in_order_and_named(clean_sources, monkeypatch):
    assert scheduler.resolve(None) == scheduler.Choice(None, scheduler.DEFAULT)
    assert scheduler.resolve("local") == scheduler.Choice("local", scheduler.CONFIG)
    monkeypatch.setattr(scheduler, "_dask_config_address", lambda: "tcp://from-dask:1")
    assert scheduler.resolve(None) == scheduler.Choice("tcp://from-dask:1", scheduler.DASK_CONFIG)
    monkeypatch.setenv(scheduler.SCHEDULER_ENV, "tcp://from-env:2")
    assert scheduler.resolve(None) == scheduler.Choice("tcp://from-env:2", scheduler.ENVIRONMENT)
    assert scheduler.resolve("process").scheduler == "process"  # a config's process/local wins over the environment
    scheduler.use_command_line_scheduler("tcp://from-cli:3")
    assert scheduler.resolve("tcp://anything:4") == scheduler.Choice("tcp://from-cli:3", scheduler.COMMAND_LINE)


def test_dask_configuration_is_read(clean_sources, monkeypatch):
    import dask

    monkeypatch.undo()  # the real reader, the environment still clean
    monkeypatch.delenv(scheduler.SCHEDULER_ENV, raising=False)
    scheduler.use_command_line_scheduler(None)
    with dask.config.set({"scheduler-address": "tcp://configured:8786"}):
        assert scheduler.resolve(None) == scheduler.Choice("tcp://configured:8786", scheduler.DASK_CONFIG)


def test_parse_scheduler_option():
    assert scheduler.parse_scheduler_option(["a=1", "--scheduler", "tcp://h:1", "b=2"]) == ("tcp://h:1", ["a=1", "b=2"])
    assert scheduler.parse_scheduler_option(["--scheduler=local"]) == ("local", [])
    assert scheduler.parse_scheduler_option(["a=1"]) == (None, ["a=1"])
    with pytest.raises(ConfigError, match="--scheduler needs a value"):
        scheduler.parse_scheduler_option(["--scheduler"])


class Peer:
    """A TCP server on localhost that accepts and then stays silent or sends garbage."""

    def __init__(self, garbage: bytes | None) -> None:
        self.server = socket.socket()
        self.server.bind(("127.0.0.1", 0))
        self.server.listen(8)
        self.address = f"tcp://127.0.0.1:{self.server.getsockname()[1]}"
        self.garbage, self.connections = garbage, []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                connection, _ = self.server.accept()
            except OSError:
                return
            self.connections.append(connection)
            if self.garbage is not None:
                try:
                    connection.sendall(self.garbage)
                except OSError:
                    pass

    def close(self) -> None:
        for connection in self.connections:
            connection.close()
        self.server.close()


def refused_port() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"tcp://127.0.0.1:{probe.getsockname()[1]}"


@pytest.mark.parametrize("peer", ["silent", "http", "zeros", "refused"])
def test_a_peer_that_is_not_a_scheduler_is_one_sentence_in_bounded_time(peer, clean_sources, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1)
    garbage = {"silent": None, "http": b"HTTP/1.1 400 Bad Request\r\n\r\n" * 40, "zeros": b"\0" * 4096}
    server = Peer(garbage[peer]) if peer != "refused" else None
    address = server.address if server else refused_port()
    scheduler.use_command_line_scheduler(address)
    done = threading.Event()
    outcome = {}

    def attempt():
        try:
            executors.map_chunks(len, ["ab"], lambda i, r: None)
        except BaseException as error:  # noqa: BLE001 - the test looks at what came out
            outcome["error"] = error
        done.set()

    threading.Thread(target=attempt, daemon=True).start()
    try:
        # the bound: the promised second plus slack for a loaded machine; without it a silent peer held for minutes
        assert done.wait(60), f"a {peer} peer held the batch"
    finally:
        if server:
            server.close()
    error = outcome.get("error")
    assert isinstance(error, ConfigError), repr(error)
    message = str(error)
    assert address in message and "the command line (--scheduler)" in message and "\n" not in message
    expected = {"silent": "did not answer within 1 s", "http": "is not a Dask scheduler",
                "zeros": "is not a Dask scheduler", "refused": "no Dask scheduler answers"}[peer]
    assert expected in message, message


def test_an_address_from_the_environment_is_named_as_such(clean_sources, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1)
    address = refused_port()
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)
    with pytest.raises(ConfigError) as caught:
        executors.map_chunks(len, ["ab"], lambda i, r: None)
    assert "(from the environment (DASK_SCHEDULER_ADDRESS))" in str(caught.value)
    assert "batch.scheduler" not in str(caught.value)


def test_gyrolab_batch_refuses_an_address_in_a_config_and_leaves_nothing(cli, tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "DASK_SCHEDULER_ADDRESS"}
    refused = cli("--batch", *TINY, "initial.r0=1,2", "batch.scheduler=tcp://127.0.0.1:9", "hydra.sweep.dir=grid",
                  env_extra={"DASK_SCHEDULER_ADDRESS": ""})
    assert refused.returncode == 2
    one_sentence(refused, "batch.scheduler=", "--scheduler", "DASK_SCHEDULER_ADDRESS")
    assert not (tmp_path / "grid").exists()
    del env


def test_gyrolab_batch_scheduler_option_names_its_source(cli, tmp_path):
    pytest.importorskip("distributed")
    address = refused_port()
    done = cli("--batch", *TINY, "initial.r0=1,2", "--scheduler", address, "hydra.sweep.dir=grid")
    assert done.returncode == 2
    one_sentence(done, address, "from the command line (--scheduler)")
    assert not (tmp_path / "grid").exists()   # probed before the sweep directory is made


# ---- --batch's exit status ------------------------------------------------------------------------------------------

def test_batch_with_failed_points_exits_1_saying_how_many(cli, tmp_path):
    """RK4 with a step far too long for a fast spin overflows (two of three points), as -m exits 1 for a failed
    job; the dataset is complete all the same."""
    done = cli("--batch", "integrator=rk4_numba", "integrator.step=0.9", "time.end=200", "time.n_output=3",
               "output.euler_angles=false", "batch.chunk=1", "initial.r0=500,400,0.1", "hydra.sweep.dir=grid")
    assert done.returncode == 1, done.stderr[-2000:]
    assert last_line(done).startswith("gyrolab: 2 of 3 points failed") and "Traceback" not in done.stderr
    assert (tmp_path / "grid" / "sweep.nc").is_file()
    fine = cli("--batch", *TINY, "initial.r0=1,2", "hydra.sweep.dir=fine")
    assert fine.returncode == 0 and "failed" not in fine.stderr, fine.stderr[-2000:]


# ---- 3. a full disk loses nothing -----------------------------------------------------------------------------------

GRID = [*TINY, "time.end=2", "time.n_output=51", "batch.output=trajectory", "batch.chunk=4",
        "initial.r0=range(1,3,0.25)", "initial.theta0=0.3,0.6"]   # 16 points, 4 chunks


def data_variables(path: Path) -> dict:
    import xarray as xr

    with xr.open_dataset(path) as ds:
        return {name: ds[name].values.copy() for name in ds.data_vars}


def assert_same_data(path: Path, reference: Path) -> None:
    import numpy as np

    got, want = data_variables(path), data_variables(reference)
    assert sorted(got) == sorted(want)
    for name, values in want.items():
        np.testing.assert_array_equal(got[name], values, err_msg=name)   # exact: bit for bit (NaN where NaN)


def with_file_size_limit(limit: int):
    """A subprocess's preexec_fn: a file-size limit of ``limit`` bytes, SIGXFSZ ignored so that a write past it
    is an OSError (EFBIG) in Python, as a full disk is (ENOSPC)."""
    def limit_files() -> None:
        import resource
        import signal

        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    return limit_files


def gyrolab_limited(cwd: Path, limit: int | None, *args: str):
    import subprocess

    return subprocess.run([sys.executable, "-m", "gyrolab", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=600, preexec_fn=with_file_size_limit(limit) if limit else None)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    from gyrolab.batch.sweep import run_batch_sweep

    return run_batch_sweep(GRID, tmp_path_factory.mktemp("uninterrupted"))


def test_a_chunk_write_failing_for_want_of_space_keeps_the_finished_chunks(tmp_path, monkeypatch, uninterrupted):
    """ENOSPC on the third chunk's write: one sentence, exit status 3, two chunks kept in the journal; the rerun
    runs the others only and ends with the data of an uninterrupted run, bit for bit."""
    import errno

    from gyrolab.batch import runner, store
    from gyrolab.batch.sweep import run_batch_sweep
    from gyrolab.errors import OutputError

    real_write, calls = store.Store._write, []

    def full_disk(self, name, chunk, data):
        calls.append(name)
        if calls.count("job_status") == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_write(self, name, chunk, data)

    monkeypatch.setattr(store.Store, "_write", full_disk)
    with pytest.raises(OutputError) as caught:
        run_batch_sweep(GRID, tmp_path)
    message = str(caught.value)
    assert caught.value.exit_code == 3 and "\n" not in message
    assert "no space left on device" in message and "the 2 finished chunks" in message and "rerun" in message
    part = tmp_path / "sweep.nc.part"
    assert part.is_file() and not (tmp_path / "sweep.nc").exists()
    monkeypatch.setattr(store.Store, "_write", real_write)
    ran = []
    real_run_chunk = runner.run_chunk
    monkeypatch.setattr(runner, "run_chunk", lambda task: ran.append(task.index) or real_run_chunk(task))
    path = run_batch_sweep(GRID, tmp_path)
    assert sorted(ran) == [2, 3]   # the two finished chunks are not run again
    assert not part.exists()
    assert_same_data(path, uninterrupted)


def test_the_last_sync_failing_keeps_every_chunk(tmp_path, monkeypatch, uninterrupted):
    """The last step (the counts written and the file synced) fails: every chunk stays journaled, the rerun only
    finishes the file."""
    import errno

    from gyrolab.batch import runner, store
    from gyrolab.batch.sweep import run_batch_sweep
    from gyrolab.errors import OutputError

    real_fsync, calls = store._fsync, []

    def full_disk_at_the_end(path):
        calls.append(path)
        if len(calls) == 6:   # the creation, four chunks, then the finish
            raise OSError(errno.ENOSPC, "No space left on device")
        real_fsync(path)

    monkeypatch.setattr(store, "_fsync", full_disk_at_the_end)
    with pytest.raises(OutputError, match="the 4 finished chunks"):
        run_batch_sweep(GRID, tmp_path)
    monkeypatch.setattr(store, "_fsync", real_fsync)
    monkeypatch.setattr(runner, "run_chunk", lambda task: pytest.fail("a finished chunk ran again"))
    assert_same_data(run_batch_sweep(GRID, tmp_path), uninterrupted)


@pytest.mark.parametrize("fraction", [0.2, 0.95])
def test_gyrolab_batch_under_a_file_size_limit_is_one_sentence_and_resumes(tmp_path, fraction, uninterrupted):
    """A real file-size limit (setrlimit in the child): exit 3, one sentence naming the limit, no traceback, no
    partial store that blocks the rerun; the rerun with no limit completes, bit-identical."""
    args = ["--batch", *GRID, "hydra.sweep.dir=grid"]
    limit = int(fraction * uninterrupted.stat().st_size)
    failed = gyrolab_limited(tmp_path, limit, *args)
    assert failed.returncode == 3, failed.stderr[-3000:]
    one_sentence(failed, "sweep.nc.part", "file-size limit")
    assert not (tmp_path / "grid" / "sweep.nc").exists()
    done = gyrolab_limited(tmp_path, None, *args)
    assert done.returncode == 0, done.stderr[-3000:]
    assert_same_data(tmp_path / "grid" / "sweep.nc", uninterrupted)


def test_an_unreadable_part_that_never_held_a_chunk_is_created_again(tmp_path, uninterrupted):
    """A partial store left by an older gyrolab whose creation failed (truncated, no journaled chunk) does not
    block the batch."""
    from gyrolab.batch.sweep import run_batch_sweep

    (tmp_path / "sweep.nc.part").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))
    assert_same_data(run_batch_sweep(GRID, tmp_path), uninterrupted)


SWEEP = ["-m", "time.end=2", "time.n_output=201", "output.figures=false", "initial.r0=1,2,3"]


@pytest.fixture(scope="module")
def uninterrupted_sweep(tmp_path_factory):
    where = tmp_path_factory.mktemp("sweep")
    done = gyrolab_limited(where, None, *SWEEP, "hydra.sweep.dir=ms")
    assert done.returncode == 0, done.stderr[-3000:]
    return where / "ms"


@pytest.mark.parametrize("fraction", [0.25, 0.6])
def test_a_multirun_under_a_file_size_limit_exits_3_and_resumes(tmp_path, fraction, uninterrupted_sweep):
    """Per-job run.nc (a limit below a run's size) or sweep.nc (below the sweep's size): exit 3 with one sentence;
    the rerun with room runs what is missing and ends with the uninterrupted sweep's data, bit for bit."""
    run_size = (uninterrupted_sweep / "0" / "run.nc").stat().st_size
    sweep_size = (uninterrupted_sweep / "sweep.nc").stat().st_size
    limit = int(fraction * run_size) if fraction < 0.5 else max(run_size + 4096, int(fraction * sweep_size))
    if limit >= sweep_size:
        pytest.skip("the sweep's file is not larger than a run's here")
    failed = gyrolab_limited(tmp_path, limit, *SWEEP, "hydra.sweep.dir=ms")
    assert failed.returncode == 3, failed.stderr[-3000:]
    one_sentence(failed, "file-size limit")
    done = gyrolab_limited(tmp_path, None, *SWEEP, "hydra.sweep.dir=ms")
    assert done.returncode == 0, done.stderr[-3000:]
    variables = data_variables(uninterrupted_sweep / "sweep.nc")
    got = data_variables(tmp_path / "ms" / "sweep.nc")
    import numpy as np

    for name in variables:
        if "time" in name or name.startswith(("job_", "failed_")):
            continue   # wall times and the job bookkeeping differ between sessions by design
        np.testing.assert_array_equal(got[name], variables[name], err_msg=name)


STABILITY = ["experiment=stability_map", "batch.points=16", "hydra.run.dir=sm"]


@pytest.fixture(scope="module")
def uninterrupted_map(tmp_path_factory):
    where = tmp_path_factory.mktemp("map")
    done = gyrolab_limited(where, None, *STABILITY)
    assert done.returncode == 0, done.stderr[-3000:]
    return where / "sm" / "stability_map.nc"


@pytest.mark.parametrize("fraction", [0.3, 0.7])
def test_a_stability_map_under_a_file_size_limit_exits_3_and_resumes(tmp_path, fraction, uninterrupted_map):
    """The map's store (0.3) or its Poincaré sections' rewrite (0.7) fails: exit 3, one sentence; the rerun
    completes with the uninterrupted map's data, bit for bit."""
    failed = gyrolab_limited(tmp_path, int(fraction * uninterrupted_map.stat().st_size), *STABILITY)
    assert failed.returncode == 3, failed.stderr[-3000:]
    one_sentence(failed, "file-size limit", "rerun")
    done = gyrolab_limited(tmp_path, None, *STABILITY)
    assert done.returncode == 0, done.stderr[-3000:]
    assert_same_data(tmp_path / "sm" / "stability_map.nc", uninterrupted_map)


def test_a_run_that_recorded_an_address_still_reproduces(cli, tmp_path):
    """batch.scheduler is not used by a single run, and an old dataset's stored config may name an address: the
    key stays readable, so reproducing it works (only running a batch with it is refused)."""
    done = cli(*TINY, "batch.scheduler=tcp://127.0.0.1:9", "hydra.run.dir=old")
    assert done.returncode == 0, done.stderr[-2000:]
    again = cli("--reproduce", "old/run.nc")
    assert again.returncode == 0, again.stderr[-2000:]
