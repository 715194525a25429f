"""Experiments: tasks built from many scenes (``task: NAME`` in an experiment config).

A plain run has ``task: scene``; an experiment file sets another task and
its own section, and the app hands the composed config to the task's
``run(cfg, out_dir)``, which writes its dataset and figures in ``out_dir``.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from omegaconf import DictConfig

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
