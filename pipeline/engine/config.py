"""Hydra composition for gyrolab: where configs come from (:class:`ConfigSource`), plugin config nodes, friendly
errors. The search path is built with Hydra's own functions, exactly as ``@hydra.main`` builds it, so that the
config the preflight validates is the config that runs.
"""

from __future__ import annotations

import difflib
import os
import re
import warnings
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache
from importlib.resources import files
from pathlib import Path
from typing import Any

from hydra.core.config_search_path import ConfigSearchPath, SearchPathQuery
from hydra.core.config_store import ConfigStore
from hydra.core.global_hydra import GlobalHydra
from hydra.core.hydra_config import HydraConfig
from hydra.errors import HydraException, MissingConfigException, OverrideParseException
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import ConfigKeyError, OmegaConfBaseException, ValidationError

from gyrolab.compat import Hydra, create_automatic_config_search_path
from gyrolab.contracts import registry
from gyrolab.engine.schemas import (
    REQUIRED_SECTIONS,
    SELECTABLE_GROUPS,
    missing_section,
    plugin_schema,
    unknown_key_sentence,
    validate,
)
from gyrolab.engine.schemas import first_line as _first_line
from gyrolab.engine.schemas import sentence as schema_sentence
from gyrolab.engine.unread import refuse_given_accuracy
from gyrolab.errors import ConfigError, GyrolabWarning, choices, leaves, shorten
from gyrolab.output.user_yaml import check_user_config_dir

CONFIG_MODULE = "gyrolab.conf"
CONFIG_NAME = "config"
PACKAGED_PATH = f"pkg://{CONFIG_MODULE}"
#: the file of ``@hydra.main``: Hydra resolves a relative ``--config-path`` against its folder
_APP_FILE = str(Path(__file__).resolve().parent.parent / "app" / "__init__.py")


@dataclass(frozen=True)
class ConfigSource:
    """Where the primary config and the config groups come from (Hydra's ``-cp``, ``-cn``, ``-cd``)."""

    config_path: str = PACKAGED_PATH
    config_name: str = CONFIG_NAME
    config_dir: str | None = None
    #: ``hydra.searchpath`` of the composed config (Hydra appends it while composing; listing options needs it)
    searchpath: tuple[str, ...] = ()

    @classmethod
    def from_args(cls, config_path: str | None, config_name: str | None, config_dir: str | None) -> ConfigSource:
        """The source Hydra would use for these command-line options; ConfigError for a missing directory."""
        if config_dir is not None:
            config_dir = _user_dir(config_dir, "--config-dir", "your YAML files (e.g. --config-dir myconf)")
            warn_shadowed(config_dir, "--config-dir")
        if config_path is not None and not config_path.startswith("pkg://"):
            config_path = _user_dir(config_path, "--config-path",
                                    "your primary config (e.g. --config-path myconf --config-name mine)")
        if config_name is not None:
            config_name = config_name.removesuffix(".yaml")
            if not config_name or "\0" in config_name:
                raise ConfigError("--config-name is empty; give the name of your primary YAML file without "
                                  ".yaml (e.g. --config-name mine)")
        return cls(config_path or PACKAGED_PATH, config_name or CONFIG_NAME, config_dir)

    def search_path(self) -> ConfigSearchPath:
        """Hydra's search path for this source, built as ``hydra._internal.utils._run_hydra`` builds it."""
        search_path = create_automatic_config_search_path(_APP_FILE, None, self.config_path)
        if self.config_dir is not None:
            search_path.prepend(provider="command-line", path=f"file://{self.config_dir}",
                                anchor=SearchPathQuery(provider="schema"))
        for path in self.searchpath:
            if str(path).startswith("file://"):  # a config's hydra.searchpath: the user's files, checked as -cd's
                _check_search_dir(str(path)[len("file://"):])
            search_path.append(provider="main", path=path)
        return search_path


_source = ConfigSource()


def _user_dir(path: str, option: str, holds: str) -> str:
    """``path`` made absolute and checked as a user's config folder; ConfigError when it is no directory."""
    path = os.path.abspath(path)
    if not os.path.isdir(path):
        raise ConfigError(f"{option} {path!r} is not a directory; give the folder that holds {holds}")
    check_user_config_dir(path, option)
    return path


@cache
def _check_search_dir(directory: str) -> None:
    if os.path.isdir(directory):
        check_user_config_dir(os.path.abspath(directory), "hydra.searchpath")
        warn_shadowed(os.path.abspath(directory), "hydra.searchpath")


class ShadowedConfigWarning(GyrolabWarning):
    """A file in a user's config folder that is never read: gyrolab's packaged file of the same name wins."""


@cache
def warn_shadowed(directory: str, option: str) -> None:
    """One warning per file of a user's config folder (``--config-dir``, ``hydra.searchpath``) that has the path of
    one of gyrolab's packaged configs: Hydra searches gyrolab's configs first (``--config-dir`` goes after them on
    the search path, as in every Hydra app), so that file is never read."""
    packaged = files(CONFIG_MODULE)
    for path in sorted(Path(directory).rglob("*.yaml")):
        relative = path.relative_to(directory)
        if not packaged.joinpath(*relative.parts).is_file():
            continue
        shown = os.path.relpath(path) if not os.path.relpath(path).startswith("..") else str(path)
        group, name = relative.parent.as_posix(), relative.stem
        if group == ".":
            what, instead = f"gyrolab's primary config {relative.name}", "name yours mine.yaml and give --config-name mine"
        else:
            what, instead = (f"gyrolab's own {group} option {name!r}",
                             f"give yours another name and choose it by that name ({group}={name}_mine)")
        warnings.warn(f"{shown} is not read: {what} has the same name and is found first ({option} is searched after "
                      f"gyrolab's configs); {instead}", ShadowedConfigWarning, stacklevel=2)


def use_source(source: ConfigSource) -> None:
    """Make ``source`` the one :func:`compose_config` composes from (the app sets it from its options)."""
    global _source
    _source = source


@contextmanager
def hydra_for(source: ConfigSource | None = None) -> Iterator[None]:
    """A Hydra initialised on ``source`` (default: the current one) for the duration of the block."""
    GlobalHydra.instance().clear()
    Hydra.create_main_hydra2(task_name="app", config_search_path=(source or _source).search_path())
    try:
        yield
    finally:
        GlobalHydra.instance().clear()


@cache
def register_plugin_configs() -> None:
    """Give every third-party plugin a config node, its schema (``gyrolab.engine.schemas.plugin_schema``) with its
    ``_target_``, so that ``force=[..., its_name]`` works as the built-ins' YAML files do. A system plugin's
    ``default_body`` also becomes the body option ``body=NAME``, which selects the system (as
    ``conf/body/gyrostat_*.yaml`` do: a system option cannot override the body group that follows it). A plugin that
    cannot be used costs one ``PluginLoadWarning`` and gets a node without parameters: a scene naming it composes
    and is then refused by ``registry.load`` in one sentence."""
    store = ConfigStore.instance()
    for group in registry.GROUPS:
        for name, target in registry.external(group).items():
            try:
                cls = registry.load(group, name)
                node: Any = OmegaConf.merge(OmegaConf.structured(plugin_schema(cls)), {"_target_": target})
            except ConfigError as error:
                warnings.warn(f"{error}; gyrolab goes on without it", registry.PluginLoadWarning, stacklevel=1)
                cls, node = None, {"_target_": target}
            # A force option nests under its own name so that several can be selected at once.
            store.store(group=group, name=name, node={name: node} if group == "force" else node)
            body = plugin_default_body(group, cls) if cls is not None else None
            if body is not None:
                store.store(group="body", name=name, package="_global_",
                            node={"defaults": [{"override /system": name}], "body": body})


def plugin_default_body(group: str, cls: type) -> dict[str, Any] | None:
    """A third-party system's ``default_body`` (its body section), None for other plugins or without one."""
    body = cls.default_body if group == "system" else None
    if body is None:
        return None
    if not isinstance(body, dict) or not all(isinstance(k, str) for k in body):
        raise ConfigError(f"system plugin {cls.__name__}.default_body={shorten(repr(body))} must be a dict of "
                          "body keys to values (its body section); fix the plugin package")
    return dict(body)


def group_options(group: str) -> list[str]:
    """Names selectable in a config group (needs an initialised Hydra)."""
    return sorted(GlobalHydra.instance().config_loader().get_group_options(group))


def compose_config(overrides: Sequence[str], *, return_hydra_config: bool = False,
                   run_mode: RunMode = RunMode.RUN, from_shell: bool = False,
                   config_name: str | None = None, refuse_unread: bool = True) -> DictConfig:
    """Compose gyrolab's config with command-line style overrides; ConfigError on any problem.

    Inside a running gyrolab app (an experiment composing its scenes) Hydra is already
    initialised on the run's search path, and is reused with the run's primary config.
    A value the overrides give and the config's integrator does not read (``integrator=taylor accuracy=1e-8``)
    is refused (``gyrolab.engine.unread``); ``refuse_unread=False`` leaves that to the caller (the app's
    preflight, which decides over every job of a sweep).
    """
    register_plugin_configs()
    if GlobalHydra.instance().is_initialized():
        running = HydraConfig.get().job.config_name if HydraConfig.initialized() else None
        cfg = _compose(overrides, config_name or running or _source.config_name, return_hydra_config, run_mode,
                       from_shell)
    else:
        with hydra_for(_source):
            cfg = _compose(overrides, _source.config_name, return_hydra_config, run_mode, from_shell)
    if refuse_unread:
        refuse_given_accuracy(cfg, overrides)
    return cfg


def _compose(overrides: Sequence[str], config_name: str, return_hydra_config: bool, run_mode: RunMode,
             from_shell: bool) -> DictConfig:
    hydra = GlobalHydra.instance().hydra
    try:
        cfg = hydra.compose_config(config_name=config_name, overrides=list(overrides), run_mode=run_mode,
                                   from_shell=from_shell)
    except MissingConfigException as error:
        raise friendly_missing(error, config_name) from None
    except OverrideParseException as error:
        raise ConfigError(f"malformed override: {_first_line(error)}") from None
    except (HydraException, OmegaConfBaseException) as error:
        raise friendly_composition_error(error, overrides, config_name) from None
    except OverflowError:  # an integer of hundreds of digits given for a number
        raise ConfigError(f"{shorten(' '.join(overrides), 120)}: a number is too large; gyrolab takes numbers up to "
                          f"{MAX_MAGNITUDE:.0e} in magnitude (use nondimensional or scaled units)") from None
    except (ValueError, TypeError) as error:  # Hydra's defaults list on a malformed group override
        raise ConfigError(f"cannot compose the config with {shorten(' '.join(overrides), 120)} "
                          f"({shorten(_first_line(error), 120)})") from None
    # checked by the schemas, used as any mapping (an experiment sets whole sections); Hydra's own node stays typed
    plain = OmegaConf.create(OmegaConf.to_container(OmegaConf.masked_copy(cfg, [k for k in cfg if k != "hydra"]),
                                                    resolve=False))
    if return_hydra_config and "hydra" in cfg:
        plain.hydra = cfg.hydra
    OmegaConf.set_struct(plain, True)
    return plain


def _unknown_option(text: str) -> ConfigError | None:
    """"Could not load 'force/magnet'" (an option of a list group) as an unknown option with the valid ones."""
    loading = re.search(r"Could not load '(.+)/([^/']+)'", text)
    if not loading:
        return None
    group, option = loading.groups()
    try:
        valid = group_options(group)
    except Exception:  # noqa: BLE001 - the list is a hint
        valid = []
    return _unknown(group, option, valid)


def _unknown(group: str, option: str, valid: Sequence[str]) -> ConfigError:
    close = difflib.get_close_matches(option, valid, n=1)
    hint = f"; did you mean {group}={close[0]}?" if close else ""
    return ConfigError(f"unknown {group} {shorten(repr(option))}{hint} (valid choices: {choices(valid)})")


def friendly_missing(error: MissingConfigException, config_name: str = CONFIG_NAME) -> ConfigError:
    missing = error.missing_cfg_file or ""
    group, _, option = missing.rpartition("/")
    if group and error.options is not None:
        return _unknown(group, option, error.options)
    if missing == config_name or "Primary config" in str(error):
        return ConfigError(f"primary config {config_name!r} not found in {_source.config_path}"
                           f"{' or ' + _source.config_dir if _source.config_dir else ''}; --config-name names a "
                           "YAML file (without .yaml) in --config-path or --config-dir")
    return _unknown_option(_first_line(error)) or ConfigError(_first_line(error))


def friendly_composition_error(error: Exception, overrides: Sequence[str], config_name: str) -> ConfigError:
    """One sentence for Hydra's "Could not override 'KEY'" and friends, with the closest valid name."""
    text = _first_line(error)
    cause = error.__cause__ or error.__context__
    if isinstance(cause, (ValidationError, ConfigKeyError)) and (getattr(cause, "full_key", None)
                                                                 or "Merge error" in str(cause)):
        return schema_sentence(cause)  # a schema's refusal: the key, the value, what is expected
    if text.startswith("Could not append to config. An item is already at '"):
        key = text.split("'")[1]
        return ConfigError(f"+{shorten(key)}=... adds a key, but `{shorten(key)}` exists already; change it with "
                           f"{shorten(key)}=VALUE (or ++{shorten(key)}=VALUE to add or change)")
    if text.startswith("Error merging override ") and cause is not None:
        override = text[len("Error merging override "):]
        reason = _first_line(cause).split(" full_key:")[0]
        return ConfigError(f"override {shorten(override)!r} cannot be applied ({shorten(reason, 160)})")
    unknown = _unknown_option(text)
    if unknown is not None:
        return unknown
    if text.startswith("Could not override '"):
        key = text.split("'")[1]
        override = next((o for o in overrides if o.lstrip("+~").split("=", 1)[0].split("@")[0] == key), key)
        return ConfigError(unknown_key_sentence(key, _known_names(overrides, key, config_name), override,
                                                type(cause).__name__ if cause else ""))
    if "Could not delete from config" in text or "Could not find" in text:
        return ConfigError(f"{shorten(text, 200)}; ~KEY deletes only a key or group the config has")
    return ConfigError(shorten(text, 300))


def _known_names(overrides: Sequence[str], key: str, config_name: str) -> list[str]:
    """Every key path of the config composed without the override of ``key`` (and the config groups)."""
    rest = [o for o in overrides if o.lstrip("+~").split("=", 1)[0].split("@")[0] != key]
    try:
        cfg = GlobalHydra.instance().hydra.compose_config(config_name=config_name, overrides=rest,
                                                          run_mode=RunMode.RUN, from_shell=False)
    except Exception:  # noqa: BLE001 - the hint is best effort; the sentence stands without it
        return []
    return [*key_paths(cfg), *SELECTABLE_GROUPS]


def key_paths(node: Any, prefix: str = "") -> Iterator[str]:
    """Dotted paths of every key in a config (mappings only; list items are not keys)."""
    if isinstance(node, DictConfig):
        for key in node.keys():
            path = f"{prefix}.{key}" if prefix else str(key)
            yield path
            child = node._get_node(key)
            if isinstance(child, DictConfig) and not child._is_interpolation():
                yield from key_paths(child, path)


# ---- the scene config: its schemas (gyrolab.engine.schemas), then what a type cannot say ----------------------

def check_scene_config(cfg: DictConfig) -> dict[str, Any]:
    """The scene config resolved to plain values (keys and types: :func:`gyrolab.engine.schemas.validate`);
    ConfigError for a missing section, an unknown key, a wrong type, a bad reference, a number too large to compute
    with or a torque that silently vanishes."""
    for section in REQUIRED_SECTIONS:
        if section not in cfg or OmegaConf.is_missing(cfg, section) or cfg[section] is None:
            raise ConfigError(missing_section(section))
    plain = validate(cfg)
    for section, node in plain.items():
        _check_magnitudes(str(section), node)
    _check_degenerate_vectors(plain)
    return plain


def _check_degenerate_vectors(plain: dict[str, Any]) -> None:
    """A zero centre-of-mass vector under uniform gravity is a torque that silently vanishes: refused.

    (Zero field directions and axes are refused by the plugins that normalise them.)
    """
    forces = plain.get("force") or {}  # a dict: the schema's
    magnetic = forces.get("magnetic")
    if isinstance(magnetic, dict) and _is_zero(magnetic.get("moment")):
        raise ConfigError(f"force.magnetic.moment={magnetic['moment']} is a zero vector, so the magnetic force would "
                          "exert no torque; give the body's magnetic moment (e.g. force.magnetic.moment=[0,0,1]), or "
                          "leave magnetic out of the forces (force=[uniform_gravity])")
    if "uniform_gravity" not in forces:
        return
    body = plain.get("body") or {}
    key = "com" if body.get("units") == "si" else "com_direction"
    vector = body.get(key)
    if _is_zero(vector):
        raise ConfigError(f"body.{key}={vector} is a zero vector, so uniform gravity would exert no torque; give the "
                          f"centre of mass's direction (e.g. body.{key}=[0,0,1]), or to run without gravity torque "
                          "leave uniform_gravity out of the forces (force=[] for the torque-free Euler top)")


def _is_zero(vector: Any) -> bool:
    return isinstance(vector, list) and bool(vector) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and v == 0 for v in vector)


#: no physical setting of a scene is this large; beyond it squares and products overflow a double
MAX_MAGNITUDE = 1e100


def _check_magnitudes(where: str, node: Any) -> None:
    """ConfigError for a number beyond :data:`MAX_MAGNITUDE` (``initial.r0=1e300`` overflows the first product)."""
    for path, value in leaves(node, where):
        if not isinstance(value, (int, float)) or isinstance(value, bool):
            continue
        try:
            large = MAX_MAGNITUDE < abs(float(value)) < float("inf")  # inf and nan: require_finite says so
        except OverflowError:
            large = True
        if large:
            raise ConfigError(f"{path}={shorten(repr(value), 40)} is too large; gyrolab takes numbers up to "
                              f"{MAX_MAGNITUDE:.0e} in magnitude (use nondimensional or scaled units)")
