"""Where a batch's chunks run: this process, a local Dask cluster (one single-threaded worker per core, so numba does
not oversubscribe them), or an existing Dask scheduler (docs/cluster.md). One process writes the output; at most a
few chunks per worker are submitted at a time, so memory is bounded by a few chunks.
"""

from __future__ import annotations

import errno
import itertools
import logging
import os
import tempfile
import uuid
from pathlib import Path
from collections.abc import Callable, Iterable
from importlib.util import find_spec
from typing import Any, TypeVar

from gyrolab.batch.scheduler import CONNECT_TIMEOUT, IN_PROCESS, LOCAL, probe
from gyrolab.errors import ConfigError, GyrolabError, OutputError, shorten
from gyrolab.output.atomic import reason
from gyrolab.output.trust import private_dir

Task = TypeVar("Task")
Result = TypeVar("Result")

#: chunks submitted per worker thread at a time: one running, one queued (memory: a few chunks per worker)
CHUNKS_PER_THREAD = 2
#: the errnos of a write that failed for want of space: a chunk failing so is a full disk (exit 3), not a bug
FULL_DISK = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)
#: environment of local-cluster workers: one thread each for numba and the BLAS libraries
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def map_chunks(function: Callable[[Task], Result], tasks: Iterable[Task],
               on_result: Callable[[int, Result], None], scheduler: str | None = None,
               source: str = "the caller") -> None:
    """Run ``function`` on every task where ``scheduler`` says; ``on_result(index, result)`` for each result, here,
    as they complete (in task order when they run here); ``source``: where the scheduler's address came from."""
    kind = scheduler_kind(scheduler)
    if kind == "process":
        for index, task in enumerate(tasks):
            try:
                result = function(task)
            except Exception as error:  # noqa: BLE001 - one sentence naming the chunk, whatever went wrong
                raise chunk_error(index, error, "in this process") from error
            on_result(index, result)
        return
    with _client(kind, str(scheduler), source) as client:
        where = "on the local Dask cluster" if kind == "local" else f"on the Dask cluster at {scheduler}"
        _map_on(client, function, tasks, on_result, where=where)


def scheduler_kind(scheduler: str | None) -> str:
    """``"process"``, ``"local"`` or ``"address"``; ConfigError for anything else, or when Dask is missing."""
    if scheduler is None or str(scheduler).strip() in IN_PROCESS:
        return "process"
    text = str(scheduler).strip()
    if text == LOCAL:
        kind = "local"
    elif text.startswith(("tcp://", "tls://")) and len(text) > len("tcp://"):
        kind = "address"
    else:
        raise ConfigError(f"scheduler {shorten(text)!r} is not a scheduler; valid: process (this process), "
                          "local (a Dask cluster on this machine) or the address of a running Dask scheduler "
                          "(tcp://HOST:PORT or tls://HOST:PORT)")
    if find_spec("distributed") is None:
        raise ConfigError(f"scheduler {text} runs chunks on Dask, which is not installed; install it with: "
                          'pip install "gyrolab[cluster]"')
    return kind


def chunk_error(index: int, error: BaseException, where: str) -> GyrolabError:
    """One sentence naming the chunk; a gyrolab error keeps its class (and so its exit status)."""
    message = " ".join(str(error).split()) or type(error).__name__
    if isinstance(error, GyrolabError):
        return type(error)(f"chunk {index} of the batch failed {where}: {message}")
    if isinstance(error, OSError) and error.errno in FULL_DISK:   # e.g. numba writing its cache in a worker
        return OutputError(f"chunk {index} of the batch failed {where}: a file could not be written ({reason(error)}); "
                           "the finished chunks are kept: free some space and rerun the same command")
    return GyrolabError(f"chunk {index} of the batch failed {where} ({type(error).__name__}: {message})")


def _client(kind: str, scheduler: str, source: str) -> Any:
    """A connected ``distributed.Client`` (closing it also closes a local cluster it started); an address is first
    probed (``gyrolab.batch.scheduler.probe``), then connected within the same ``CONNECT_TIMEOUT``."""

    from distributed import Client, LocalCluster  # optional (the cluster extra): imported when used

    if kind == "local":


        # workers spill pickles to their scratch folder and load them back: one only this user can write
        scratch = private_dir(Path(tempfile.gettempdir()) / f"gyrolab-dask-{os.geteuid()}", "Dask's scratch folder")
        cluster = LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR, env=dict(WORKER_ENV),
                               local_directory=str(scratch))
        return Client(cluster, set_as_default=False)
    probe(scheduler, source, CONNECT_TIMEOUT)
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as error:
        reason = " ".join(str(error).split()).rstrip(".") or type(error).__name__
        raise ConfigError(f"no Dask scheduler answers at {scheduler} (from {source}) within {CONNECT_TIMEOUT} s "
                          f"({shorten(reason, 120)}); start one (dask scheduler) or give its address") from None


def _map_on(client: Any, function: Callable[[Task], Result], tasks: Iterable[Task],
            on_result: Callable[[int, Result], None], *, where: str) -> None:
    """Submit at most ``CHUNKS_PER_THREAD`` chunks per worker thread; hand results over as they complete."""
    from distributed import as_completed  # optional (the cluster extra)

    threads = sum(client.nthreads().values()) or 1
    limit = max(2, CHUNKS_PER_THREAD * threads)
    numbered = enumerate(tasks)
    run = uuid.uuid4().hex[:12]
    index_of: dict[str, int] = {}
    pending = as_completed(loop=client.loop)

    def submit(count: int) -> None:
        for index, task in itertools.islice(numbered, count):
            future = client.submit(function, task, key=f"gyrolab-chunk-{run}-{index}", pure=False, retries=0)
            index_of[future.key] = index
            pending.add(future)

    submit(limit)
    try:
        for future in pending:
            index = index_of.pop(future.key)
            if future.status == "error":
                raise chunk_error(index, future.exception(), where)
            result = future.result()
            future.release()  # the cluster forgets the result: memory stays bounded
            on_result(index, result)
            submit(1)
    finally:
        pending.clear()

