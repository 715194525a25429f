"""No config and no dataset can run code: the one place where gyrolab decides what a config may name.

The threat model and the rules are in docs/safety.md, "Safety and failures"; :func:`check_config` is applied to
every composed config before Hydra creates a directory, instantiates a callback or configures logging.
"""

from __future__ import annotations

import os
import re
import site
import sysconfig
from collections.abc import Iterator, Sequence
from functools import cache
from importlib.resources import files
from pathlib import Path
from typing import Any

from hydra.core.plugins import Plugins
from hydra.plugins.launcher import Launcher
from hydra.plugins.sweeper import Sweeper
from omegaconf import DictConfig, ListConfig, OmegaConf, open_dict
from omegaconf.errors import OmegaConfBaseException

from gyrolab.contracts import registry
from gyrolab.engine.schemas import resolve_plain
from gyrolab.errors import ConfigError, leaves, shorten
from gyrolab.output.user_yaml import stored_yaml

#: ``_target_`` values allowed under ``hydra`` besides the installed launchers and sweepers
#: (gyrolab's sweep callback and sweeper are named, not imported: the engine sits below gyrolab.sweep)
HYDRA_TARGETS = frozenset({"gyrolab.sweep.callbacks.SweepCallback", "hydra_plugins.gyrolab_sweeper.GyrolabSweeper"})
#: classes a logging config may name with ``class`` or ``()``
LOGGING_CLASSES = frozenset({
    "logging.StreamHandler", "logging.FileHandler", "logging.NullHandler",
    "logging.handlers.RotatingFileHandler", "logging.handlers.WatchedFileHandler",
    "logging.Formatter", "logging.Filter", "colorlog.ColoredFormatter",
})
#: ``ext://`` objects a logging config may name
LOGGING_EXTERNALS = frozenset({"ext://sys.stdout", "ext://sys.stderr"})
#: environment variables a config may set for its jobs
ENV_ALLOWED = re.compile(r"^(OMP|MKL|OPENBLAS|NUMEXPR|NUMBA|VECLIB_MAXIMUM|BLIS)_NUM_THREADS$")
#: launcher options that become shell lines or scheduler arguments
LAUNCHER_SHELL_KEYS = ("setup", "srun_args", "additional_parameters")


@cache
def hydra_targets() -> frozenset[str]:
    """gyrolab's callback and sweeper and every installed Hydra launcher and sweeper class."""
    found = {f"{cls.__module__}.{cls.__qualname__}" for kind in (Launcher, Sweeper)
             for cls in Plugins.instance().discover(kind)}
    return HYDRA_TARGETS | found


def check_config(cfg: DictConfig, run_dir: Path | None = None, *, command_line: Sequence[str] = (),
                 job_subdir: bool = False) -> None:
    """ConfigError (one sentence naming the key) unless ``cfg`` is safe to hand to Hydra and gyrolab.

    ``cfg`` is a composed config, with its ``hydra`` node when Hydra will run it;
    ``run_dir`` is the directory the run (or sweep) writes in; ``job_subdir`` says a
    sweep job writes in ``run_dir/<hydra.sweep.subdir>``; ``command_line`` holds the
    overrides the user typed (shell lines of a launcher are accepted from there).
    """
    scene_keys = [k for k in cfg.keys() if k != "hydra"]
    scene = resolve_plain(OmegaConf.masked_copy(cfg, scene_keys)) if scene_keys else {}
    hydra = cfg.get("hydra") if "hydra" in cfg else None
    plain_hydra = _resolved_hydra(cfg, run_dir, job_subdir) if hydra is not None and run_dir is not None else {}
    _check_plugin_targets(scene)
    if not plain_hydra:
        return
    _check_hydra_targets(plain_hydra)
    mode = str(plain_hydra.get("mode") or "")
    if mode.endswith("MULTIRUN") != job_subdir and mode not in ("", "None"):
        raise ConfigError(f"hydra.mode={mode.rsplit('.', 1)[-1]} disagrees with the command line; start a sweep "
                          "with -m (gyrolab -m KEY=V1,V2 ...) and a single run without it")
    _check_paths(plain_hydra, Path(run_dir))
    out = Path(os.path.abspath(run_dir))
    out = out / str((plain_hydra.get("sweep") or {}).get("subdir", "")) if job_subdir else out
    for name in ("job_logging", "hydra_logging"):
        _check_logging(plain_hydra.get(name), f"hydra.{name}", out)
    for key in (plain_hydra.get("job") or {}).get("env_set") or {}:
        if not ENV_ALLOWED.match(str(key)):
            raise ConfigError(f"hydra.job.env_set.{shorten(str(key))} is not allowed; a config may set thread counts "
                              "only (OMP_NUM_THREADS, MKL_NUM_THREADS, ...); set other variables in your shell")
    _check_launcher_shell(plain_hydra.get("launcher") or {}, command_line)


def _check_plugin_targets(scene: dict) -> None:
    """ConfigError unless every ``_target_`` of the scene names a registered gyrolab plugin."""
    allowed_plugins = {registry._normalise(t) for group in registry.GROUPS for t in registry.targets(group).values()}
    for path, value in _targets(scene):
        if registry._normalise(str(value)) not in allowed_plugins:
            group = path.split(".", 1)[0]
            valid = (f"choose one by name ({group}=NAME), valid names: {', '.join(registry.names(group))}"
                     if group in registry.GROUPS else "a config may name only registered gyrolab plugins")
            raise ConfigError(f"{path}={shorten(repr(value))} is not a registered gyrolab plugin and cannot be "
                              f"called; {valid}")


def _check_hydra_targets(plain_hydra: dict) -> None:
    """ConfigError unless every ``_target_`` under hydra is gyrolab's sweep callback or an installed launcher or
    sweeper."""
    allowed = hydra_targets()
    for path, value in _targets(plain_hydra, "hydra"):
        if str(value) not in allowed:
            raise ConfigError(f"{path}={shorten(repr(value))} is not allowed; under hydra a config may name only "
                              f"gyrolab's sweep callback and the installed launchers and sweepers "
                              f"({', '.join(sorted(t.rsplit('.', 1)[1] for t in allowed))})")


def check_stored_config(text: str, where: str) -> DictConfig:
    """A config stored in a dataset, checked as a user's YAML file is (``gyrolab.output.user_yaml.stored_yaml``:
    tags, anchors, depth, size); ConfigError for interpolations."""
    plain = stored_yaml(text, where)  # a mapping: stored_yaml refuses anything else
    for path, value in leaves(plain):
        if isinstance(value, str) and "${" in value:
            raise ConfigError(f"{where}: {path}={shorten(repr(value))} is an interpolation, but a stored config is "
                              "resolved; the dataset was edited, and gyrolab will not rerun it")
    try:
        cfg = OmegaConf.create(plain)
    except OmegaConfBaseException as error:
        raise ConfigError(f"{where} is not a valid config ({shorten(str(error).splitlines()[0], 120)})") from None
    check_config(cfg)
    return cfg


def check_output_dir(text: str, key: str) -> None:
    """ConfigError for an output directory that is empty, the working directory or a parent, or in site-packages."""
    directory = Path(text)
    if not text.strip() or text.strip() in (".", "./"):
        raise ConfigError(f"{key}={text!r} would write into the working directory itself; give a directory "
                          f"for the results, e.g. {key}=outputs/run1")
    if "\0" in text or len(text) > 4096 or any(len(part) > 255 for part in directory.parts):
        raise ConfigError(f"{key}={shorten(repr(text))} is not a usable path (a NUL byte, a name longer than 255 "
                          f"characters or a path longer than 4096); give a directory, e.g. {key}=outputs/run1")
    resolved = Path(os.path.abspath(directory))
    cwd = Path(os.getcwd())
    if resolved == cwd or resolved in cwd.parents:
        raise ConfigError(f"{key}={shorten(text)} is the working directory or one of its parents; give a "
                          f"directory of its own for the results, e.g. {key}=outputs/run1")
    try:  # through symbolic links: a link into site-packages is where it points
        real = Path(os.path.realpath(resolved, strict=False))
    except (OSError, RuntimeError):  # a symlink loop (RuntimeError before Python 3.13)
        raise ConfigError(f"{key}={shorten(text)} cannot be resolved (a loop of symbolic links?); give a directory "
                          f"for the results, e.g. {key}=outputs/run1") from None
    _refuse_link_loop(resolved, key, text)
    _refuse_code_dirs(resolved, real, key, text)


def _refuse_code_dirs(resolved: Path, real: Path, key: str, text: str) -> None:
    """ConfigError for an output directory (as given, and where its links point) in a system directory, a
    site-packages folder or a folder Python loads code from."""
    for candidate in (resolved, real):
        if _is_system_dir(candidate):
            raise ConfigError(f"{key}={shorten(text)} is inside a system directory ({candidate.parts[1]}); give a "
                              f"directory for results, e.g. {key}=outputs/run1")
    for candidate in (resolved, real):
        if {"site-packages", "dist-packages"} & set(candidate.parts):  # any Python's, not only this one's
            raise ConfigError(f"{key}={shorten(text)} is inside a site-packages folder, where Python loads code "
                              f"from; give a directory for results, e.g. {key}=outputs/run1")
    for protected in _protected_dirs():
        for candidate in (resolved, real):
            if candidate == protected or protected in candidate.parents:
                raise ConfigError(f"{key}={shorten(text)} is inside {protected}, where Python loads code from; "
                                  f"give a directory for results, e.g. {key}=outputs/run1")


#: top-level folders of the operating system: results never go there (gyrolab may run as root in a container)
SYSTEM_DIRS = frozenset({"bin", "boot", "dev", "etc", "lib", "lib32", "lib64", "proc", "run", "sbin", "sys", "usr"})


def _is_system_dir(path: Path) -> bool:
    parts = path.parts
    if os.name != "posix" or len(parts) < 2 or parts[1] not in SYSTEM_DIRS:
        return False
    return not (parts[1] == "usr" and len(parts) > 2 and parts[2] == "local")  # /usr/local: the admin's own


def _refuse_link_loop(path: Path, key: str, text: str) -> None:
    """ConfigError when an existing part of ``path`` is a loop of symbolic links (realpath does not say so)."""
    for part in (path, *path.parents):
        if os.path.islink(part):
            try:
                os.stat(part)
            except OSError as error:
                if error.errno == 40:  # ELOOP
                    raise ConfigError(f"{key}={shorten(text)} goes through a loop of symbolic links ({part}); give a "
                                      f"directory for the results, e.g. {key}=outputs/run1") from None


@cache
def _protected_dirs() -> tuple[Path, ...]:
    dirs = set()
    for path in [*site.getsitepackages(), site.getusersitepackages(),
                 *(sysconfig.get_paths().get(k) for k in ("purelib", "platlib", "stdlib", "platstdlib")),
                 str(Path(__file__).resolve().parents[1])]:  # the last one: gyrolab's own folder
        if path:
            dirs.add(Path(os.path.abspath(path)))
            dirs.add(Path(os.path.realpath(path)))
    return tuple(sorted(dirs))


# ---- helpers ----------------------------------------------------------------------------------------------

def _resolved_hydra(cfg: DictConfig, run_dir: Path, job_subdir: bool) -> dict[str, Any]:
    """The ``hydra`` node resolved as a job would see it (output_dir set, job 0 of a sweep)."""
    copy = cfg.copy()
    with open_dict(copy):
        copy.hydra.job.num = 0
        copy.hydra.job.id = "0"
        copy.hydra.runtime.output_dir = str(run_dir)
        if job_subdir:
            subdir = OmegaConf.select(copy, "hydra.sweep.subdir", throw_on_resolution_failure=False)
            copy.hydra.runtime.output_dir = str(Path(run_dir) / str(subdir))
    plain: dict[str, Any] = {}
    try:
        for key in copy.hydra.keys():
            if key != "overrides":  # the command line as typed (checked as the config it composes)
                node = copy.hydra._get_node(key)
                plain[str(key)] = (OmegaConf.to_container(node, resolve=True, throw_on_missing=False)
                                   if isinstance(node, (DictConfig, ListConfig)) else copy.hydra[key])
    except OmegaConfBaseException as error:
        key = getattr(error, "full_key", None) or "hydra"
        raise ConfigError(f"{shorten(str(key))} cannot be resolved before the run "
                          f"({shorten(str(error).splitlines()[0], 120)}); give a plain value") from None
    return plain


def _items(node: Any, prefix: str = "") -> Iterator[tuple[str, str, Any]]:
    """(path, key, value) of every mapping entry, at any depth (lists too)."""
    if isinstance(node, dict):
        for key, value in node.items():
            path = f"{prefix}.{key}" if prefix else str(key)
            yield path, str(key), value
            yield from _items(value, path)
    elif isinstance(node, list):
        for i, value in enumerate(node):
            yield from _items(value, f"{prefix}[{i}]")


def _targets(node: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    for path, key, value in _items(node, prefix):
        if key == "_target_":
            yield path, value


def _check_logging(conf: Any, where: str, out_dir: Path) -> None:
    if conf is None:
        return
    if not isinstance(conf, dict):
        raise ConfigError(f"{where} must be a logging configuration (a mapping)")
    for path, key, value in _items(conf, where):
        if key in ("()", "class"):
            if str(value) not in LOGGING_CLASSES:
                raise ConfigError(f"{path}={shorten(repr(value))} is not allowed; a logging config may name only "
                                  f"{', '.join(sorted(LOGGING_CLASSES))}")
        elif key == ".":
            raise ConfigError(f"{path} sets attributes of a logging object, which a config may not do")
        elif key == "filename":
            target = Path(os.path.abspath(os.path.join(out_dir, str(value))))
            inside = target.parent == out_dir or out_dir in target.parents
            if not inside or target.suffix != ".log" or os.path.islink(target):
                raise ConfigError(f"{path}={shorten(str(value))} is not allowed; a log file must be a .log file inside "
                                  f"the run directory ({shorten(str(out_dir))})")
        if isinstance(value, str) and value.startswith("ext://") and value not in LOGGING_EXTERNALS:
            raise ConfigError(f"{path}={shorten(repr(value))} is not allowed; a logging config may refer only to "
                              "ext://sys.stdout and ext://sys.stderr")


def _check_paths(hydra: dict[str, Any], run_dir: Path) -> None:
    for key, value in (("hydra.output_subdir", hydra.get("output_subdir")),
                       ("hydra.sweep.subdir", (hydra.get("sweep") or {}).get("subdir"))):
        if value is None:
            continue
        text = str(value)
        parts = Path(text).parts
        if not text.strip() or Path(text).is_absolute() or ".." in parts:
            raise ConfigError(f"{key}={text!r} must be a relative path inside the run directory (no '..'), "
                              "e.g. .hydra")
    name = str((hydra.get("job") or {}).get("name", ""))
    if not name or "/" in name or os.sep in name or name in (".", ".."):
        raise ConfigError(f"hydra.job.name={shorten(repr(name))} must be a plain name (no '/'), e.g. gyrolab")
    folder = (hydra.get("launcher") or {}).get("submitit_folder")
    if folder is not None:
        resolved = Path(os.path.abspath(str(folder).replace("%j", "job")))
        base = Path(os.path.abspath(run_dir))
        if base not in resolved.parents:
            raise ConfigError(f"hydra.launcher.submitit_folder={shorten(str(folder))} must be inside the sweep "
                              "directory, e.g. ${hydra.sweep.dir}/.submitit/%j")


@cache
def _packaged_launcher_shell() -> dict[str, Any]:
    found: dict[str, Any] = {}
    for option in (files("gyrolab.conf") / "hydra" / "launcher").iterdir():
        if option.name.endswith(".yaml"):
            node = OmegaConf.to_container(OmegaConf.load(str(option)))
            for key in LAUNCHER_SHELL_KEYS:
                if node.get(key) is not None:
                    found.setdefault(key, []).append(node[key])
    return found


def _check_launcher_shell(launcher: dict[str, Any], command_line: Sequence[str]) -> None:
    typed = {o.lstrip("+").split("=", 1)[0] for o in command_line}
    for key in LAUNCHER_SHELL_KEYS:
        value = launcher.get(key)
        if value in (None, [], {}, "") or f"hydra.launcher.{key}" in typed:
            continue
        if value not in _packaged_launcher_shell().get(key, []):
            raise ConfigError(f"hydra.launcher.{key}={shorten(repr(value))} comes from a config file; shell lines and "
                              f"scheduler arguments run as you, so give them on the command line "
                              f"(hydra.launcher.{key}=...)")


#: a file name a config may give for an output: plain names and folders, ending in .nc
_OUTPUT_NAME = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.+-]*(/[A-Za-z0-9_][A-Za-z0-9_.+-]*)*\.nc$")


def confined_output_path(out_dir: str | os.PathLike[str], name: Any, key: str) -> Path:
    """``out_dir/name`` when it stays inside ``out_dir`` (symlinks resolved), else one ConfigError sentence: every file
    a config names for writing goes through here, so that it cannot make gyrolab write a file Python would load
    (docs/faults.md, "Paths: results stay inside the run directory")."""
    text = str(name) if isinstance(name, (str, os.PathLike)) else ""
    parts = Path(text).parts
    if not _OUTPUT_NAME.match(text) or ".." in parts or len(text) > 255:
        raise ConfigError(f"{key}={shorten(repr(name))} must be a file name ending in .nc inside the run directory "
                          f"(no '/..', no absolute path), e.g. {key}=stability_map.nc")
    base = Path(out_dir).resolve()
    target = (base / text).resolve()
    if base not in target.parents:
        raise ConfigError(f"{key}={shorten(text)} leads outside the run directory through a symbolic link; "
                          f"give a file name inside it, e.g. {key}=stability_map.nc")
    for protected in _protected_dirs():
        if target == protected or protected in target.parents:
            raise ConfigError(f"{key}={shorten(text)} lands inside {protected}, where Python loads code from; "
                              f"choose a run directory for results")
    return base / text
