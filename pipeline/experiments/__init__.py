"""Experiments: tasks built from many scenes (``task: NAME`` in an experiment config, its own section beside the
scene's); the app hands the composed config to the task's ``run(cfg, out_dir)``, which writes its dataset and figures.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
import tempfile
from collections.abc import Sequence
from functools import cache
from pathlib import Path

import xarray as xr
from omegaconf import DictConfig, open_dict

from gyrolab.contracts.capabilities import or_list
from gyrolab.engine.schemas import Task, only_declared_keys
from gyrolab.engine.unread import covers, given_overrides
from gyrolab.errors import ConfigError, choices
from gyrolab.sweep.reproduce import compare, load_run

#: a declaration ``TASK = Task("NAME", ...)`` in a module of this package names the task that module runs
_DECLARATION = re.compile(r'^TASK = Task\(\s*"(\w+)"', re.MULTILINE)


def _task_modules() -> dict[str, str]:
    """Task name -> module, read from the declarations' text (importing every experiment would cost ~0.6 s)."""
    found = {}
    for module in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        source = Path(__path__[0], f"{module.name}.py")
        declared = _DECLARATION.search(source.read_text(encoding="utf-8")) if source.is_file() else None
        if declared:
            found[declared.group(1)] = f"{__name__}.{module.name}"
    return found


#: task name -> the module whose ``run(cfg, out_dir)`` runs it (and whose ``TASK`` says what it reads and sets)
TASKS = _task_modules()
#: a plain run (Scene.run: it measures the stored trajectory's error), gyrolab batch, the jobs of a sweep
SCENE = Task("scene", reads=("output.error_estimate",))
BATCH_COMMAND = "gyrolab batch"
SWEEP = "a sweep (gyrolab -m)"
_RUNS = {BATCH_COMMAND: Task(BATCH_COMMAND, reads=("batch",)), SWEEP: Task(SWEEP, reads=("output.job_figures",))}


def declaration(run: str) -> Task:
    """What ``run`` (``task NAME``, ``gyrolab batch``, a sweep) declares it reads and sets (imports its module)."""
    name = run.removeprefix("task ")
    if name in TASKS:
        return importlib.import_module(TASKS[name]).TASK
    if run in _RUNS:
        return _RUNS[run]
    return SCENE if name == "scene" else Task(name)  # an unknown task: run_task refuses it in its own sentence


@cache
def read_by() -> dict[str, tuple[str, ...]]:
    """Each key only some runs read (``gyrolab.engine.schemas.only_declared_keys``) -> the runs that declare it."""
    runs = {"task scene": SCENE, **{f"task {n}": declaration(f"task {n}") for n in TASKS}, **_RUNS}
    return {key: tuple(name for name, task in runs.items() if key in task.reads) for key in only_declared_keys()}


def refuse_unread(run: str, overrides: Sequence[str], *, sweep: bool = False) -> None:
    """ConfigError for the first value ``overrides`` give that ``run`` (``task NAME`` or ``gyrolab batch``; ``sweep``:
    its jobs are a sweep's) does not read: a key only other runs read (``batch.output=final`` on a plain run), or one
    the task sets itself (its declaration's ``sets``). A config file's value is a default for the runs that read it,
    and null unsets a key: neither is refused."""
    roles = [declaration(run), *([_RUNS[SWEEP]] if sweep else [])]
    described = f"{run} in {SWEEP}" if sweep else run
    for key, text in given_overrides(overrides).items():
        if text.partition("=")[2].strip() == "null":
            continue
        for optional in only_declared_keys():
            if covers(optional, key) and not any(optional in role.reads for role in roles):
                readers = read_by()[optional]
                way = f"run it with {BATCH_COMMAND}, or drop it" if BATCH_COMMAND in readers else "drop it"
                raise ConfigError(f"{text} is read only by {or_list(list(readers))}; this run ({described}) does not "
                                  f"read it, so it would change nothing: {way}")
        for unread, why in roles[0].sets.items():
            if covers(unread, key):
                raise ConfigError(f"{text} is not read by {run} ({why}); drop it")


def check_task(name: str, cfg: DictConfig, out_dir: Path) -> None:
    """The refusals an experiment can make before anything runs (its module's ``check(cfg, out_dir)``, if any):
    the preflight calls it, so that a bad grid or output name leaves no run directory behind."""
    if name in TASKS:
        check = getattr(importlib.import_module(TASKS[name]), "check", None)
        if check is not None:
            check(cfg, out_dir)


def run_task(name: str, cfg: DictConfig, out_dir: Path) -> list[Path]:
    """Run experiment task ``name``; returns the files it wrote."""
    if name not in TASKS:
        raise ConfigError(f"unknown task {name!r}; valid choices: {choices(['scene', *TASKS])}")
    return importlib.import_module(TASKS[name]).run(cfg, out_dir)


def task_of(cfg: DictConfig) -> str:
    """What a config runs: its task, ``regime`` for a plain run with a regime, else ``scene``."""
    task = cfg.get("task") or "scene"
    return "regime" if task == "scene" and cfg.get("regime") else str(task)


def reproduce_task(path: Path, cfg: DictConfig) -> tuple[object, list[str]]:
    """(the comparison, the report's head) of running the experiment a dataset's stored ``cfg`` names again, into a
    temporary directory, and comparing the dataset of the same name (``gyrolab reproduce PATH/regime.nc``, ...)."""
    task = task_of(cfg)
    if task not in TASKS:
        raise ConfigError(f"{path} was written by task {task!r}, which this gyrolab does not have; valid choices: "
                          f"{choices(['scene', *TASKS])}")
    cfg = cfg.copy()
    if isinstance(cfg.get("output"), DictConfig) and "figures" in cfg.output:
        with open_dict(cfg):
            cfg.output.figures = False   # the datasets are compared, not the figures
    with tempfile.TemporaryDirectory(prefix="gyrolab-reproduce-") as tmp:
        written = [Path(p) for p in run_task(task, cfg, Path(tmp))]
        same_name = [p for p in written if p.name == Path(path).name and p.suffix == ".nc"]
        if not same_name:
            datasets = sorted({p.name for p in written if p.suffix == ".nc"})
            raise ConfigError(f"{path}: task {task} writes {', '.join(datasets) or 'no dataset'}, not "
                              f"{Path(path).name}; give the dataset it wrote under its own name")
        new = xr.load_dataset(same_name[0], decode_times=False, decode_timedelta=False)
    stored = load_run(path)
    head = [f"reproducing {path} ({stored.attrs.get('title', '?')}): task {task} run again"]
    return compare(stored, new), head
