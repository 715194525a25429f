"""Experiments: tasks built from many scenes (``task: NAME`` in an experiment config).

A plain run has ``task: scene``; an experiment file sets another task and
its own section, and the app hands the composed config to the task's
``run(cfg, out_dir)``, which writes its dataset and figures in ``out_dir``.
"""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from pathlib import Path

from omegaconf import DictConfig

from gyrolab.contracts.capabilities import or_list
from gyrolab.engine.unread import covers, given_overrides
from gyrolab.errors import ConfigError, choices

TASKS = {
    "work_precision": "gyrolab.experiments.work_precision",
    # expansion regimes (Ismail (2021), Shaker et al.)
    "regime": "gyrolab.experiments.regime_run",
    "regime_validity": "gyrolab.experiments.regime_validity",
    "ismail2021_tables": "gyrolab.experiments.ismail2021_tables",
    "shaker_omega3": "gyrolab.experiments.shaker_omega3",
    "orbit_family": "gyrolab.experiments.orbit_family",
    # issue 14: a chaos indicator over a grid of initial conditions, as one resumable batch
    "stability_map": "gyrolab.experiments.stability_map",
    # satellite-gyrostat (Yehia & El-kenani (2021))
    "yehia2021_precessions": "gyrolab.experiments.yehia2021_precessions",
}


#: config keys only some runs read (docs/configs.md, "Values a run does not read") and the runs that read them: the
#: tasks that run Scene.run read output.error_estimate (it measures the stored trajectory's error); batch.* is read by
#: gyrolab batch and by the experiments that run one; a regime by the tasks that compare with it (a plain run given
#: a regime is task regime); output.job_figures by the jobs of a sweep
BATCH_COMMAND = "gyrolab batch"
SWEEP = "a sweep (gyrolab -m)"
READ_BY = {
    "batch": ("task stability_map", BATCH_COMMAND),
    "output.error_estimate": ("task scene", "task work_precision", "task yehia2021_precessions"),
    "regime": ("task regime", "task shaker_omega3"),
    "output.job_figures": (SWEEP,),
}
#: config keys a task does not read, because it sets them itself for the scenes it runs or runs none: a value given
#: for them would change nothing; and why (said in the refusal)
NOT_READ_BY = {
    "work_precision": {
        "integrator": "it runs every method of work_precision.methods",
        "accuracy": "auto's settings are listed in work_precision.methods",
        "time.n_output": "it compares final states, with time.n_output=2",
    },
    "yehia2021_precessions": {
        key: "each precession case sets its own body, forces, initial state and span, the span from yehia2021.orbits"
        for key in ("body", "force", "initial", "time")
    },
    "stability_map": {
        key: "the map's grid sets it, from stability_map.theta0, stability_map.r0 and their n_ and _spacing settings"
        for key in ("initial.theta0", "initial.r0")
    },
    "orbit_family": {
        key: "each family of orbit_family.families sets its own body, Newtonian k and tilt, and the continuation "
             "its spins and periods"
        for key in ("system", "body", "force", "initial", "time", "integrator", "accuracy")
    },
    "ismail2021_tables": {
        key: "it regenerates the paper's two tables from the paper's own parameters"
        for key in ("system", "body", "force", "initial", "time", "integrator", "accuracy")
    },
}


def refuse_unread(run: str, overrides: Sequence[str], *, sweep: bool = False) -> None:
    """ConfigError for the first value ``overrides`` give that ``run`` (``task NAME`` or ``gyrolab batch``; ``sweep``:
    its jobs are a sweep's) does not read: a key only other runs read (READ_BY: ``batch.output=final`` on a plain run),
    or one the task does not read (NOT_READ_BY). A config file's value is a default for the runs that read it, and
    null unsets a key: neither is refused."""
    roles = {run, SWEEP} if sweep else {run}
    described = f"{run} in {SWEEP}" if sweep else run
    for key, text in given_overrides(overrides).items():
        if text.partition("=")[2].strip() == "null":
            continue
        for optional, readers in READ_BY.items():
            if covers(optional, key) and not roles & set(readers):
                way = f"run it with {BATCH_COMMAND}, or drop it" if BATCH_COMMAND in readers else "drop it"
                raise ConfigError(f"{text} is read only by {or_list(list(readers))}; this run ({described}) does not "
                                  f"read it, so it would change nothing: {way}")
        for unread, why in NOT_READ_BY.get(run.removeprefix("task "), {}).items():
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


def task_of_config(cfg: DictConfig) -> str:
    """What a config runs: its task, ``regime`` for a plain run with a regime, else ``scene``."""
    task = cfg.get("task") or "scene"
    return "regime" if task == "scene" and cfg.get("regime") else str(task)


def reproduce_task(path: Path, cfg: DictConfig) -> tuple[object, list[str]]:
    """(the comparison, the report's head) of running the experiment a dataset's stored ``cfg`` names again, into a
    temporary directory, and comparing the dataset of the same name (``gyrolab reproduce PATH/regime.nc``, ...)."""
    import tempfile

    import xarray as xr
    from omegaconf import open_dict

    from gyrolab.sweep.reproduce import compare, load_run

    task = task_of_config(cfg)
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
