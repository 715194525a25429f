"""The ``gyrolab`` command: a Hydra app that runs one scene (or a multirun sweep) per invocation.

Before Hydra starts, a preflight turns the usual mistakes — an unknown plugin
name, a malformed override, an invalid scene, an unwritable output
directory — into one sentence and a non-zero exit, so that no run directory
with a partial ``run.nc`` is left behind.

In a multirun each job is resumable and a failing job is recorded, not fatal
(``gyrolab.sweep.job``); the sweep callback then writes ``sweep.nc``.

This module is ``gyrolab run``, the default subcommand, and ``main``; the package holds the rest of the
command line: ``parser`` (which subcommand a command line names, one argparse parser per other
subcommand), ``commands`` (``batch``, ``plot``, ``reproduce``, ``aggregate``, ``new-force``, ``completion``)
and ``completion`` (the bash and zsh script). Logs go to stderr, results to stdout
(``gyrolab.output.written``).
"""

from __future__ import annotations

import atexit
import copy
import dataclasses
import difflib
import gc
import logging
import os
import signal
import sys
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.errors import OverrideParseException
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict

from gyrolab.engine.budget import check_budget, check_sweep_size, check_tolerances
from gyrolab.engine.composition import composing_once
from gyrolab.engine.hydra_private import get_args_parser
from gyrolab.engine.config import (
    SELECTABLE_GROUPS,
    ConfigSource,
    check_scene_config,
    compose_config,
    group_options,
    hydra_for,
    register_plugin_configs,
    use_source,
)
from gyrolab.engine.safety import check_config, check_output_dir
from gyrolab.engine.unread import ACCURACY, given_keys, ignored_accuracy, unread_accuracy
from gyrolab.engine.unread import refusal as unread_refusal
from gyrolab.errors import ConfigError, GyrolabError, GyrolabWarning, choices, require_finite, shorten
from gyrolab.figures.options import figure_options
from gyrolab.engine.progress import allow_bars, compile_notes_on_console, on_terminal
from gyrolab.output.dask_free_writes import install_dask_free_writes
from gyrolab.output.written import announce_written
from gyrolab.engine.scene import Scene
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import job_identity
from gyrolab.sweep.job import draws_job_figures, run_sweep_job

if TYPE_CHECKING:
    from gyrolab.sweep.aggregate import SweepSummary

log = logging.getLogger("gyrolab")


def fail(error: GyrolabError) -> None:
    print(f"gyrolab: error: {error}", file=sys.stderr)
    sys.exit(error.exit_code)


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


def preflight(argv: Sequence[str]) -> list[str]:
    """Validate the command line before Hydra creates any output directory; the command line Hydra should run.

    The config is composed exactly as Hydra will compose it (the same search path,
    primary config and overrides, from a user's ``--config-dir`` too; inside ``main``, Hydra's run is
    then served from this composition, ``gyrolab.engine.composition``), checked by
    ``gyrolab.engine.safety`` (no config can run code), against the schema (unknown
    keys, types), the budget, and the scene's own validation.
    """
    args, _ = get_args_parser().parse_known_args(list(argv))
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
        return list(argv)
    overrides = parse_overrides(args.overrides)
    rewritten = _plus_group_as_override(source, list(argv), overrides)
    if rewritten != list(argv):
        argv = rewritten
        args, _ = get_args_parser().parse_known_args(argv)
        overrides = parse_overrides(args.overrides)
    sweeps = [o for o in overrides if o.is_sweep_override()]
    if sweeps and not args.multirun:
        raise ConfigError(f"{shorten(sweeps[0].input_line)!r} is a sweep; run it with -m (gyrolab -m "
                          f"{shorten(sweeps[0].input_line)} ...), or give one value")
    sweeping = bool(args.multirun)
    check_launcher_installed(overrides)
    if sweeping:
        _refuse_swept_hydra_settings(overrides)
        check_sweep_size(overrides)  # before anything expands a range(0,1e12,1)
        Grid.from_overrides(args.overrides)  # discrete sweeps, each value once
    with hydra_for(source):
        # One job composed and validated: the first value of every sweep (each group choice checked for safety).
        first = _compose_job(source, _job_overrides(overrides, {}), sweeping)
    with hydra_for(dataclasses.replace(source, searchpath=tuple(first.hydra.searchpath or ()))):
        check_plugin_names(overrides)  # every value of every swept group
        configs = [first]
        swept = [*overrides, *(_sweeper_params(configs[0]) if sweeping else [])]
        for o in swept:
            if o.is_sweep_override() and _is_group(o, configs[0]):
                values = list(o.sweep_string_iterator())[(1 if o in overrides else 0):]  # the first: composed
                configs += [_compose_job(source, _job_overrides(swept, {id(o): value}), sweeping) for value in values]
    cfg = configs[0]
    for composed in configs:
        check_scene_config(_without_hydra(composed))
    refuse_unread_accuracy(configs, [o.input_line for o in overrides])
    run_text = _output_dir_text(cfg, "sweep" if sweeping else "run")
    check_output_dir(run_text, "hydra.sweep.dir" if sweeping else "hydra.run.dir")
    run_dir = Path(run_text)
    from gyrolab.output.trust import check_tree

    check_tree(run_dir, sweep=sweeping)  # a planted link in a directory received from someone else
    for composed in configs:
        check_config(composed, run_dir, command_line=args.overrides, job_subdir=sweeping)
    validate_scene(_without_hydra(cfg))
    from gyrolab.experiments import check_task, refuse_unread

    refuse_unread(f"task {task_of(cfg)}", [o.input_line for o in overrides], sweep=sweeping)  # batch.* on a plain run
    check_task(task_of(cfg), _without_hydra(cfg), run_dir)  # an experiment's own refusals, before its directory
    check_writable(run_dir)
    return argv


def refuse_unread_accuracy(configs: Sequence[DictConfig], overrides: Sequence[str]) -> None:
    """ConfigError when the command line gives ``accuracy`` and no job's integrator reads it
    (``gyrolab.engine.unread``). A sweep over integrators (``-m integrator=auto,taylor accuracy=1e-8``) gives the
    target to the jobs that read it; the others run at their own settings, warn and record it, as for a value
    from a config file."""
    if ACCURACY not in given_keys(overrides):
        return
    sentences = [unread_accuracy(composed) for composed in configs]
    if all(sentences):
        raise unread_refusal(configs[0], sentences[0])


def _output_dir_text(cfg: DictConfig, mode: str) -> str:
    """``hydra.run.dir`` (or ``hydra.sweep.dir``) resolved as Hydra will resolve it, or one sentence why not.

    ``${hydra:...}`` needs the Hydra config registered, as it is inside the run; a key that only
    exists once the job runs (``hydra.runtime.*``) cannot name the directory before it exists.
    """
    from omegaconf.errors import OmegaConfBaseException

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
    """``+experiment=mine`` as ``experiment=mine`` when the primary config already lists the group.

    Hydra refuses to add a group its defaults list has (``experiment: null`` in gyrolab's
    config.yaml); both spellings are common, so both select the option. The command line
    Hydra runs is rewritten the same way.
    """
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
#: sections every run needs, with a key to show in the message
from gyrolab.engine.schemas import REQUIRED_SECTIONS  # noqa: E402  (derived from the schemas)


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


def _refuse_swept_hydra_settings(overrides: Sequence[Override]) -> None:
    for o in overrides:
        if o.is_sweep_override() and (o.key_or_group.startswith(("hydra.", "hydra/"))):
            raise ConfigError(f"{shorten(o.input_line)!r} sweeps a Hydra setting; Hydra's settings are one per "
                              "sweep, so give a single value")


def validate_scene(scene_cfg: DictConfig) -> None:
    """The checks every run's scene config passes: schema, tolerances, budget, the scene's own validation."""
    from gyrolab.batch.scheduler import check_configured
    from gyrolab.experiments import TASKS

    plain = check_scene_config(scene_cfg)
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
        return  # an experiment validates the scenes it composes
    probe = scene_cfg.copy()
    with open_dict(probe):
        probe.time.n_output = 2  # the state's size, before allocating n_output samples
    check_budget(plain, Scene.from_config(probe).system.initial_state().size)
    if task_of(scene_cfg) == "regime":  # the regime's domain is checked before anything is written
        from gyrolab.experiments.regime_run import prepare

        prepare(scene_cfg, report=False)   # the run reports the domain warnings (once)
    else:
        Scene.from_config(scene_cfg)


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
    from importlib.util import find_spec

    for o in overrides:
        if o.key_or_group != "hydra/launcher" or o.is_delete():
            continue
        name = str(o.value())
        module = EXTRA_LAUNCHERS.get(name)
        if module is not None and not _importable(module, find_spec):
            raise ConfigError(f"hydra/launcher={name} needs the sweep launchers, which are not installed; "
                              'install them with: pip install "gyrolab[cluster]"')


def _importable(module: str, find_spec) -> bool:  # noqa: ANN001 - importlib.util.find_spec
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


@hydra.main(config_path="pkg://gyrolab.conf", config_name="config", version_base="1.3")
def _task(cfg: DictConfig) -> None:
    hydra_cfg = HydraConfig.get()
    out_dir = Path(hydra_cfg.runtime.output_dir)
    if hydra_cfg.mode == RunMode.MULTIRUN:
        allow_bars(False)  # the sweep shows one bar for all its jobs
        _quiet_console()
        job_figures = draws_job_figures(cfg.output)
        run_sweep_job(cfg, out_dir, list(hydra_cfg.overrides.task), hydra_cfg.job.num,
                      lambda job_id: _run_one(cfg, out_dir, job_id, figures=job_figures))
        return
    try:
        _run_one(cfg, out_dir)
    except GyrolabError as error:
        fail(error)


def _run_one(cfg: DictConfig, out_dir: Path, job_id: str | None = None, figures: bool = True) -> Path:
    """Run the scene, write ``run.nc`` (and figures) in ``out_dir``; GyrolabError on bad input or a failed run.

    ``figures=False`` (a multirun's jobs unless ``output.job_figures``): the scene's figures are not drawn.

    ``out_dir`` is locked meanwhile (a second run into it is refused in one sentence) and cleared of
    the temporary files that killed writes left there (``gyrolab.output.lock.writing_in``).
    """
    from gyrolab.output.lock import writing_in

    with writing_in(out_dir):
        return _run_locked(cfg, out_dir, job_id, figures)


def _run_locked(cfg: DictConfig, out_dir: Path, job_id: str | None, figures: bool) -> Path:
    from gyrolab.output.dataset import write_dataset

    task = task_of(cfg)
    # an accuracy the integrator does not read (the preflight refused one the command line gave to every job): said,
    # and recorded in run.nc; for the tasks that run the scene's integrator
    ignored = (ignored_accuracy(cfg, HydraConfig.get().overrides.task) if task in ("scene", "regime") else None)
    if ignored:
        log.warning("%s", ignored)
    if task != "scene":
        from gyrolab.experiments import run_task

        written = run_task(task, cfg, out_dir)
        for path in written:
            announce_written(path)
        return written[0]
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
    """The subcommand ``argv`` names (``batch``, ``plot``, ``reproduce``, ``aggregate``, ``new-force``,
    ``completion``, or an old spelling ``--batch``, ...; options in any position): its exit status, or None for
    ``run`` (Hydra's app, the default)."""
    from gyrolab.app.parser import split_command

    command, rest = split_command(argv)
    return None if command == "run" else run_subcommand(command, rest)


def run_subcommand(command: str, argv: Sequence[str]) -> int:
    """Parse ``argv`` with ``command``'s parser (``gyrolab.app.parser``) and run it (``gyrolab.app.commands``)."""
    from gyrolab.app.commands import RUNNERS
    from gyrolab.app.parser import parse

    args = parse(command, argv)
    if hasattr(args, "config_dir"):
        use_source(ConfigSource.from_args(args.config_path, args.config_name, args.config_dir))
    return RUNNERS[command](args)


#: Hydra's options that choose where configs come from, long and short
SOURCE_OPTIONS = {"--config-dir": "config_dir", "-cd": "config_dir", "--config-path": "config_path",
                  "-cp": "config_path", "--config-name": "config_name", "-cn": "config_name"}


def split_source_options(argv: Sequence[str]) -> tuple[ConfigSource, list[str]]:
    """(the config source named by leading ``--config-dir``/``--config-path``/``--config-name``, the rest)."""
    given: dict[str, str] = {}
    rest = list(argv)
    while rest and rest[0].split("=", 1)[0] in SOURCE_OPTIONS:
        option, has_value, value = rest.pop(0).partition("=")
        if not has_value:
            if not rest:
                raise ConfigError(f"{option} needs a value, e.g. {option} myconf")
            value = rest.pop(0)
        given[SOURCE_OPTIONS[option]] = value
    source = ConfigSource.from_args(given.get("config_path"), given.get("config_name"), given.get("config_dir"))
    return source, rest


def absolute_config_path(argv: Sequence[str]) -> list[str]:
    """``argv`` with a relative ``--config-path`` made absolute from the working directory.

    Hydra reads a relative --config-path against the folder of the app's source file,
    which is inside the installed package; a user means the working directory.
    """
    out = list(argv)
    for i, arg in enumerate(out):
        option, has_value, value = arg.partition("=")
        if option in ("--config-path", "-cp"):
            if has_value and value and not value.startswith("pkg://"):
                out[i] = f"{option}={os.path.abspath(value)}"
            elif not has_value and i + 1 < len(out) and not out[i + 1].startswith("pkg://"):
                out[i + 1] = os.path.abspath(out[i + 1])
    return out


def _plot(argv: Sequence[str]) -> int:
    """``--plot PATH ...`` (kept for callers of the old function): ``gyrolab plot``."""
    return run_subcommand("plot", [a for a in (argv[0].partition("=")[2], *argv[1:]) if a])


def _batch(overrides: Sequence[str]) -> int:
    """``--batch OVERRIDES`` (kept for callers of the old function): ``gyrolab batch``."""
    return run_subcommand("batch", list(overrides))


def _sweep_status(summary: SweepSummary | None = None) -> int:
    """0 if every job of the last sweep finished, else 1 (with one line saying where the errors are)."""
    from gyrolab.sweep import callbacks

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


def shell_completion(argv: Sequence[str]) -> int:
    """Hydra's ``--shell-completion install=bash`` (or ``zsh``, ``uninstall=...``): gyrolab's own completion
    script (``gyrolab.app.completion``), which knows the subcommands; Hydra's cannot see an installed app."""
    from gyrolab.app.completion import SHELLS, script

    args, _ = get_args_parser().parse_known_args(list(argv))
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
    # The interpreter's last garbage collection walks every object numba, scipy, xarray and Hydra created:
    # ~1 s of every command's wall time (0.1 s after a freeze, measured). Files are closed explicitly, so
    # nothing needs that collection's finalisers.
    atexit.register(gc.freeze)
    show_warnings_in_one_line()
    quiet_logging_failures()
    install_dask_free_writes()  # run.nc and sweep.nc hold numpy arrays: writing them need not import Dask
    _main_process.append(os.getpid())
    previous = signal.signal(signal.SIGTERM, _terminated)
    try:
        with composing_once():  # the preflight's composition is the one Hydra runs (and a sweep's jobs start from)
            _main(absolute_config_path(sys.argv[1:]))
    except KeyboardInterrupt as interruption:  # Ctrl-C or SIGTERM: every write is whole or absent, locks released
        from gyrolab.output.lock import release_all

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
        from gyrolab.output.atomic import reason

        why = reason(error) if isinstance(error, OSError) else type(error).__name__
        where = getattr(self, "baseFilename", None) or "stream"
        try:
            print(f"gyrolab: warning: cannot write the log {where} ({why}); its further lines are dropped",
                  file=sys.stderr)
        except Exception:  # noqa: BLE001 - stderr itself may be the full device
            pass

    handle_error.gyrolab_quiet = True  # type: ignore[attr-defined]
    logging.Handler.handleError = handle_error  # type: ignore[method-assign]


def _main(argv: list[str]) -> None:
    try:
        from gyrolab.app.parser import split_command

        command, argv = split_command(argv)
        if command == "run":  # --scheduler ADDRESS: the only config-free way to Dask, for experiments run by Hydra too
            from gyrolab.batch.scheduler import take_scheduler_option

            argv = take_scheduler_option(argv)
        sys.argv[1:] = argv
        if command == "run" and ("--version" in argv or "-V" in argv):
            from gyrolab.output.provenance import gyrolab_version

            print(f"gyrolab {gyrolab_version()}")
            sys.exit(0)
        if command != "run":
            sys.exit(run_subcommand(command, argv))
        if "--shell-completion" in argv or "-sc" in argv:
            sys.exit(shell_completion(argv))
        from gyrolab.output.trust import check_kernel_cache

        check_kernel_cache()  # before the preflight, which may load a compiled kernel
        register_plugin_configs()
        from gyrolab.sweep.sweeper import register_plugin

        register_plugin()  # gyrolab's own sweeper (conf/hydra/sweeper/gyrolab.yaml), before Hydra instantiates it
        with compile_notes_on_console():  # the preflight may compile a force plugin's torque
            sys.argv[1:] = preflight(argv)
    except GyrolabError as error:
        fail(error)
    from gyrolab.sweep import callbacks

    # each command starts clean (tests and notebooks run several in one process): no outcome of an earlier
    # sweep (a sweep without gyrolab's callback, from a user's primary config, would not clear it) and bars
    # allowed again (a multirun job turns them off)
    callbacks.reset()
    allow_bars(True)
    from gyrolab.output.lock import release_all

    try:
        _task()
    finally:
        release_all()  # a failed run's lock too (Hydra skips the callback's on_run_end when the job exits)
    status = _sweep_status()
    if status:
        sys.exit(status)
