"""Where a batch's chunks run: this process, a local Dask cluster, or an existing Dask scheduler.

``map_chunks(function, tasks, on_result, scheduler)`` calls ``function(task)`` for every task and hands
each result to ``on_result(index, result)`` in the calling process as it arrives (so one process writes
the output). ``function`` must be a module-level function and the tasks picklable, so that the same call
runs its chunks in other processes or on other machines:

- ``scheduler`` None or ``"process"``: here, one chunk after another (the compiled kernels use every core
  through numba's threads);
- ``"local"``: a Dask ``LocalCluster`` on this machine, one single-threaded worker process per core
  (numba limited to one thread per worker, so the workers do not oversubscribe the cores);
- ``"tcp://HOST:PORT"`` (or ``tls://``): an existing Dask scheduler and its workers (``dask scheduler``,
  ``dask worker``, a dask-jobqueue ``SLURMCluster``: docs/cluster.md).

``scheduler`` may be a ``gyrolab.batch.scheduler.Choice`` (the value and its source, which messages name);
None: the trusted sources of this invocation (``gyrolab.batch.scheduler.resolve``: the command line's
``--scheduler``, ``DASK_SCHEDULER_ADDRESS``, Dask's ``scheduler-address``), else this process. A string is
the caller's own (Python code): trusted as given.

Before connecting, the address is probed within ``CONNECT_TIMEOUT`` seconds (connect, ask its identity, check
that it is a Dask scheduler): a refused port, a silent peer and a peer that is not a scheduler are one
sentence each, not a hang or a traceback.

At most a few chunks per worker are submitted at a time, so memory is bounded by a few chunks, not by
the batch. A chunk that fails stops the batch with one sentence naming the chunk.

A batch's chunk task (``gyrolab.batch.runner.ChunkTask``) carries what a worker needs to rebuild the
compiled model (a plain resolved config): a plugin torque's compiled function is a machine address that
does not pickle. Each worker process rebuilds it once per config (``gyrolab.batch.runner.run_chunk``) and
reuses it for the next chunks.
"""

from __future__ import annotations

import asyncio
import errno
import itertools
import os
import uuid
from collections.abc import Callable, Iterable
from importlib.util import find_spec
from typing import Any, TypeVar

from gyrolab.batch.scheduler import SCHEDULER_ENV, Choice, resolve
from gyrolab.errors import ConfigError, GyrolabError, OutputError, shorten
from gyrolab.output.atomic import reason

Task = TypeVar("Task")
Result = TypeVar("Result")

IN_PROCESS = ("process", "")
LOCAL = "local"
#: the errnos of a write that failed for want of space: a chunk failing so is an OutputError (exit 3)
FULL_DISK = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)
#: seconds to wait for a scheduler to answer before saying it cannot be reached
CONNECT_TIMEOUT = 10
#: chunks submitted per worker thread at a time: one running, one queued (memory: a few chunks per worker)
CHUNKS_PER_THREAD = 2
#: environment of local-cluster workers: one thread each for numba and the BLAS libraries
WORKER_ENV = {"NUMBA_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}


def map_chunks(function: Callable[[Task], Result], tasks: Iterable[Task],
               on_result: Callable[[int, Result], None], scheduler: str | Choice | None = None) -> None:
    """Run ``function`` on every task where ``scheduler`` says; ``on_result(index, result)`` for each result,
    in this process, in the order they complete (in task order when they run here)."""
    choice = as_choice(scheduler)
    scheduler = choice.scheduler
    kind = scheduler_kind(choice)
    if kind == "process":
        for index, task in enumerate(tasks):
            try:
                result = function(task)
            except Exception as error:  # noqa: BLE001 - one sentence naming the chunk, whatever went wrong
                raise chunk_error(index, error, "in this process") from error
            on_result(index, result)
        return
    with _client(kind, choice) as client:
        _map_on(client, function, tasks, on_result, where=_where(kind, str(scheduler)))


def as_choice(scheduler: str | Choice | None) -> Choice:
    """The scheduler and its source: a Choice as given, a string as the caller's, None from the trusted sources."""
    if isinstance(scheduler, Choice):
        return scheduler
    if scheduler is None:
        return resolve(None)
    return Choice(str(scheduler), "the caller")


def chosen_scheduler(scheduler: str | Choice | None) -> str | None:
    """The scheduler ``map_chunks`` uses for ``scheduler`` (None: this process)."""
    return as_choice(scheduler).scheduler


def scheduler_kind(scheduler: str | Choice | None) -> str:
    """``"process"``, ``"local"`` or ``"address"``; ConfigError for anything else, or when Dask is missing."""
    choice = as_choice(scheduler)
    if choice.scheduler is None or str(choice.scheduler).strip() in IN_PROCESS:
        return "process"
    text = str(choice.scheduler).strip()
    if text == LOCAL:
        kind = "local"
    elif text.startswith(("tcp://", "tls://")) and len(text) > len("tcp://"):
        kind = "address"
    else:
        raise ConfigError(f"scheduler {shorten(text)!r} from {choice.source} is not a scheduler; valid: process (this "
                          "process), local (a Dask cluster on this machine) or the address of a running Dask "
                          "scheduler (tcp://HOST:PORT or tls://HOST:PORT)")
    if find_spec("distributed") is None:
        raise ConfigError(f"scheduler {text} from {choice.source} runs chunks on Dask, which is not installed; "
                          'install it with: pip install "gyrolab[cluster]"')
    return kind


def chunk_error(index: int, error: BaseException, where: str) -> GyrolabError:
    """One sentence naming the chunk; a gyrolab error keeps its class (and so its exit status)."""
    message = " ".join(str(error).split()) or type(error).__name__
    if isinstance(error, GyrolabError):
        return type(error)(f"chunk {index} of the batch failed {where}: {message}")
    if isinstance(error, OSError) and error.errno in FULL_DISK:   # e.g. numba writing its cache: exit 3
        return OutputError(f"chunk {index} of the batch failed {where}: a file could not be written ({reason(error)}); "
                           "the finished chunks are kept: free some space and rerun the same command")
    return GyrolabError(f"chunk {index} of the batch failed {where} ({type(error).__name__}: {message})")


def _where(kind: str, scheduler: str) -> str:
    return "on the local Dask cluster" if kind == "local" else f"on the Dask cluster at {scheduler}"


def _client(kind: str, choice: Choice) -> Any:
    """A connected ``distributed.Client`` (closing it also closes a local cluster it started)."""
    import logging

    from distributed import Client, LocalCluster

    if kind == "local":
        cluster = LocalCluster(n_workers=os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.ERROR, env=dict(WORKER_ENV))
        return Client(cluster, set_as_default=False)
    address = str(choice.scheduler)
    probe_scheduler(address, choice.source)
    try:
        return Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError) as error:
        raise _unreachable(address, choice.source, error) from None


def probe_scheduler(address: str, source: str, timeout: float | None = None) -> None:
    """Connect to ``address``, ask its identity and check that a Dask scheduler answered, all within
    ``timeout`` seconds (``CONNECT_TIMEOUT``); one sentence naming the address and its source otherwise.

    ``distributed.Client`` alone waits without bound on a peer that accepts and stays silent, and a peer
    that sends something else ends in an arbitrary exception (a frame length of exabytes is a MemoryError).
    TLS settings come from Dask's configuration (``distributed.comm.tls``), as the Client's do."""
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    try:
        identity = asyncio.run(_identity(address, timeout))
    except (asyncio.TimeoutError, TimeoutError):
        raise ConfigError(f"the Dask scheduler at {address} (from {source}) did not answer within {timeout:g} s; "
                          "check the address and that the scheduler is running (dask scheduler)") from None
    except OSError as error:
        raise _unreachable(address, source, error) from None
    except Exception as error:  # noqa: BLE001 - whatever a peer that is not a scheduler makes the protocol raise
        raise _not_a_scheduler(address, source, f"{type(error).__name__}: {error}") from None
    if not isinstance(identity, dict) or identity.get("type") != "Scheduler":
        kind = identity.get("type") if isinstance(identity, dict) else type(identity).__name__
        raise _not_a_scheduler(address, source, f"it says it is {shorten(str(kind), 40)}")


async def _identity(address: str, timeout: float) -> Any:
    """The peer's answer to ``identity``, all within ``timeout`` s. A plain TCP connect comes first, so that a
    refused port or an unknown host is an OSError at once (Dask's connect retries it until its timeout); Dask's
    connect (with its handshake, which waits without bound on a silent peer) and the exchange share what is left."""
    import socket
    import time

    from distributed.comm import connect
    from distributed.comm.addressing import get_address_host_port
    from distributed.security import Security

    deadline = time.monotonic() + timeout
    host, port = get_address_host_port(address)
    await asyncio.wait_for(asyncio.to_thread(lambda: socket.create_connection((host, port), timeout).close()),
                           timeout)

    async def exchange() -> Any:
        comm = await connect(address, timeout=timeout, deserialize=False, **Security().get_connection_args("client"))
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    return await asyncio.wait_for(exchange(), max(deadline - time.monotonic(), 0.01))


def _unreachable(address: str, source: str, error: BaseException) -> ConfigError:
    reason = " ".join(str(error).split()).rstrip(".") or type(error).__name__
    return ConfigError(f"no Dask scheduler answers at {address} (from {source}) within {CONNECT_TIMEOUT} s "
                       f"({shorten(reason, 120)}); start one (dask scheduler) or give its address")


def _not_a_scheduler(address: str, source: str, reason: str) -> ConfigError:
    reason = " ".join(reason.split()).rstrip(".")
    return ConfigError(f"the peer at {address} (from {source}) is not a Dask scheduler ({shorten(reason, 120)}); "
                       "check the address and its protocol (tcp:// or tls://, docs/cluster.md)")


def _map_on(client: Any, function: Callable[[Task], Result], tasks: Iterable[Task],
            on_result: Callable[[int, Result], None], *, where: str) -> None:
    """Submit at most ``CHUNKS_PER_THREAD`` chunks per worker thread; hand results over as they complete."""
    from distributed import as_completed

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


__all__ = ["SCHEDULER_ENV", "as_choice", "chosen_scheduler", "chunk_error", "map_chunks", "probe_scheduler",
           "scheduler_kind"]
