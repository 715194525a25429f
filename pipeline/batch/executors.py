"""Where a batch's chunks run.

``map_chunks(function, tasks, on_result)`` calls ``function(task)`` for every task and hands each result
to ``on_result(index, result)`` in the calling process as it arrives (so one process writes the output).
``function`` must be a module-level function and the tasks picklable, so that the same call can run
its chunks elsewhere (another process, a Dask cluster).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

Task = TypeVar("Task")
Result = TypeVar("Result")


def map_chunks(function: Callable[[Task], Result], tasks: Sequence[Task],
               on_result: Callable[[int, Result], None], scheduler: str | None = None) -> None:
    """Run ``function`` on every task; ``scheduler`` None runs them here, one after another
    (the compiled kernels already use every core through numba's threads)."""
    if scheduler not in (None, "", "process"):
        raise ValueError(f"scheduler {scheduler!r} is not available here; valid: process")
    for index, task in enumerate(tasks):
        on_result(index, function(task))


__all__: Sequence[Any] = ["map_chunks"]
