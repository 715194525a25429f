"""Hydra composition for gyrolab: the config module, plugin config nodes, friendly errors."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

from hydra import compose, initialize_config_module
from hydra.core.config_store import ConfigStore
from hydra.core.global_hydra import GlobalHydra
from hydra.errors import HydraException, MissingConfigException, OverrideParseException
from omegaconf import DictConfig
from omegaconf.errors import OmegaConfBaseException

from gyrolab.engine import registry
from gyrolab.errors import ConfigError, choices

CONFIG_MODULE = "gyrolab.conf"
CONFIG_NAME = "config"
#: groups whose options are chosen by name on the command line
SELECTABLE_GROUPS = ("system", "body", "initial", "force", "integrator", "regime", "experiment")


@cache
def register_plugin_configs() -> None:
    """Give every third-party plugin a config node built from its ``__init__`` keyword defaults.

    Built-in plugins have YAML files in ``conf/``; a plugin package only
    registers an entry point, and this makes ``force=[..., its_name]`` work.
    """
    store = ConfigStore.instance()
    for group in registry.GROUPS:
        for name, target in registry.external(group).items():
            cls = registry.load(group, name)
            node = {"_target_": target, **registry.default_params(cls)}
            # A force option nests under its own name so that several can be selected at once.
            store.store(group=group, name=name, node={name: node} if group == "force" else node)


def group_options(group: str) -> list[str]:
    """Names selectable in a config group (needs an initialised Hydra)."""
    loader = GlobalHydra.instance().config_loader()
    return sorted(loader.get_group_options(group))


def compose_config(overrides: Sequence[str], *, return_hydra_config: bool = False) -> DictConfig:
    """Compose gyrolab's config with command-line style overrides; ConfigError on any problem.

    Inside a running gyrolab app (an experiment composing its scenes) Hydra is already
    initialised on the same config module, and is reused.
    """
    register_plugin_configs()
    if GlobalHydra.instance().is_initialized():
        return _compose(overrides, return_hydra_config)
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        return _compose(overrides, return_hydra_config)


def _compose(overrides: Sequence[str], return_hydra_config: bool) -> DictConfig:
    try:
        return compose(config_name=CONFIG_NAME, overrides=list(overrides), return_hydra_config=return_hydra_config)
    except MissingConfigException as error:
        raise friendly_missing(error) from None
    except OverrideParseException as error:
        raise ConfigError(f"malformed override: {_first_line(error)}") from None
    except (HydraException, OmegaConfBaseException) as error:
        raise ConfigError(_first_line(error)) from None


def friendly_missing(error: MissingConfigException) -> ConfigError:
    missing = error.missing_cfg_file or ""
    group, _, option = missing.rpartition("/")
    if group and error.options is not None:
        return ConfigError(f"unknown {group} {option!r}; valid choices: {choices(error.options)}")
    return ConfigError(_first_line(error))


def _first_line(error: Exception) -> str:
    """The first line of a Hydra/OmegaConf message, without its pointer to the online docs."""
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    line = lines[0] if lines else type(error).__name__
    return line.split(" See https://")[0]
