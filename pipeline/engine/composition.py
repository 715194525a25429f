"""One composition per command: Hydra's config composition, remembered for the rest of the command.

Without it, one ``gyrolab`` run composed its config three times (the preflight, Hydra's ``get_mode``
and Hydra's run), and a sweep of N jobs N + 4 times, each composition reading every YAML file of the
defaults list again (~60 ms). Inside :func:`composing_once` Hydra's ``ConfigLoaderImpl`` splits its
composition in two, as its own code does:

1. the *skeleton*: the defaults list and the config merged from it, which depend only on the primary
   config, the search path and the overrides that choose config-group options (``integrator=rk4``,
   ``hydra/launcher=joblib``, ``+experiment=x``, ``~regime``); composed once per distinct set of
   those, exactly as Hydra composes it (the same functions, in the same order);
2. the rest, for every request: a copy of the skeleton, the value overrides applied with Hydra's own
   function, and the ``hydra`` node filled in (overrides, choices, override_dirname, cwd, ...), by a
   copy of the tail of Hydra's ``_load_configuration_impl`` (Hydra is pinned to 1.3.x for it; the
   tests compare both paths' configs key by key).

So the preflight's composition is the one Hydra's run uses, and the jobs of a value sweep share one
skeleton; every job still gets the config Hydra would compose for it. Which overrides shape the
defaults list follows Hydra 1.3's own rule (``defaults_list.Overrides``: the name of a config group,
not given a mapping); when Hydra's defaults list takes other overrides as values on a first
composition, that request is composed by Hydra itself. ``tests/test_sweep_composition.py`` compares
both paths' configs for every job of a set of sweeps, which is what a new Hydra is checked by.
"""

from __future__ import annotations

import copy
import os
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

from hydra.conf import ConfigSourceInfo
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.core.utils import JobRuntime
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict

from gyrolab.engine.hydra_private import ConfigLoaderImpl, create_defaults_list, get_overrides_dirname


@dataclass
class Skeleton:
    """The config Hydra merged from one defaults list, before any value override, and what goes with it."""

    cfg: DictConfig
    known_choices: dict[str, Any]
    sources: list[Any]
    #: a default was left out because it is missing (``group: ???``): only a multirun composition does that
    skipped_missing: bool


class CompositionMemo:
    """Skeletons by what shapes them, and the config repositories that classify overrides."""

    def __init__(self) -> None:
        self.skeletons: dict[tuple, Skeleton] = {}
        self.repositories: dict[tuple, Any] = {}
        self.compositions = 0   # skeletons composed (how many times Hydra read the YAML files)
        self.requests = 0       # configs handed out

    def load(self, loader: ConfigLoaderImpl, config_name: str | None, overrides: list[str], run_mode: RunMode,
             from_shell: bool, validate_sweep_overrides: bool) -> DictConfig:
        """What ``loader._load_configuration_impl`` returns for these arguments."""
        if config_name is None:
            return _ORIGINAL(loader, config_name=config_name, overrides=overrides, run_mode=run_mode,
                             from_shell=from_shell, validate_sweep_overrides=validate_sweep_overrides)
        from hydra import __version__, version

        self.requests += 1
        loader.ensure_main_config_source_available()
        parsed = OverridesParser.create().parse_overrides(overrides=overrides)
        place = (_search_path_key(loader), config_name, _searchpath_override(parsed))
        repo = self.repositories.get(place)
        if repo is None:  # (Hydra's order: the repository, then the sweep check)
            _, repo = loader._parse_overrides_and_create_caching_repo(
                config_name, [o.input_line for o in parsed if o.get_key_element() == "hydra.searchpath"])
            self.repositories[place] = repo
        if validate_sweep_overrides:
            loader.validate_sweep_overrides_legal(overrides=parsed, run_mode=run_mode, from_shell=from_shell)
        shaping, config_overrides = _classify(parsed, repo)
        skeleton = self._skeleton(loader, place, config_name, parsed, shaping, config_overrides, run_mode)
        if skeleton is None:  # classified unlike Hydra (a Hydra this code does not know): Hydra composes it
            return _ORIGINAL(loader, config_name=config_name, overrides=overrides, run_mode=run_mode,
                             from_shell=from_shell, validate_sweep_overrides=validate_sweep_overrides)

        # From here on a copy of the tail of Hydra 1.3's ConfigLoaderImpl._load_configuration_impl.
        cfg = copy.deepcopy(skeleton.cfg)
        ConfigLoaderImpl._apply_overrides_to_config(config_overrides, cfg)
        app_overrides = []
        for override in parsed:
            if override.is_hydra_override():
                cfg.hydra.overrides.hydra.append(override.input_line)
            else:
                cfg.hydra.overrides.task.append(override.input_line)
                app_overrides.append(override)
        with open_dict(cfg.hydra):
            cfg.hydra.runtime.choices.update(skeleton.known_choices)
            for key in cfg.hydra.job.env_copy:
                cfg.hydra.job.env_set[key] = os.environ[key]
        cfg.hydra.runtime.version = __version__
        cfg.hydra.runtime.version_base = version.getbase()
        cfg.hydra.runtime.cwd = os.getcwd()
        cfg.hydra.runtime.config_sources = [ConfigSourceInfo(path=x.path, schema=x.scheme(), provider=x.provider)
                                            for x in skeleton.sources]
        if "name" not in cfg.hydra.job:
            cfg.hydra.job.name = JobRuntime().get("name")
        cfg.hydra.job.override_dirname = get_overrides_dirname(
            overrides=app_overrides,
            kv_sep=cfg.hydra.job.config.override_dirname.kv_sep,
            item_sep=cfg.hydra.job.config.override_dirname.item_sep,
            exclude_keys=cfg.hydra.job.config.override_dirname.exclude_keys,
        )
        cfg.hydra.job.config_name = config_name
        return cfg

    def _skeleton(self, loader: ConfigLoaderImpl, place: tuple, config_name: str, parsed: list[Override],
                  shaping: tuple[str, ...], config_overrides: list[Override], run_mode: RunMode) -> Skeleton | None:
        """The skeleton for these overrides, composed on first use; None if Hydra splits them otherwise."""
        multirun = run_mode == RunMode.MULTIRUN
        key = (*place, shaping)
        # A run's skeleton serves a multirun's request too (skipping missing defaults changes nothing when there
        # are none), and a multirun's a run's when it skipped none.
        found = self.skeletons.get((*key, False))
        if found is not None:
            return found
        found = self.skeletons.get((*key, True))
        if found is not None and (multirun or not found.skipped_missing):
            return found
        # As Hydra composes: a fresh repository (its own YAML cache), the defaults list, the merge.
        _, repo = loader._parse_overrides_and_create_caching_repo(config_name, [o.input_line for o in parsed])
        defaults_list = create_defaults_list(repo=repo, config_name=config_name, overrides_list=parsed,
                                             prepend_hydra=True, skip_missing=multirun)
        if [o.input_line for o in defaults_list.config_overrides] != [o.input_line for o in config_overrides]:
            return None
        cfg = loader._compose_config_from_defaults_list(defaults=defaults_list.defaults, repo=repo)
        OmegaConf.set_struct(cfg, True)
        OmegaConf.set_readonly(cfg.hydra, False)
        self.compositions += 1
        skeleton = Skeleton(cfg, dict(defaults_list.overrides.known_choices), list(repo.get_sources()),
                            multirun and _has_missing(defaults_list.defaults_tree))
        self.skeletons[(*key, multirun)] = skeleton
        return skeleton


def _classify(parsed: Sequence[Override], repo: Any) -> tuple[tuple[str, ...], list[Override]]:
    """(the overrides that shape the defaults list, the value overrides), split as Hydra's ``Overrides`` does."""
    appended, chosen, values = [], [], []
    for override in parsed:
        if override.is_sweep_override():
            continue  # Hydra's defaults list ignores a sweep (the master config of a multirun)
        if isinstance(override.value(), dict) or not repo.group_exists(override.key_or_group):
            values.append(override)
        elif override.is_add():
            appended.append(override.input_line)  # appended to the defaults list in this order
        else:
            chosen.append((override.get_key_element(), override.input_line))
    # A choice or deletion is looked up by its key, so only the order among one key's overrides matters
    # (the last wins): a job's Hydra overrides go first, the command line may have had them last.
    chosen.sort(key=lambda item: item[0])
    return (*appended, "", *(line for _, line in chosen)), values


def _searchpath_override(parsed: Sequence[Override]) -> str | None:
    return next((o.input_line for o in parsed if o.get_key_element() == "hydra.searchpath"), None)


def _search_path_key(loader: ConfigLoaderImpl) -> tuple:
    return tuple((p.provider, p.path) for p in loader.config_search_path.get_path())


def _has_missing(tree: Any) -> bool:
    """Whether a defaults tree holds a default whose option is missing (``???``)."""
    node = getattr(tree, "node", tree)
    try:
        if str(node.get_config_path()).endswith("???"):
            return True
    except Exception:  # noqa: BLE001 - a node without a path (the virtual root) is not missing
        pass
    return any(_has_missing(child) for child in (getattr(tree, "children", None) or []))


_ORIGINAL = ConfigLoaderImpl._load_configuration_impl
#: the memo of the command running now (None outside :func:`composing_once`)
active: CompositionMemo | None = None


@contextmanager
def composing_once() -> Iterator[CompositionMemo]:
    """Within the block every Hydra composition in this process goes through one :class:`CompositionMemo`.

    Scoped to one command: the YAML files, the working directory and the environment are taken to stay
    as they are while it runs (the tail that reads the last two runs for every request anyway).
    """
    global active
    if active is not None:  # nested (a command run from a command): the outer memo serves
        yield active
        return
    memo = active = CompositionMemo()

    def load(self: ConfigLoaderImpl, config_name: str | None, overrides: list[str], run_mode: RunMode,
             from_shell: bool = True, validate_sweep_overrides: bool = True) -> DictConfig:
        return memo.load(self, config_name, list(overrides), run_mode, from_shell, validate_sweep_overrides)

    ConfigLoaderImpl._load_configuration_impl = load
    try:
        yield memo
    finally:
        ConfigLoaderImpl._load_configuration_impl = _ORIGINAL
        active = None
