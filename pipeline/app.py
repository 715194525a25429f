"""The ``gyrolab`` command: a Hydra app that runs one scene (or a multirun sweep) per invocation.

Before Hydra starts, a preflight turns the usual mistakes — an unknown plugin
name, a malformed override, an invalid scene, an unwritable output
directory — into one sentence and a non-zero exit, so that no run directory
with a partial ``run.nc`` is left behind.

In a multirun each job is resumable and a failing job is recorded, not fatal
(``gyrolab.sweep.job``); the sweep callback then writes ``sweep.nc``. Two
more commands work on results: ``gyrolab --reproduce PATH/run.nc`` and
``gyrolab --aggregate SWEEP_DIR``.
"""

from __future__ import annotations

import logging
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import hydra
from hydra._internal.utils import get_args_parser
from hydra.core.hydra_config import HydraConfig
from hydra import initialize_config_module
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.errors import OverrideParseException
from hydra.types import RunMode
from omegaconf import DictConfig, open_dict

from gyrolab.engine.config import (
    CONFIG_MODULE,
    SELECTABLE_GROUPS,
    compose_config,
    group_options,
    register_plugin_configs,
)
from gyrolab.errors import ConfigError, GyrolabError, choices
from gyrolab.engine.progress import allow_bars, on_terminal
from gyrolab.engine.scene import Scene
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import job_identity
from gyrolab.sweep.job import run_sweep_job

if TYPE_CHECKING:
    from gyrolab.sweep.aggregate import SweepSummary

log = logging.getLogger("gyrolab")


def fail(error: GyrolabError) -> None:
    print(f"gyrolab: error: {error}", file=sys.stderr)
    sys.exit(error.exit_code)


def preflight(argv: Sequence[str]) -> None:
    """Validate the command line before Hydra creates any output directory."""
    args, _ = get_args_parser().parse_known_args(list(argv))
    if args.help or args.hydra_help or args.info or args.shell_completion or args.cfg:
        return  # Hydra's own informational commands
    parser = OverridesParser.create()
    overrides = []
    for text in args.overrides:
        try:
            overrides.extend(parser.parse_overrides([text]))
        except OverrideParseException as error:
            reason = str(error).strip().splitlines()[0].split(" See https://")[0]
            raise ConfigError(f"malformed override {text!r}: {reason}") from None
    sweeping = args.multirun or any(o.is_sweep_override() for o in overrides)
    check_launcher_installed(overrides)
    check_plugin_names(overrides)
    if sweeping:
        Grid.from_overrides(args.overrides)  # discrete sweeps, each value once
    # One job composed and validated: the first value of every sweep.
    first = [f"{o.get_key_element()}={next(iter(o.sweep_string_iterator()))}" if o.is_sweep_override()
             else o.input_line for o in overrides]
    cfg = compose_config(first, return_hydra_config=True)
    scene_cfg = _without_hydra(cfg)
    if task_of(scene_cfg) == "regime":  # the regime's domain is checked before anything is written
        from gyrolab.experiments.regime_run import prepare

        prepare(scene_cfg)
    else:
        Scene.from_config(scene_cfg)
    run_dir = cfg.hydra.sweep.dir if sweeping else cfg.hydra.run.dir
    check_writable(Path(str(run_dir)))


def check_plugin_names(overrides: Sequence[Override]) -> None:
    """Every option named for a config group (swept or not, in lists too) must exist."""
    selected = [o for o in overrides if o.key_or_group in SELECTABLE_GROUPS and o.package is None
                and not o.is_delete()]
    if not selected:
        return
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        for o in selected:
            valid = group_options(o.key_or_group)
            values = list(o.sweep_string_iterator()) if o.is_sweep_override() else [o.value()]
            for value in values:
                items = value if isinstance(value, list) else str(value).strip("[]").split(",")
                for name in (str(item).strip() for item in items):
                    if name and name != "null" and name not in valid:
                        raise ConfigError(f"unknown {o.key_or_group} {name!r}; valid choices: {choices(valid)}")


#: launcher option -> the module that provides it (installed by the ``cluster`` extra)
EXTRA_LAUNCHERS = {
    "joblib": "hydra_plugins.hydra_joblib_launcher",
    "submitit_local": "hydra_plugins.hydra_submitit_launcher",
    "submitit_slurm": "hydra_plugins.hydra_submitit_launcher",
    "slurm": "hydra_plugins.hydra_submitit_launcher",
}


def check_launcher_installed(overrides: Sequence[Override]) -> None:
    """A launcher of the ``cluster`` extra, chosen without the extra installed, is one sentence."""
    from importlib.util import find_spec

    for o in overrides:
        if o.key_or_group != "hydra/launcher" or o.is_delete():
            continue
        name = str(o.value())
        module = EXTRA_LAUNCHERS.get(name)
        if module is not None and find_spec(module) is None:
            raise ConfigError(f"hydra/launcher={name} needs the sweep launchers, which are not installed; "
                              'install them with: pip install "gyrolab[cluster]"')


def _without_hydra(cfg: DictConfig) -> DictConfig:
    cfg = cfg.copy()
    with open_dict(cfg):
        cfg.pop("hydra", None)
    return cfg


def check_writable(directory: Path) -> None:
    """ConfigError unless ``directory`` exists or can be created, and accepts new files."""
    existing = directory
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    try:
        if not existing.is_dir():
            raise NotADirectoryError(20, "a path component is a file, not a directory")
        probe = tempfile.mkdtemp(prefix=".gyrolab-write-check-", dir=existing)
        Path(probe).rmdir()
    except OSError as error:
        raise ConfigError(f"output directory {str(directory)!r} is not writable ({error.strerror or error}); "
                          "choose a writable hydra.run.dir (or hydra.sweep.dir)") from None


@hydra.main(config_path="pkg://gyrolab.conf", config_name="config", version_base="1.3")
def _task(cfg: DictConfig) -> None:
    hydra_cfg = HydraConfig.get()
    out_dir = Path(hydra_cfg.runtime.output_dir)
    if hydra_cfg.mode == RunMode.MULTIRUN:
        allow_bars(False)  # the sweep shows one bar for all its jobs
        _quiet_console()
        run_sweep_job(cfg, out_dir, list(hydra_cfg.overrides.task), hydra_cfg.job.num,
                      lambda job_id: _run_one(cfg, out_dir, job_id))
        return
    try:
        _run_one(cfg, out_dir)
    except GyrolabError as error:
        fail(error)


def _run_one(cfg: DictConfig, out_dir: Path, job_id: str | None = None) -> Path:
    """Run the scene, write ``run.nc`` (and figures) in ``out_dir``; GyrolabError on bad input or a failed run."""
    from gyrolab.output.dataset import write_dataset

    task = task_of(cfg)
    if task != "scene":
        from gyrolab.experiments import run_task

        written = run_task(task, cfg, out_dir)
        for path in written:
            log.info("wrote %s", path)
        return written[0]
    scene = Scene.from_config(cfg)
    ds = scene.run()
    ds.attrs["hydra_overrides"] = " ".join(HydraConfig.get().overrides.task)
    ds.attrs["job_id"] = job_identity(cfg) if job_id is None else job_id
    path = write_dataset(ds, out_dir / "run.nc")
    log.info("wrote %s", path)
    if cfg.output.get("figures", True):
        from gyrolab.output.figures import save_figures  # matplotlib only when figures are drawn

        for figure in save_figures(ds, out_dir / "figures"):
            log.info("wrote %s", figure)
    return path


def task_of(cfg: DictConfig) -> str:
    """What a run does: an experiment's task, a regime comparison when a regime is chosen, else the scene."""
    task = cfg.get("task") or "scene"
    return "regime" if task == "scene" and cfg.get("regime") else task


def _quiet_console() -> None:
    """On a terminal, a sweep job logs warnings only to the console (all of it goes to its log file)."""
    if not on_terminal(sys.stderr):
        return
    for handler in logging.getLogger().handlers:
        if isinstance(handler, logging.StreamHandler) and not isinstance(handler, logging.FileHandler):
            handler.setLevel(logging.WARNING)


def run_command(argv: Sequence[str]) -> int | None:
    """``--reproduce PATH``, ``--aggregate SWEEP_DIR``, ``--batch OVERRIDES``, ``--new-force NAME``: exit status, or
    None for a Hydra run."""
    if argv and argv[0] == "--batch":
        return _batch(argv[1:])
    if argv and argv[0].split("=", 1)[0] == "--new-force":
        from gyrolab.scaffold import new_force_package

        name = argv[0].partition("=")[2] or (argv[1] if len(argv) == 2 else "")
        if len(argv) > (1 if "=" in argv[0] else 2):
            raise ConfigError("--new-force takes one name; usage: gyrolab --new-force NAME")
        root = new_force_package(name)
        print(f"wrote {root}/: pip install -e {root} && python -m pytest {root}/tests")
        return 0
    if not argv or argv[0].split("=", 1)[0] not in ("--reproduce", "--aggregate"):
        return None
    option, _, value = argv[0].partition("=")
    rest = ([value] if value else []) + list(argv[1:])
    if len(rest) != 1:
        raise ConfigError(f"{option} takes exactly one path (got {len(rest)}: {' '.join(rest) or 'none'}); "
                          f"usage: gyrolab {option} {'PATH/run.nc' if option == '--reproduce' else 'SWEEP_DIR'}")
    logging.basicConfig(level=logging.INFO, format="[%(asctime)s][%(name)s][%(levelname)s] - %(message)s")
    if option == "--reproduce":
        from gyrolab.sweep.reproduce import report, reproduce

        comparison, stored = reproduce(Path(rest[0]))
        print("\n".join(report(Path(rest[0]), comparison, stored)))
        return 0 if comparison.identical else 1
    from gyrolab.sweep.aggregate import aggregate_sweep, log_summary

    summary = aggregate_sweep(Path(rest[0]))
    log_summary(summary)
    return _sweep_status(summary)


def _batch(overrides: Sequence[str]) -> int:
    """``gyrolab --batch KEY=V1,V2 ... [hydra.sweep.dir=DIR]``: the grid in one batch, one sweep.nc."""
    from datetime import datetime

    from gyrolab.sweep.batch import run_batch_sweep

    logging.basicConfig(level=logging.INFO, format="[%(asctime)s][%(name)s][%(levelname)s] - %(message)s")
    out_dir = Path(f"outputs/batch/{datetime.now():%Y-%m-%d}/{datetime.now():%H-%M-%S}")
    scene_overrides = []
    for override in overrides:
        if override.startswith("hydra.sweep.dir="):
            out_dir = Path(override.split("=", 1)[1])
        elif override.startswith("hydra."):
            raise ConfigError(f"{override!r}: a batch sweep runs in one process; of Hydra's settings it takes "
                              "hydra.sweep.dir only")
        else:
            scene_overrides.append(override)
    check_writable(out_dir)
    path = run_batch_sweep(scene_overrides, out_dir)
    log.info("wrote %s", path)
    return 0


def _sweep_status(summary: SweepSummary | None = None) -> int:
    """0 if every job of the last sweep finished, else 1 (with one line saying where the errors are)."""
    from gyrolab.sweep import callbacks

    if callbacks.last_error:
        print(f"gyrolab: error: {callbacks.last_error}", file=sys.stderr)
        return 1
    summary = summary or callbacks.last_summary
    if summary is None or not (summary.failed or summary.missing):
        return 0
    missing = f" and {summary.missing} did not run" if summary.missing else ""
    print(f"gyrolab: {summary.failed} of {summary.n_jobs} jobs failed{missing}; see failed_job_error and "
          f"job_status in {summary.path}", file=sys.stderr)
    return 1


def main() -> None:
    """Console entry point ``gyrolab`` (also ``python -m gyrolab``)."""
    argv = sys.argv[1:]
    if argv[:1] in (["--version"], ["-V"]):
        from gyrolab.output.provenance import gyrolab_version

        print(f"gyrolab {gyrolab_version()}")
        sys.exit(0)
    try:
        status = run_command(argv)
        if status is not None:
            sys.exit(status)
        register_plugin_configs()
        preflight(argv)
    except GyrolabError as error:
        fail(error)
    _task()
    status = _sweep_status()
    if status:
        sys.exit(status)
