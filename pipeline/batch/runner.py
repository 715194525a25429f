"""Running a plan: chunks of points, each a picklable task integrated by the integrator's batch kernel, or by one
``integrate`` call per point with that point's system (docs/batch.md, "Chunks, kernels, progress").
"""

from __future__ import annotations

import json
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from omegaconf import OmegaConf

from gyrolab.batch import executors
from gyrolab.batch.integrate import integrate_arrays, integrate_points
from gyrolab.batch.outputs import MODES, Output, indicator_outputs, merge_rows, state_outputs
from gyrolab.batch.plan import Plan, _with_values
from gyrolab.batch.scheduler import choose_scheduler
from gyrolab.batch.store import Store
from gyrolab.contracts.integrator import BATCH_KERNEL, CHOOSES_METHOD, VECTOR_LANES
from gyrolab.engine.progress import duration
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError
from gyrolab.kernels.vector_width import lane_attributes

log = logging.getLogger("gyrolab.batch")

#: a chunk's trajectories (points × output times × state, float64) stay under ``batch.memory`` MiB
DEFAULT_MEMORY_MIB = 64
MAX_CHUNK = 200_000
INTEGRATION_FAILED = "the trajectory became non-finite (NaN or inf); reduce integrator.step or choose an adaptive " \
                     "integrator"


@dataclass(frozen=True)
class Settings:
    output: str = "reductions"
    decimate: int = 10
    chunk: int | None = None        # None: from ``memory``
    memory: float = DEFAULT_MEMORY_MIB
    scheduler: str | None = None    # never from a config: ``gyrolab.batch.scheduler.choose_scheduler``
    scheduler_source: str = "the default"

    @classmethod
    def from_config(cls, node: Any) -> Settings:
        node = dict(node or {})
        output = node.get("output", cls.output)
        if output not in MODES:
            raise ConfigError(f"batch.output={output!r} is not a batch output; valid choices: {', '.join(MODES)}")
        decimate = node.get("decimate", cls.decimate)
        if isinstance(decimate, bool) or not isinstance(decimate, int) or decimate < 1:
            raise ConfigError(f"batch.decimate={decimate!r} must be a positive integer (store every k-th output time)")
        chunk = node.get("chunk", "auto")
        if chunk in (None, "auto"):
            chunk = None
        elif isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
            raise ConfigError(f"batch.chunk={chunk!r} must be a positive number of points or auto")
        memory = node.get("memory", cls.memory)
        if isinstance(memory, bool) or not isinstance(memory, (int, float)) or not memory > 0:
            raise ConfigError(f"batch.memory={memory!r} must be a positive number of MiB")
        where = choose_scheduler(node.get("scheduler"))
        return cls(output=output, decimate=decimate, chunk=chunk, memory=float(memory), scheduler=where.scheduler,
                   scheduler_source=where.source)


@dataclass
class RunStats:
    """What ``run_plan`` did: the file, chunks run now, seconds in the kernels and in all."""

    path: Path
    chunks: int = 0
    kernel_time: float = 0.0    # inside the integration kernels (``integrate_arrays``; its first call loads them)
    wall_time: float = 0.0      # the chunks' phase: from the first task handed over to the file renamed
    chunk_time: float = 0.0     # the chunks' own wall time (kernels plus their outputs), summed
    plan_time: float = 0.0      # the plan (``gyrolab.batch.sweep.run_batch`` sets it)


@dataclass(frozen=True)
class Chunk:
    """Points ``start:stop`` (flat, C order): one block of the grid, stored at ``slab``."""

    start: int
    stop: int
    slab: tuple            # an int or a slice per grid dimension
    shape: tuple[int, ...]  # the block's shape over the grid dimensions


@dataclass
class ChunkTask:
    index: int
    config: dict[str, Any]          # the first valid point's plain config: what a worker rebuilds
    config_key: str
    output: str
    decimate: int
    times: np.ndarray
    rows: np.ndarray                # rows of the chunk with a valid point
    y0: np.ndarray                  # their initial states
    params: np.ndarray              # their compiled-model parameters
    combo: np.ndarray               # per row: its combination of body/force values (a key of ``combos``)
    combos: dict[int, dict[str, Any]]  # per combination in the chunk: the body/force values that differ from ``config``
    n_rows: int
    #: the integrator to run (``auto``: the method and tolerance chosen once for the batch); None: the config's
    integrator: Any = None


@dataclass
class ChunkResult:
    index: int
    outputs: dict[str, Output]
    failed: np.ndarray              # (n_rows,) the integration failed (non-finite)
    kernel_time: float
    wall_time: float
    #: the integrator settings the chunk ran with (adaptive kernels; None for fixed steps and the indicator)
    settings: dict | None = None
    #: the first chunk of its process: its kernel time includes loading (or compiling) the kernels
    first_in_process: bool = False


def chunk_size(plan: Plan, settings: Settings) -> int:
    """Points per chunk: ``batch.chunk``, else as many as keep the chunk's trajectories under ``batch.memory``."""
    if settings.chunk is not None:
        return settings.chunk
    state = max(plan.y0.shape[1], 1)
    per_point = len(plan.times) * state * 8 * (2 if settings.output in ("trajectory", "decimated") else 1)
    return int(min(MAX_CHUNK, max(1, settings.memory * 2**20 // per_point)))


def chunks(shape: tuple[int, ...], size: int) -> list[Chunk]:
    """Blocks of at most ``size`` points (at least one row of the last dimension), each a hyperslab."""
    inner = [math.prod(shape[k:]) for k in range(len(shape) + 1)]
    k = next(k for k in range(len(shape) + 1) if inner[k] <= size)
    if k == 0:
        return [Chunk(0, inner[0], tuple(slice(None) for _ in shape), shape)]
    d = k - 1
    block = max(1, size // inner[k])
    out = []
    for prefix in np.ndindex(*shape[:d]):
        base = (np.ravel_multi_index(prefix, shape[:d]) if d else 0) * inner[d]
        for lo in range(0, shape[d], block):
            hi = min(lo + block, shape[d])
            slab = tuple(int(p) for p in prefix) + (slice(lo, hi),) + tuple(slice(None) for _ in shape[k:])
            out.append(Chunk(base + lo * inner[k], base + hi * inner[k], slab, (hi - lo,) + shape[k:]))
    return out


def run_plan(plan: Plan, path: Path, settings: Settings, only: set[int] | None = None) -> RunStats:
    """Integrate every valid point of ``plan``, streaming to ``path`` (resuming a killed run of the same
    command); ``only``: just the chunks of these numbers (``gyrolab reproduce --points``: the others stay missing)."""
    size = chunk_size(plan, settings)
    blocks = chunks(plan.shape, size)
    identity = plan.identity(size)
    store = Store(path, plan, identity, settings, messages=[*plan.messages, INTEGRATION_FAILED])
    done = store.open()
    if done is None:   # already complete
        return RunStats(path)
    integrator, store.integrator_attributes = batch_integrator(plan, settings)
    pending = [i for i in range(len(blocks)) if i not in done and (only is None or i in only)]
    built = {i: chunk_task(plan, blocks[i], i, settings, integrator) for i in pending}
    tasks = [task for task in built.values() if task is not None]
    empty = [i for i, task in built.items() if task is None]
    log.info("batch: %d points in %d chunks of ≤ %d (%s), %d stored already, %d to run; output %s", plan.size,
             len(blocks), size, settings.output, len(done), len(tasks), path)
    for i in empty:   # no valid point: only the points' errors, which the store wrote when it was created
        store.chunk_done(i, blocks[i], None)
    progress = _Progress(len(tasks))
    kind = executors.scheduler_kind(settings.scheduler)
    if tasks and kind == "process":
        _share_systems(plan)
    if tasks:
        log.info("batch: chunks run %s (from %s)", {"process": "in this process", "local": "on a local Dask cluster"}
                 .get(kind, f"on the Dask scheduler at {settings.scheduler}"), settings.scheduler_source)

    def on_result(_: int, result: ChunkResult) -> None:
        store.chunk_done(result.index, blocks[result.index], result)
        progress.update(result)

    executors.map_chunks(run_chunk, tasks, on_result, scheduler=settings.scheduler, source=settings.scheduler_source)
    store.finish()
    return progress.summary(path)


def batch_integrator(plan: Plan, settings: Settings) -> tuple[Any, dict[str, Any]]:
    """(the integrator every chunk runs, its dataset attributes, which always say how the points ran:
    ``batch_path``); None: the config's own. An integrator that chooses its method (CHOOSES_METHOD) chooses here,
    once for the batch, on its valid points (docs/batch.md, "integrator=auto chooses once per batch")."""
    if plan.base is None or settings.output == "indicator" or not plan.integrator_class.supports(CHOOSES_METHOD):
        return None, {} if plan.base is None else path_attributes(plan.integrator_class, settings)

    scene = Scene.from_config(OmegaConf.create(plan.base))
    valid = np.flatnonzero(plan.valid)
    start = time.perf_counter()
    method, choice = scene.integrator.choose_batch_method(scene.compiled_model, plan.times, plan.y0[valid],
                                                          plan.combo_params[plan.combo[valid]])
    settings_text = ", ".join(f"{k.removeprefix('integrator_')}={v:.3g}" if isinstance(v, float)
                              else f"{k.removeprefix('integrator_')}={v}" for k, v in method.attributes().items())
    log.info("batch: %s chose %s (%s) for every chunk, in %.1f s", scene.integrator.name, method.name, settings_text,
             time.perf_counter() - start)
    return method, {**{k: v for k, v in choice.items() if v is not None}, **path_attributes(type(method), settings)}


def path_attributes(integrator: type, settings: Settings) -> dict[str, Any]:
    """How a batch's points run with ``integrator`` (the dataset's ``batch_path``) and, for a vectorised batch kernel,
    the lane width it was compiled for and the CPU's vector width."""
    if settings.output == "indicator":
        return {"batch_path": "variational kernel"}
    if not integrator.supports(BATCH_KERNEL):
        return {"batch_path": "one integrate() call per point"}
    if not integrator.supports(VECTOR_LANES):
        return {"batch_path": "batch kernel"}
    return {"batch_path": "batch kernel, vectorised across trajectories", **lane_attributes()}


def chunk_task(plan: Plan, chunk: Chunk, index: int, settings: Settings, integrator: Any = None) -> ChunkTask | None:
    """The picklable task of one chunk (None: the chunk has no valid point)."""
    valid = plan.valid[chunk.start:chunk.stop]
    rows = np.flatnonzero(valid)
    if not rows.size:
        return None
    points = chunk.start + rows
    base_combo = int(plan.combo[int(np.argmax(plan.valid))])
    combo = plan.combo[points]
    combos = {int(c): (plan.combo_values[c] if c != base_combo else {}) for c in np.unique(combo)}
    return ChunkTask(index=index, config=plan.base, config_key=plan.base_key, output=settings.output,
                     decimate=settings.decimate, times=plan.times, rows=rows, y0=plan.y0[points],
                     params=plan.combo_params[combo], combo=combo, combos=combos,
                     n_rows=chunk.stop - chunk.start, integrator=integrator)


def plan_tasks(plan: Plan, settings: Settings) -> list[ChunkTask]:
    """Every chunk of ``plan`` with a valid point as its task (what ``run_plan`` hands the executor)."""
    integrator = batch_integrator(plan, settings)[0]
    blocks = chunks(plan.shape, chunk_size(plan, settings))
    tasks = (chunk_task(plan, block, i, settings, integrator) for i, block in enumerate(blocks))
    return [task for task in tasks if task is not None]


_CONTEXTS: dict[str, Any] = {}


def _context(key: str, config: dict[str, Any]) -> dict[str, Any]:
    """The scene of a batch's config (its compiled model, integrator), built once per process."""
    context = _CONTEXTS.get(key)
    if context is None:

        scene = Scene.from_config(OmegaConf.create(config))
        context = {"scene": scene, "compiled": scene.compiled_model, "systems": {}}
        _CONTEXTS.clear()   # one batch at a time per process
        _CONTEXTS[key] = context
    return context


def _share_systems(plan: Plan) -> None:
    """Chunks run in this process reuse the systems the plan built, one per combination of body/force values
    (a Monte Carlo over bodies builds each body once, not again per chunk); workers elsewhere build their own."""
    if plan.base is None:
        return
    systems = _context(plan.base_key, plan.base)["systems"]
    base_combo = int(plan.combo[int(np.argmax(plan.valid))])
    for c, system in plan.systems.items():
        if c != base_combo:
            systems.setdefault(_combo_key(plan.combo_values[c]), system)


def _combo_key(values: dict[str, Any]) -> str:
    return json.dumps(values, sort_keys=True, default=str)


def _system(context: dict[str, Any], config: dict[str, Any], values: dict[str, Any]) -> Any:
    """The system with a point's body and force values (built once per process and combination)."""
    if not values:
        return context["scene"].system
    systems, key = context["systems"], _combo_key(values)
    if key not in systems:
        systems[key] = Scene.from_config(OmegaConf.create(_with_values(config, values))).system
    return systems[key]


_kernels_called = False   # whether this process has run a chunk (its kernels are loaded)


def run_chunk(task: ChunkTask) -> ChunkResult:
    """Integrate one chunk's valid points and compute what ``task.output`` stores."""

    global _kernels_called
    first, _kernels_called = not _kernels_called, True
    # reported when it starts, not only when it ends: a one-chunk batch would otherwise say nothing for minutes
    log.info("batch: chunk %d: integrating %d points%s", task.index + 1, len(task.rows),
             " (the first chunk of this process loads the integration kernels, and compiles them once on a fresh "
             "cache: minutes)" if first else "")
    start = time.perf_counter()
    context = _context(task.config_key, task.config)
    compiled = context["compiled"]
    integrator = task.integrator if task.integrator is not None else context["scene"].integrator
    if task.output == "indicator":
        kernel = time.perf_counter()
        outputs = indicator_outputs(compiled, integrator, task.times, task.y0, task.params)
        kernel_time = time.perf_counter() - kernel
        failed = np.zeros(len(task.rows), dtype=bool)
        for out in outputs.values():
            failed |= ~np.isfinite(out.data.reshape(len(task.rows), -1)).all(axis=1)
        settings = None
    else:
        groups = [(_system(context, task.config, task.combos[int(c)]), np.flatnonzero(task.combo == c))
                  for c in np.unique(task.combo)]
        if integrator.supports(BATCH_KERNEL):
            solution = integrate_arrays(compiled, integrator, task.times, task.y0, task.params, failures="mark")
        else:   # one integrate() call per point, each with its own system's right-hand side: a single run's numbers
            rhs = {int(j): system.rhs for system, rows in groups for j in rows}
            solution = integrate_points(integrator, rhs.__getitem__, task.times, task.y0, compiled, task.params,
                                        failures="mark")
        kernel_time = solution.wall_time
        failed = np.asarray(solution.failed, dtype=bool)
        settings = solution.settings
        with np.errstate(invalid="ignore"):   # every row, so that a chunk whose points all failed still has its
            # (every variable: the store is created from the first chunk's)
            outputs = state_outputs(task.output, task.decimate, solution.t, solution.y, groups)
        for out in outputs.values():
            out.data[failed] = np.nan
    all_failed = np.zeros(task.n_rows, dtype=bool)
    all_failed[task.rows] = failed
    return ChunkResult(index=task.index, outputs=merge_rows(outputs, task.rows, task.n_rows), failed=all_failed,
                       kernel_time=kernel_time, wall_time=time.perf_counter() - start, settings=settings,
                       first_in_process=first)


class _Progress:
    """A log line per chunk (points done, rate, ETA) and a summary (share of the time in the kernels)."""

    def __init__(self, n_chunks: int) -> None:
        self.n_chunks = n_chunks
        self.chunks = 0
        self.kernel = 0.0
        self.in_chunks = 0.0
        self.start = time.perf_counter()
        self.loading = 0.0   # kernel time of chunks that were their process's first (loading or compiling)

    def update(self, result: ChunkResult) -> None:
        self.chunks += 1
        self.kernel += result.kernel_time
        self.loading += result.kernel_time if result.first_in_process else 0.0
        self.in_chunks += result.wall_time
        elapsed = time.perf_counter() - self.start
        eta = elapsed / self.chunks * (self.n_chunks - self.chunks)
        log.info("batch: chunk %d/%d done (%.0f%%), %s elapsed, ETA %s", self.chunks, self.n_chunks,
                 100.0 * self.chunks / max(self.n_chunks, 1), duration(elapsed), duration(eta))

    def summary(self, path: Path) -> RunStats:
        elapsed = time.perf_counter() - self.start
        if self.chunks:
            log.info("batch: %d chunks in %s, %.0f%% of it in the integration kernels%s", self.chunks,
                     duration(elapsed), 100.0 * self.kernel / max(elapsed, 1e-9),
                     f" (of which {duration(self.loading)} in the first chunk of each process, loading or compiling "
                     "them)" if self.loading else "")
        return RunStats(path, self.chunks, self.kernel, elapsed, self.in_chunks)
