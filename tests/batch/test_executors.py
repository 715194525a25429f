"""Chunks on Dask: a scheduler and two workers started from the ``dask`` command line, as on a cluster.

The chunks are the batch runner's own tasks (``gyrolab.batch.runner.plan_tasks``/``run_chunk``); the
expectation for every chunk is the same chunk integrated in this process (the kernels are
deterministic and each trajectory is independent, so where a chunk runs must not change a bit).
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from gyrolab.batch import executors
from gyrolab.batch.executors import map_chunks
from gyrolab.batch.plan import plan_from_overrides
from gyrolab.batch.runner import Settings, plan_tasks, run_chunk
from gyrolab.errors import ConfigError

pytest.importorskip("distributed")

DASK = str(Path(sys.executable).with_name("dask"))
# A tiny fixed-point scene (heavy top, default body), rk4_numba: the (ω, γ) block kernel.
OVERRIDES = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=2", "time.n_output=2",
             "output.euler_angles=false", "output.figures=false"]


def chunks(n_chunks=3, per_chunk=8):
    """The chunk tasks of a batch (the runner's own, as ``--batch`` makes them): ``per_chunk`` values of r0
    per chunk, one chunk per θ0, final state stored."""
    r0 = ",".join(str(2 + 0.25 * k) for k in range(per_chunk))
    theta0 = ",".join(str(0.3 + 0.2 * k) for k in range(n_chunks))
    plan = plan_from_overrides([*OVERRIDES, f"batch.chunk={per_chunk}", f"initial.theta0={theta0}",
                                f"initial.r0={r0}"])
    tasks = plan_tasks(plan, Settings(output="final", chunk=per_chunk))
    assert len(tasks) == n_chunks
    return tasks


def _stop(process):
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()


@pytest.fixture(scope="module")
def scheduler(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker ADDRESS --nthreads 1``, each its own process; its address."""
    tmp = tmp_path_factory.mktemp("dask")
    scheduler_file = tmp / "scheduler.json"
    processes = []
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}

    def start(*args):
        processes.append(subprocess.Popen([DASK, *args], cwd=tmp, env=env, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL, start_new_session=True))

    try:
        start("scheduler", "--port", "0", "--no-dashboard", "--scheduler-file", str(scheduler_file))
        deadline = time.monotonic() + 60
        while not scheduler_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.05)
        import json

        address = json.loads(scheduler_file.read_text())["address"]
        for _ in range(2):
            start("worker", address, "--nthreads", "1", "--no-dashboard", "--local-directory", str(tmp))
        from distributed import Client

        with Client(address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(2, timeout=60)
        yield address
    finally:
        for process in processes:
            _stop(process)


def in_process(tasks):
    results = {}
    map_chunks(run_chunk, tasks, lambda i, r: results.__setitem__(i, r))
    return results


def test_chunks_on_separately_started_workers_equal_in_process_bit_for_bit(scheduler):
    tasks = chunks()
    expected = in_process(tasks)
    results = {}
    map_chunks(run_chunk, tasks, lambda i, r: results.__setitem__(i, r), scheduler=scheduler)
    assert sorted(results) == list(range(len(tasks)))
    for i in range(len(tasks)):
        assert set(results[i].outputs) == set(expected[i].outputs) >= {"omega", "gamma", "energy"}
        for name, out in expected[i].outputs.items():
            assert np.array_equal(results[i].outputs[name].data, out.data), name   # bit for bit
        assert np.array_equal(results[i].failed, expected[i].failed) and not results[i].failed.any()
    # The chunks ran on the workers: they rebuilt the scene there (once per worker process and batch).
    from distributed import Client

    with Client(scheduler, timeout=30, set_as_default=False) as client:
        kept = client.run(lambda: len(__import__("gyrolab.batch.runner").batch.runner._CONTEXTS))
    assert sum(kept.values()) >= 1 and set(kept.values()) <= {0, 1}


def test_in_flight_chunks_stay_bounded(scheduler):
    """Memory is bounded by a few chunks per worker: tasks are pulled only as results come back."""
    base = chunks(n_chunks=1, per_chunk=2)[0]
    pulled, ahead = [0], []

    def tasks():
        for _ in range(12):
            pulled[0] += 1
            yield base

    done = []

    def on_result(index, result):
        done.append(index)
        ahead.append(pulled[0] - len(done))

    map_chunks(run_chunk, tasks(), on_result, scheduler=scheduler)
    assert sorted(done) == list(range(12))
    # two workers of one thread: at most 2 chunks per thread in flight, so at most 4 pulled and unfinished
    assert max(ahead) <= executors.CHUNKS_PER_THREAD * 2 - 1


@pytest.mark.parametrize("where", ["process", "cluster"])
def test_a_failing_chunk_is_one_sentence_naming_it(scheduler, where):
    tasks = chunks(n_chunks=2, per_chunk=2)
    tasks[1].y0[0, 0] = np.nan
    with pytest.raises(ConfigError) as caught:
        map_chunks(run_chunk, tasks, lambda i, r: None, scheduler=scheduler if where == "cluster" else None)
    message = str(caught.value)
    assert message.startswith("chunk 1 of the batch failed") and "NaN" in message
    assert (scheduler in message) == (where == "cluster") and "\n" not in message
    assert caught.value.exit_code == 2


def test_unreachable_scheduler_is_one_sentence_with_its_address(monkeypatch):
    import socket

    with socket.socket() as probe:  # a port nobody listens on
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT", 1)
    address = f"tcp://127.0.0.1:{port}"
    with pytest.raises(ConfigError) as caught:
        map_chunks(run_chunk, [], lambda i, r: None, scheduler=address)
    assert address in str(caught.value) and "\n" not in str(caught.value) and caught.value.exit_code == 2


def test_scheduler_values_and_missing_dask(monkeypatch):
    with pytest.raises(ConfigError, match="valid: process.*local.*tcp://HOST:PORT"):
        map_chunks(run_chunk, [], lambda i, r: None, scheduler="localhost:8786")
    monkeypatch.setattr(executors, "find_spec", lambda name: None)
    with pytest.raises(ConfigError, match=r'pip install "gyrolab\[cluster\]"'):
        map_chunks(run_chunk, [], lambda i, r: None, scheduler="local")
    ran = []
    map_chunks(len, ["ab", "c"], lambda i, r: ran.append((i, r)))  # in this process, Dask not needed
    assert ran == [(0, 2), (1, 1)]


def test_a_batch_on_separately_started_workers_writes_the_same_dataset(scheduler, tmp_path):
    """The whole --batch path (plan, chunk tasks, workers rebuilding the scene, the streamed store) on the
    CLI-started scheduler and workers gives the dataset of the same batch run in this process."""
    import xarray as xr

    from gyrolab.batch.sweep import run_batch_sweep

    grid = [*OVERRIDES, "batch.output=final", "batch.chunk=4", "initial.r0=2,3,5", "initial.theta0=0.3,0.6,0.9"]
    here = run_batch_sweep(grid, tmp_path / "here")
    from gyrolab.batch.scheduler import use_command_line_scheduler

    use_command_line_scheduler(scheduler)   # what gyrolab --batch --scheduler ADDRESS does (never a config key)
    try:
        there = run_batch_sweep(grid, tmp_path / "there")
    finally:
        use_command_line_scheduler(None)
    with xr.open_dataset(here) as a, xr.open_dataset(there) as b:
        assert int(a.job_status.min()) == 1 and a.sizes["theta0"] == 3
        states = [name for name in a.data_vars if "job_" not in name and name != "error_message"]
        assert states
        for name in states:
            np.testing.assert_array_equal(b[name].values, a[name].values)   # bit for bit
    from distributed import Client

    with Client(scheduler, timeout=30, set_as_default=False) as client:  # the chunks ran there: scenes rebuilt
        built = client.run(lambda: len(__import__("gyrolab.batch.runner").batch.runner._CONTEXTS))
    assert sum(built.values()) >= 1


@pytest.mark.parametrize("how", ["command line", "environment"])
def test_the_command_runs_on_a_scheduler_named_on_its_command_line_or_in_the_environment(scheduler, tmp_path, how):
    """``gyrolab --batch --scheduler ADDRESS`` and ``DASK_SCHEDULER_ADDRESS=ADDRESS gyrolab --batch``: the batch
    runs there (the log names the source) and gives the dataset of the same batch in this process."""
    import xarray as xr

    grid = [*OVERRIDES, "batch.output=final", "batch.chunk=4", "initial.r0=2,3,5", "initial.theta0=0.3,0.6,0.9"]
    option = ["--scheduler", scheduler] if how == "command line" else []
    env = {**os.environ, **({"DASK_SCHEDULER_ADDRESS": scheduler} if how == "environment" else {})}
    env.pop("DASK_SCHEDULER_ADDRESS", None) if how == "command line" else None
    runs = {}
    for name, extra, environment in (("here", [], {k: v for k, v in env.items() if k != "DASK_SCHEDULER_ADDRESS"}),
                                     ("there", option, env)):
        done = subprocess.run([sys.executable, "-m", "gyrolab", "--batch", *extra, *grid, f"hydra.sweep.dir={name}"],
                              cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        runs[name] = done.stderr
    source = "the command line (--scheduler)" if how == "command line" else "the environment (DASK_SCHEDULER_ADDRESS)"
    assert f"on the Dask scheduler at {scheduler} (from {source})" in runs["there"]
    assert "in this process (from the default)" in runs["here"]
    with xr.open_dataset(tmp_path / "here" / "sweep.nc") as a, xr.open_dataset(tmp_path / "there" / "sweep.nc") as b:
        for name in ("omega", "gamma", "energy"):
            np.testing.assert_array_equal(b[name].values, a[name].values)   # bit for bit
