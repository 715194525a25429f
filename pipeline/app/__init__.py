"""The ``gyrolab`` command: a Hydra app that runs one scene (or a multirun sweep) per invocation.

Before Hydra starts, a preflight turns the usual mistakes (an unknown plugin name, a malformed override, an
invalid scene, an unwritable output directory) into one sentence and a non-zero exit, so that no run directory
with a partial ``run.nc`` is left behind. In a multirun each job is resumable and a failing job is recorded, not
fatal (``gyrolab.sweep.job``); the sweep callback then writes ``sweep.nc``.

This module is ``gyrolab run``, the default subcommand, and ``main``; ``parser`` says which subcommand a command
line names, ``commands`` runs the others, ``completion`` writes the shell script. Logs go to stderr, results to
stdout (``gyrolab.output.written``).
"""

from __future__ import annotations

import argparse
import atexit
import contextlib
import copy
import dataclasses
import difflib
import gc
import logging
import os
import shutil
import signal
import sys
import tempfile
import warnings
from collections.abc import Sequence
from importlib.util import find_spec
from pathlib import Path
from typing import TYPE_CHECKING

from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.errors import OverrideParseException
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict
from omegaconf.errors import OmegaConfBaseException

from gyrolab.app.completion import SHELLS, script
from gyrolab.app.parser import parse_command_line, run_parser
from gyrolab.batch.scheduler import check_configured, use_command_line_scheduler
from gyrolab.compat import composing_once, install_dask_free_writes, run_hydra
from gyrolab.engine.budget import check_budget, check_sweep_size, check_tolerances
from gyrolab.engine.config import (SELECTABLE_GROUPS, ConfigSource, check_scene_config, compose_config, group_options,
                                   hydra_for, register_plugin_configs, use_source)
from gyrolab.engine.progress import allow_bars, compile_notes_on_console, on_terminal
from gyrolab.engine.safety import check_config, check_output_dir
from gyrolab.engine.schemas import REQUIRED_SECTIONS  # sections every run needs, with a key to show
from gyrolab.engine.scene import Scene
from gyrolab.engine.unread import ACCURACY, given_overrides, ignored_accuracy, unread_accuracy
from gyrolab.engine.unread import refusal as unread_refusal
from gyrolab.errors import ConfigError, GyrolabError, GyrolabWarning, choices, require_finite, shorten
from gyrolab.experiments import TASKS, check_task, refuse_unread, run_task, task_of
from gyrolab.figures.options import figure_options
from gyrolab.output.atomic import reason
from gyrolab.output.dataset import write_dataset
from gyrolab.output.lock import LOCK_NAME, release_all, writing_in
from gyrolab.output.provenance import gyrolab_version
from gyrolab.output.trust import check_kernel_cache, check_tree
from gyrolab.output.written import announce_written, fail
from gyrolab.sweep import callbacks
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import job_identity
from gyrolab.sweep.job import run_sweep_job
from gyrolab.sweep.sweeper import register_plugin

if TYPE_CHECKING:
    from gyrolab.sweep.aggregate import SweepSummary

log = logging.getLogger("gyrolab")


def show_warnings_in_one_line() -> None:
    """Print gyrolab's own warnings (``GyrolabWarning``: a plugin that cannot be used, ...) as one line,
    ``gyrolab: warning: <message>``, not Python's two (file, line and source); others as Python does."""
    shown = warnings.showwarning
    if getattr(shown, "gyrolab_one_line", False):
        return

    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001 - warnings' signature
        if issubclass(category, GyrolabWarning):
            print(f"gyrolab: warning: {message}", file=sys.stderr if file is None else file)
        else:
            shown(message, category, filename, lineno, file, line)

    show.gyrolab_one_line = True
    warnings.showwarning = show


def preflight(args: argparse.Namespace) -> argparse.Namespace:
    """Validate the command line (``args``: ``gyrolab run``'s options) before Hydra creates any output directory;
    the options Hydra should run (``+group=x`` may become ``group=x``). The config is composed as Hydra will (whose
    run is then served from it: ``composing_once``) and checked (``engine.safety``, the schema, the budget, the
    scene's own validation); a plain run integrates the scene built here (``take_prepared``)."""
    if args.experimental_rerun is not None:  # Hydra unpickles the file: whoever wrote it runs code as you
        raise ConfigError(f"--experimental-rerun {shorten(args.experimental_rerun)} would load a pickle, which runs "
                          "whatever code its writer put there; rerun a dataset with gyrolab reproduce PATH/run.nc")
    source = ConfigSource.from_args(args.config_path, args.config_name, args.config_dir)
    use_source(source)
    if args.help or args.hydra_help or args.info or args.shell_completion or args.cfg:
        # Hydra's own informational commands: --help and --hydra-help configure logging from the config
        with hydra_for(source):
            cfg = _compose_job(source, list(args.overrides), False)
        check_config(cfg, Path(str(cfg.hydra.run.dir)), command_line=args.overrides)
        return args
    args, overrides = _checked_overrides(source, args)
    sweeping = bool(args.multirun)
    configs = _compose_jobs(source, overrides, sweeping)
    cfg = configs[0]
    scene_cfgs = [_without_hydra(composed) for composed in configs]
    plains = [check_scene_config(scene_cfg) for scene_cfg in scene_cfgs]
    given = [o.input_line for o in overrides]
    # each job's note on an accuracy its integrator does not read; refused when the command line gives it and no
    # job reads it (a sweep over integrators gives the target to the jobs that read it, the others warn and record it)
    notes = [ignored_accuracy(composed, given) for composed in configs]
    if ACCURACY in given_overrides(given) and all(notes):
        raise unread_refusal(configs[0], unread_accuracy(configs[0]))
    run_text = _output_dir_text(cfg, "sweep" if sweeping else "run")
    check_output_dir(run_text, "hydra.sweep.dir" if sweeping else "hydra.run.dir")
    run_dir = Path(run_text)
    check_tree(run_dir, sweep=sweeping)  # a planted link in a directory received from someone else
    for composed in configs:
        check_config(composed, run_dir, command_line=args.overrides, job_subdir=sweeping)
    scene = validate_scene(scene_cfgs[0], plains[0])
    refuse_unread(f"task {task_of(cfg)}", given, sweep=sweeping)  # batch.* on a plain run
    check_task(task_of(cfg), scene_cfgs[0], run_dir)  # an experiment's own refusals, before its directory
    check_writable(run_dir)
    if not sweeping:  # the run takes the preflight's scene and its accuracy note (_run_one)
        _prepared[:] = [Prepared(OmegaConf.to_container(scene_cfgs[0], resolve=False), scene, notes[0])]
    return args


def _checked_overrides(source: ConfigSource, args: argparse.Namespace) -> tuple[argparse.Namespace, list[Override]]:
    """(``args`` with ``+group=x`` as ``group=x`` where the group is listed, its overrides parsed), or one sentence:
    a malformed override, a sweep without -m, a launcher not installed, a sweep Hydra cannot run."""
    overrides = parse_overrides(args.overrides)
    rewritten = _plus_group_as_override(source, list(args.overrides), overrides)
    if rewritten != list(args.overrides):
        args = argparse.Namespace(**{**vars(args), "overrides": rewritten})
        overrides = parse_overrides(args.overrides)
    sweeps = [o for o in overrides if o.is_sweep_override()]
    if sweeps and not args.multirun:
        raise ConfigError(f"{shorten(sweeps[0].input_line)!r} is a sweep; run it with -m (gyrolab -m "
                          f"{shorten(sweeps[0].input_line)} ...), or give one value")
    check_launcher_installed(overrides)
    if args.multirun:
        for o in sweeps:
            if o.key_or_group.startswith(("hydra.", "hydra/")):
                raise ConfigError(f"{shorten(o.input_line)!r} sweeps a Hydra setting; Hydra's settings are one per "
                                  "sweep, so give a single value")
        check_sweep_size(overrides)  # before anything expands a range(0,1e12,1)
        Grid.from_overrides(args.overrides)  # discrete sweeps, each value once
    return args, overrides


def _compose_jobs(source: ConfigSource, overrides: list[Override], sweeping: bool) -> list[DictConfig]:
    """The configs to validate: the first job (the first value of every sweep), then one per other value of each
    swept config group (from the command line or the config's ``hydra.sweeper.params``), each option composed."""
    with hydra_for(source):
        first = _compose_job(source, _job_overrides(overrides, {}), sweeping)
    with hydra_for(dataclasses.replace(source, searchpath=tuple(first.hydra.searchpath or ()))):
        check_plugin_names(overrides)  # every value of every swept group
        configs = [first]
        swept = [*overrides, *(_sweeper_params(first) if sweeping else [])]
        for o in swept:
            if o.is_sweep_override() and _is_group(o, first):
                values = list(o.sweep_string_iterator())[(1 if o in overrides else 0):]  # the first: composed
                configs += [_compose_job(source, _job_overrides(swept, {id(o): value}), sweeping) for value in values]
    return configs


@dataclasses.dataclass
class Prepared:
    """What the preflight of a plain run built, for the run to use rather than build again."""

    #: the scene config it was built from, unresolved (the run's must be the same)
    config: dict
    #: the scene, built once (None: the task builds its own)
    scene: Scene | None
    #: why the config's ``accuracy`` goes unread (``gyrolab.engine.unread.ignored_accuracy``), or None
    accuracy_ignored: str | None


#: the preflight's work for the run of this command (at most one)
_prepared: list[Prepared] = []


def take_prepared(cfg: DictConfig) -> Prepared | None:
    """The preflight's work, if it was done for ``cfg``: the same config, with no resolver whose value could
    differ between the preflight and the run (``${now:...}``, ``${oc.env:...}``, ``${hydra:...}``)."""
    prepared = _prepared.pop() if _prepared else None
    if prepared is None or "${" in repr(prepared.config):
        return None
    return prepared if OmegaConf.to_container(cfg, resolve=False) == prepared.config else None


def _output_dir_text(cfg: DictConfig, mode: str) -> str:
    """``hydra.run.dir`` (or ``hydra.sweep.dir``) resolved as Hydra will resolve it (``${hydra:...}`` needs the Hydra
    config registered), or one sentence why not (``hydra.runtime.*`` exists only once the job runs)."""
    key = f"hydra.{mode}.dir"
    try:
        HydraConfig.instance().set_config(copy.deepcopy(cfg))  # set_config marks its argument read-only
        return str(OmegaConf.select(cfg, key, throw_on_missing=True))
    except (OmegaConfBaseException, ValueError, TypeError) as error:
        raw = OmegaConf.to_container(cfg.hydra[mode], resolve=False).get("dir")
        reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise ConfigError(f"{key}={raw!r} cannot be resolved before the run starts ({reason}); give a path, "
                          "optionally with ${now:...} or ${hydra:job.name}") from None


def _plus_group_as_override(source: ConfigSource, argv: list[str], overrides: Sequence[Override]) -> list[str]:
    """The overrides ``argv`` with ``+experiment=mine`` as ``experiment=mine`` when the primary config already lists
    the group: Hydra refuses to add a group its defaults list has; both spellings are common."""
    adds = [o for o in overrides if o.is_add() and o.key_or_group in SELECTABLE_GROUPS and o.package is None]
    if not adds:
        return argv
    with hydra_for(source):
        listed = compose_config([], return_hydra_config=True, config_name=source.config_name).hydra.runtime.choices
    for o in adds:
        if o.key_or_group in listed and o.input_line in argv:
            argv[argv.index(o.input_line)] = o.input_line[1:]
    return argv


def parse_overrides(texts: Sequence[str]) -> list[Override]:
    """Hydra's override grammar, with one sentence showing the override and the valid forms."""
    parser = OverridesParser.create()
    overrides = []
    for text in texts:
        if len(text) > MAX_OVERRIDE_CHARS:
            raise ConfigError(f"override {shorten(text)} is longer than {MAX_OVERRIDE_CHARS} characters; "
                              "keys are short dotted names such as time.end")
        try:
            overrides.extend(parser.parse_overrides([text]))
        except OverrideParseException as error:
            reason = str(error).strip().splitlines()[0].split(" See https://")[0]
            raise ConfigError(f"malformed override {shorten(text)!r} ({shorten(reason, 120)}); valid forms are "
                              f"{OVERRIDE_FORMS}") from None
    for o in overrides:
        key = o.key_or_group
        if len(key) > MAX_KEY_CHARS:
            raise ConfigError(f"override key {shorten(key)!r} is longer than {MAX_KEY_CHARS} characters; keys are "
                              "short dotted names such as time.end")
        if not key.strip():
            raise ConfigError(f"override {shorten(o.input_line)!r} has no key; valid forms are {OVERRIDE_FORMS}")
        if o.is_delete() and key in REQUIRED_SECTIONS:
            raise ConfigError(f"{o.input_line!r} deletes the section {key}, which every run needs; set its keys "
                              f"instead (e.g. {key}.{REQUIRED_SECTIONS[key]}=...)")
    return overrides


#: what a valid override looks like (for the grammar errors)
OVERRIDE_FORMS = "key=value (time.end=50), group=option (integrator=rk4), +key=value (add), ~key (delete)"
MAX_OVERRIDE_CHARS = 10_000
MAX_KEY_CHARS = 200


def _job_overrides(overrides: Sequence[Override], chosen: dict[int, str]) -> list[str]:
    """The overrides of one job: a sweep's first value, or the value chosen for it."""
    return [f"{o.get_key_element()}={chosen.get(id(o), next(iter(o.sweep_string_iterator())))}"
            if o.is_sweep_override() else o.input_line for o in overrides]


def _sweeper_params(cfg: DictConfig) -> list[Override]:
    """The sweep a config file declares in ``hydra.sweeper.params`` (Hydra adds it to the command line's)."""
    params = OmegaConf.to_container(cfg.hydra.sweeper, resolve=False).get("params") or {}
    overrides = parse_overrides([f"{key}={value}" for key, value in params.items()])
    for o in overrides:
        if o.key_or_group.startswith(("hydra.", "hydra/")):
            raise ConfigError(f"hydra.sweeper.params.{shorten(o.key_or_group)} sweeps a Hydra setting; Hydra's "
                              "settings are one per sweep, so a config may not sweep them")
    return overrides


def _is_group(o: Override, cfg: DictConfig) -> bool:
    return o.key_or_group in (cfg.hydra.runtime.choices or {}) or o.key_or_group.startswith("hydra/")


def _compose_job(source: ConfigSource, overrides: list[str], sweeping: bool) -> DictConfig:
    return compose_config(overrides, return_hydra_config=True, from_shell=True, config_name=source.config_name,
                          run_mode=RunMode.MULTIRUN if sweeping else RunMode.RUN, refuse_unread=False)


def validate_scene(scene_cfg: DictConfig, plain: dict) -> Scene | None:
    """The checks every run's scene config passes beyond its schema (``plain``: ``check_scene_config``'s answer):
    tolerances, budget, the scene's own validation; the scene, built once, for a task that runs it."""
    require_finite(plain, "")
    figure_options(plain.get("output"))  # figure formats and dpi, before anything runs
    check_tolerances(plain)
    check_configured((plain.get("batch") or {}).get("scheduler"))  # an address in a config: refused before any directory
    task = task_of(scene_cfg)
    if task not in ("scene", *TASKS):
        close = difflib.get_close_matches(task, ["scene", *TASKS], n=1)
        hint = f"did you mean task={close[0]}? " if close else ""
        raise ConfigError(f"unknown task {shorten(repr(task))}; {hint}valid choices: {choices(['scene', *TASKS])}")
    if task not in ("scene", "regime"):
        return None  # an experiment validates the scenes it composes
    if task == "regime":  # the regime's domain is checked before anything is written
        from gyrolab.experiments.regime_run import prepare  # start-up: a regime run's only (numba)

        probe = scene_cfg.copy()
        with open_dict(probe):
            probe.time.n_output = 2  # the state's size, before allocating n_output samples
        check_budget(plain, Scene.from_config(probe).system.initial_state().size)
        prepare(scene_cfg, report=False)   # the run reports the domain warnings (once)
        return None
    # the budget as soon as the state's size is known, before n_output samples are allocated
    return Scene.from_config(scene_cfg, check=lambda system: check_budget(plain, system.initial_state().size))


def check_plugin_names(overrides: Sequence[Override]) -> None:
    """Every option named for a config group (swept or not, in lists too) must exist (needs a Hydra)."""
    selected = [o for o in overrides if o.key_or_group in SELECTABLE_GROUPS and o.package is None
                and not o.is_delete()]
    for o in selected:
        valid = group_options(o.key_or_group)
        values = list(o.sweep_string_iterator()) if o.is_sweep_override() else [o.value()]
        for value in values:
            items = value if isinstance(value, list) else str(value).strip("[]").split(",")
            for name in (str(item).strip() for item in items):
                if name and name != "null" and name not in valid:
                    close = difflib.get_close_matches(name, valid, n=1)
                    hint = f"did you mean {o.key_or_group}={close[0]}? " if close else ""
                    raise ConfigError(f"unknown {o.key_or_group} {shorten(repr(name))}; {hint}valid choices: "
                                      f"{choices(valid)}")


#: launcher option -> the module that provides it (installed by the ``cluster`` extra)
EXTRA_LAUNCHERS = {
    "joblib": "hydra_plugins.hydra_joblib_launcher",
    "submitit_local": "hydra_plugins.hydra_submitit_launcher",
    "submitit_slurm": "hydra_plugins.hydra_submitit_launcher",
    "slurm": "hydra_plugins.hydra_submitit_launcher",
}


def check_launcher_installed(overrides: Sequence[Override]) -> None:
    """A launcher of the ``cluster`` extra, chosen without the extra installed, is one sentence."""
    for o in overrides:
        chosen = o.key_or_group == "hydra/launcher" and not o.is_delete()
        module = EXTRA_LAUNCHERS.get(str(o.value())) if chosen else None
        if module is not None and not _importable(module):
            raise ConfigError(f"hydra/launcher={o.value()} needs the sweep launchers, which are not installed; "
                              'install them with: pip install "gyrolab[cluster]"')


def _importable(module: str) -> bool:
    """Whether ``module`` can be imported (find_spec raises, rather than says None, when a parent package is missing)."""
    try:
        return find_spec(module) is not None
    except (ImportError, ValueError):
        return False


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


def _task(cfg: DictConfig) -> None:
    """Hydra's task: one run, or one job of a multirun (``gyrolab.compat.run_hydra`` calls it as ``@hydra.main`` does)."""
    hydra_cfg = HydraConfig.get()
    out_dir = Path(hydra_cfg.runtime.output_dir)
    if hydra_cfg.mode == RunMode.MULTIRUN:
        allow_bars(False)  # the sweep shows one bar for all its jobs
        _quiet_console()
        # a job draws its figures only with output.job_figures=true: gyrolab plot SWEEP_DIR draws them from run.nc
        job_figures = bool(cfg.output.get("figures", True)) and bool(cfg.output.get("job_figures", False))
        run_sweep_job(cfg, out_dir, list(hydra_cfg.overrides.task), hydra_cfg.job.num,
                      lambda job_id: _run_one(cfg, out_dir, job_id, figures=job_figures))
        return
    fresh = _only_hydras_files(out_dir)  # Hydra made it for this run (else: a folder the user pointed at)
    try:
        _run_one(cfg, out_dir)
    except GyrolabError as error:
        if fresh and _only_hydras_files(out_dir):
            # a run refused once integrating (auto's pilot, a failed step) leaves no folder of a run that never was;
            # the sentence below says what its log would
            shutil.rmtree(out_dir, ignore_errors=True)
        fail(error)


def _only_hydras_files(out_dir: Path) -> bool:
    """Whether ``out_dir`` holds only what is there before the task starts: Hydra's configs, the job's log and the
    folder's lock (taken from the preflight on)."""
    return out_dir.is_dir() and {p.name for p in out_dir.iterdir()} <= {".hydra", "gyrolab.log", LOCK_NAME}


def _run_one(cfg: DictConfig, out_dir: Path, job_id: str | None = None, figures: bool = True) -> Path:
    """Run the scene, write ``run.nc`` (and, unless ``figures=False``, figures) in ``out_dir``, locked meanwhile and
    cleared of what killed writes left (``writing_in``); GyrolabError on bad input or a failed run."""
    with writing_in(out_dir):
        task = task_of(cfg)
        prepared = take_prepared(cfg) if job_id is None else None  # a plain run: the preflight's scene and note
        # an accuracy the integrator does not read (the preflight refused one the command line gave to every job):
        # said, and recorded in run.nc; for the tasks that run the scene's integrator
        ignored = None if task not in ("scene", "regime") else prepared.accuracy_ignored if prepared else \
            ignored_accuracy(cfg, HydraConfig.get().overrides.task)
        if ignored:
            log.warning("%s", ignored)
        if task != "scene":
            written = run_task(task, cfg, out_dir)
            for path in written:
                announce_written(path)
            return written[0]
        if prepared and prepared.scene:
            scene = prepared.scene
            scene.log_notes()  # into the run's log, as a scene built here says them
        else:
            scene = Scene.from_config(cfg)
        scene.accuracy_ignored = ignored  # in the dataset's attributes, as compose_scene records it
        ds = scene.run()
        ds.attrs["hydra_overrides"] = " ".join(HydraConfig.get().overrides.task)
        ds.attrs["job_id"] = job_identity(cfg) if job_id is None else job_id
        path = write_dataset(ds, out_dir / "run.nc")
        announce_written(path)
        if not figures:
            return path
        from gyrolab.figures.redraw import draw_figures  # matplotlib only when figures are drawn

        for figure in draw_figures("run.nc", ds, out_dir, cfg.output):
            announce_written(figure)
        return path


def _quiet_console() -> None:
    """On a terminal, a sweep job logs warnings only to the console (all of it goes to its log file)."""
    if not on_terminal(sys.stderr):
        return
    for handler in logging.getLogger().handlers:
        if isinstance(handler, logging.StreamHandler) and not isinstance(handler, logging.FileHandler):
            handler.setLevel(logging.WARNING)


def run_subcommand(command: str, args: argparse.Namespace) -> int:
    """Run ``command`` (not ``run``) with its parsed options (``gyrolab.app.commands``)."""
    from gyrolab.app.commands import RUNNERS  # import cycle: commands imports gyrolab.app

    if hasattr(args, "config_dir"):
        use_source(ConfigSource.from_args(args.config_path, args.config_name, args.config_dir))
    return RUNNERS[command](args)


def absolute_config_path(args: argparse.Namespace) -> argparse.Namespace:
    """``args`` with a relative ``--config-path`` made absolute from the working directory (Hydra reads it against
    the folder of the app's source file, inside the installed package; a user means the working directory)."""
    path = args.config_path
    if path and not path.startswith("pkg://"):
        args.config_path = os.path.abspath(path)
    return args


def _sweep_status(summary: SweepSummary | None = None) -> int:
    """0 if every job of the last sweep finished, else 1 (with one line saying where the errors are)."""
    if callbacks.last_error:
        print(f"gyrolab: error: {callbacks.last_error}", file=sys.stderr)
        return callbacks.last_exit_code
    summary = summary or callbacks.last_summary
    if summary is None or not (summary.failed or summary.missing):
        return 0
    missing = f" and {summary.missing} did not run" if summary.missing else ""
    if summary.write_failures:   # a full disk: exit 3 as for any failed write; the jobs run again on resume
        print(f"gyrolab: error: {summary.failed} of {summary.n_jobs} jobs failed{missing}, {summary.write_failures} "
              f"of them because their results could not be written (see failed_job_error in {summary.path}); "
              "rerun the same command once there is room", file=sys.stderr)
        return 3
    print(f"gyrolab: {summary.failed} of {summary.n_jobs} jobs failed{missing}; see failed_job_error and "
          f"job_status in {summary.path}", file=sys.stderr)
    return 1


def shell_completion(args: argparse.Namespace) -> int:
    """Hydra's ``--shell-completion install=bash`` (or ``zsh``, ``uninstall=...``): gyrolab's own completion
    script (``gyrolab.app.completion``), which knows the subcommands; Hydra's cannot see an installed app."""
    args_list = list(args.overrides)
    action, _, shell = (args_list[0] if len(args_list) == 1 else "").partition("=")
    if action not in ("install", "uninstall") or shell not in SHELLS:
        raise ConfigError(f"--shell-completion takes install=SHELL or uninstall=SHELL with SHELL one of "
                          f"{', '.join(SHELLS)} (got {shorten(' '.join(args_list)) or 'nothing'}); "
                          f'e.g. eval "$(gyrolab --shell-completion install=bash)", the same as gyrolab completion bash')
    print(script(shell) if action == "install" else "complete -r gyrolab")
    return 0


def main() -> None:
    """Console entry point ``gyrolab`` (also ``python -m gyrolab``): the subcommand named on the command line
    (``gyrolab.app.parser``), by default ``run``, Hydra's app (preflight, then ``_task``)."""
    # the interpreter's last garbage collection walks every object numba, scipy, xarray and Hydra created (files are
    # closed explicitly, so none of its finalisers is needed), and what the imports built lives until exit: frozen,
    # neither is walked again (docs/batch.md, "Scaling")
    atexit.register(gc.freeze)
    gc.freeze()
    show_warnings_in_one_line()
    quiet_logging_failures()
    install_dask_free_writes()  # run.nc and sweep.nc hold numpy arrays: writing them need not import Dask
    _main_process.append(os.getpid())
    previous = signal.signal(signal.SIGTERM, _terminated)
    try:
        with composing_once():  # the preflight's composition is the one Hydra runs (and a sweep's jobs start from)
            _main(sys.argv[1:])
    except KeyboardInterrupt as interruption:  # Ctrl-C or SIGTERM: every write is whole or absent, locks released
        release_all()
        print("gyrolab: interrupted; the same command resumes", file=sys.stderr)
        sys.exit(getattr(interruption, "exit_code", 130))
    finally:
        signal.signal(signal.SIGTERM, previous)
        _main_process.pop()


class Terminated(KeyboardInterrupt):
    """SIGTERM, handled as Ctrl-C is (exit 143: 128 + SIGTERM)."""

    exit_code = 128 + signal.SIGTERM


#: the process that runs ``main`` (a forked worker, e.g. of a figure pool, inherits the handler, not the role)
_main_process: list[int] = []


def _terminated(signum: int, frame: object) -> None:
    if _main_process and os.getpid() != _main_process[-1]:  # a forked worker told to stop: stop as by default
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        return
    raise Terminated()


def quiet_logging_failures() -> None:
    """A log line that cannot be written (a full disk under ``gyrolab.log``) is said once, in one line, and that
    log's further failures are silent: not Python's "--- Logging error ---" and a traceback for every line."""
    if getattr(logging.Handler.handleError, "gyrolab_quiet", False):
        return

    def handle_error(self: logging.Handler, record: logging.LogRecord) -> None:
        if getattr(self, "_gyrolab_failed", False):
            return
        self._gyrolab_failed = True  # type: ignore[attr-defined]
        error = sys.exc_info()[1]
        why = reason(error) if isinstance(error, OSError) else type(error).__name__
        where = getattr(self, "baseFilename", None) or "stream"
        with contextlib.suppress(Exception):  # stderr itself may be the full device
            print(f"gyrolab: warning: cannot write the log {where} ({why}); its further lines are dropped",
                  file=sys.stderr)

    handle_error.gyrolab_quiet = True  # type: ignore[attr-defined]
    logging.Handler.handleError = handle_error  # type: ignore[method-assign]


def _main(argv: list[str]) -> None:
    _prepared.clear()  # nothing from an earlier command of this process
    try:
        command, args = parse_command_line(argv)
        if command != "run":
            sys.exit(run_subcommand(command, args))
        if args.version:
            print(f"gyrolab {gyrolab_version()}")
            sys.exit(0)
        # --scheduler ADDRESS: the only config-free way to Dask, for experiments run by Hydra too; None when not
        # given, so no value is left from an earlier command
        use_command_line_scheduler(args.scheduler)
        if args.shell_completion:
            sys.exit(shell_completion(args))
        args = absolute_config_path(args)
        check_kernel_cache()  # before the preflight, which may load a compiled kernel
        register_plugin_configs()
        register_plugin()  # gyrolab's own sweeper (conf/hydra/sweeper/gyrolab.yaml), before Hydra instantiates it
        with compile_notes_on_console():  # the preflight may compile a force plugin's torque
            args = preflight(args)
    except GyrolabError as error:
        fail(error)
    # each command starts clean (tests and notebooks run several in one process): no outcome of an earlier
    # sweep (a sweep without gyrolab's callback, from a user's primary config, would not clear it) and bars
    # allowed again (a multirun job turns them off)
    callbacks.reset()
    allow_bars(True)
    try:
        run_hydra(args, run_parser(), _task, config_path="pkg://gyrolab.conf", config_name="config")
    finally:
        release_all()  # a failed run's lock too (Hydra skips the callback's on_run_end when the job exits)
    status = _sweep_status()
    if status:
        sys.exit(status)
