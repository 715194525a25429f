"""The one place where gyrolab reaches into Hydra's and xarray's internals: each use is checked against the
library version it was written for and takes the library's own public path otherwise (what each gains:
docs/performance.md, "A sweep's per-job overhead").

* :func:`composing_once` (Hydra 1.3.x): one composition per command. Inside the block
  ``ConfigLoaderImpl._load_configuration_impl`` composes the *skeleton* (the defaults list and the config merged
  from it) once per set of group choices, with Hydra's functions in Hydra's order, and serves each request from
  a copy: the value overrides applied with Hydra's function, the ``hydra`` node filled by a copy of the tail of
  Hydra 1.3's ``_load_configuration_impl``; a request Hydra classifies otherwise is Hydra's own.
  ``tests/compat/test_composing_once.py`` compares both paths for every job of sweeps.
* :func:`install_dask_free_writes` (xarray ``XARRAY_SUPPORTED``): ``to_netcdf`` without importing Dask for a
  dataset that holds nothing of Dask's.
* :func:`direct_dataset` (xarray ``XARRAY_SUPPORTED``): a run dataset whose coordinates a scene kept from its first
  run, assembled without xarray's alignment and merge (``Dataset._construct_direct``; the public constructor
  otherwise). ``tests/engine/test_scene.py`` compares it with a fresh build, ``tests/compat/test_direct_dataset.py``
  both paths.
* :func:`run_hydra` (Hydra 1.3.x): ``_run_hydra`` given the namespace of gyrolab's own parser; otherwise
  ``hydra.main`` on ``sys.argv`` rebuilt from it.

Also here, with no fallback (``pyproject.toml`` pins ``hydra-core>=1.3,<1.4``): the private functions the
preflight composes with exactly as Hydra will, and those gyrolab's sweeper applies job overrides with.
"""

from __future__ import annotations

import argparse
import copy
import os
import sys
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import hydra
import xarray
from hydra import version as hydra_version
from hydra._internal.core_plugins.basic_sweeper import BasicSweeper  # noqa: F401 - re-exported
from hydra._internal.config_loader_impl import ConfigLoaderImpl, get_overrides_dirname
from hydra._internal.defaults_list import create_defaults_list
from hydra._internal.hydra import Hydra  # noqa: F401 - re-exported
from hydra._internal.utils import _run_hydra, create_automatic_config_search_path, get_args_parser  # noqa: F401
from hydra.conf import ConfigSourceInfo
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.core.utils import JobRuntime
from hydra.types import RunMode
from omegaconf import DictConfig, OmegaConf, open_dict
from xarray.backends import locks, netCDF4_, writers
from xarray.namedarray import pycompat, utils

#: the versions each kept patch was written for: (first, first not supported), by (major, minor)
HYDRA_SUPPORTED = ((1, 3), (1, 4))
XARRAY_SUPPORTED = ((2024, 1), (2027, 1))


def supported(version: str, window: tuple[tuple[int, int], tuple[int, int]]) -> bool:
    """Whether ``version`` ("1.3.8", "2026.9.0", "2025.1.2.dev3") lies in ``window``."""
    try:
        major, minor = (int(part) for part in version.split(".")[:2])
    except ValueError:
        return False
    return window[0] <= (major, minor) < window[1]


def hydra_supported() -> bool:
    return supported(hydra.__version__, HYDRA_SUPPORTED)


def run_hydra(args: argparse.Namespace, parser: argparse.ArgumentParser, task_function: Any, config_path: str,
              config_name: str) -> None:
    """What ``@hydra.main(config_path, config_name, version_base="1.3")`` does with a command line ``parser`` parsed
    into ``args``; outside ``HYDRA_SUPPORTED``: ``hydra.main`` itself, on a ``sys.argv`` rebuilt from ``args``."""
    hydra_version.setbase("1.3")
    if hydra_supported():
        _run_hydra(args=args, args_parser=parser, task_function=task_function, config_path=config_path,
                   config_name=config_name)
        return
    saved = sys.argv[1:]
    sys.argv[1:] = hydra_argv(args)
    try:
        hydra.main(config_path=config_path, config_name=config_name, version_base="1.3")(task_function)()
    finally:
        sys.argv[1:] = saved


def hydra_argv(args: argparse.Namespace) -> list[str]:
    """The command line Hydra's own parser reads as ``args``: its options, then the overrides."""
    words: list[str] = []
    for action in get_args_parser()._actions:
        value = getattr(args, action.dest, None)
        if action.option_strings and value not in (None, False) and action.dest != "version":
            words += action.option_strings[:1] if action.nargs == 0 else [action.option_strings[0], str(value)]
    return [*words, *args.overrides]


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
        cfg.hydra.runtime.version = hydra.__version__
        cfg.hydra.runtime.version_base = hydra_version.getbase()
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
    """Within the block every Hydra composition in this process goes through one :class:`CompositionMemo`, scoped to
    one command: the YAML files are taken to stay as they are while it runs (the tail reads the working directory
    and the environment for every request anyway)."""
    global active
    if active is not None:  # nested (a command run from a command): the outer memo serves
        yield active
        return
    memo = CompositionMemo()
    if not hydra_supported():  # a Hydra this copy was not written for: every composition is Hydra's own
        yield memo
        return
    active = memo

    def load(self: ConfigLoaderImpl, config_name: str | None, overrides: list[str], run_mode: RunMode,
             from_shell: bool = True, validate_sweep_overrides: bool = True) -> DictConfig:
        return memo.load(self, config_name, list(overrides), run_mode, from_shell, validate_sweep_overrides)

    ConfigLoaderImpl._load_configuration_impl = load
    try:
        yield memo
    finally:
        ConfigLoaderImpl._load_configuration_impl = _ORIGINAL
        active = None


# xarray's string coder asks whether a char array is a Dask array (``pycompat.array_type("dask")``, which imports
# ``dask.array``, and ``utils.is_dask_collection``, which imports ``dask.base``), and asks Dask's scheduler whether
# to close the file after every write (``writers._get_netcdf_autoclose``) and which write lock to take
# (``locks.get_write_lock``, which imports ``distributed``). A guard in front of each gives Dask's or xarray's own
# answer without the import where the answer cannot depend on Dask (each guard says why), and asks otherwise: once
# Dask is in use (a batch on a Dask scheduler, a chunked dataset), xarray decides as before. An xarray without one
# of these functions keeps it unguarded.

_GUARD = "_gyrolab_scheduler_guard"


def direct_dataset(variables: dict[str, Any], coord_names: set[str], sizes: dict[str, int],
                   indexes: dict[str, Any]) -> xarray.Dataset:
    """The dataset of ``variables`` (in their order; those named in ``coord_names`` its coordinates, with their
    ``indexes``), already consistent: every dimension of the sizes ``sizes``. xarray's own constructor for that case
    (no alignment or merge: ~0.01 ms against ~0.25 for ``xarray.Dataset`` on the reference scene's run dataset,
    about twice that after other work has taken the caches), within ``XARRAY_SUPPORTED``; the public constructor
    otherwise."""
    if supported(xarray.__version__, XARRAY_SUPPORTED):
        return xarray.Dataset._construct_direct(variables, set(coord_names), dict(sizes), None, dict(indexes))
    coords = xarray.Coordinates({name: variables[name] for name in variables if name in coord_names},
                                indexes=indexes)
    return xarray.Dataset({name: v for name, v in variables.items() if name not in coord_names}, coords=coords)


def install_dask_free_writes() -> bool:
    """Install the four guards (once per process); whether all four are in place. False, and nothing
    installed, under an xarray outside ``XARRAY_SUPPORTED``: xarray's own path, which imports Dask."""
    if not supported(xarray.__version__, XARRAY_SUPPORTED):
        return False
    return all([
        _guard(pycompat, "_get_cached_duck_array_module", _no_dask_arrays_before_dask),
        _guard(utils, "is_dask_collection", _no_graph_no_collection),
        _guard(writers, "_get_netcdf_autoclose", _unchunked_autoclose),
        _guard(netCDF4_, "get_write_lock", lambda original: _lock_without_dask(original, locks)),
    ])


def _guard(module: Any, name: str, make: Any) -> bool:
    original = getattr(module, name, None)
    if original is None:
        return False
    if not getattr(original, _GUARD, False):
        guarded = make(original)
        setattr(guarded, _GUARD, True)
        guarded.__wrapped__ = original
        setattr(module, name, guarded)
    return True


class _DaskNotImported:
    """xarray's record of the ``dask`` duck-array module, asked before ``dask.array`` is imported: no type yet
    (nothing can be an instance of a class not loaded); anything else is xarray's own answer."""

    type: tuple = ()

    def __init__(self, original: Any) -> None:
        self._original = original

    def __getattr__(self, name: str) -> Any:
        return getattr(self._original("dask"), name)


def _no_dask_arrays_before_dask(original: Any) -> Any:
    def cached_duck_array_module(mod: Any) -> Any:
        if mod == "dask" and "dask.array" not in sys.modules:
            return _DaskNotImported(original)  # not cached: once dask.array is imported, xarray's record
        return original(mod)
    return cached_duck_array_module


def _no_graph_no_collection(original: Any) -> Any:
    def is_dask_collection(x: object) -> bool:
        if "dask" not in sys.modules and not callable(getattr(x, "__dask_graph__", None)):
            return False  # dask.base.is_dask_collection's answer for an object without a graph method
        return original(x)
    return is_dask_collection


def _unchunked_autoclose(original: Any) -> Any:
    def autoclose(dataset: Any, engine: Any) -> bool:
        if all(variable.chunks is None for variable in dataset.variables.values()):
            return False  # xarray's answer without chunks
        return original(dataset, engine)
    return autoclose


def _lock_without_dask(original: Any, locks: Any) -> Any:
    lock_maker = getattr(locks, "_get_lock_maker", None)

    def get_write_lock(key: str) -> Any:
        if lock_maker is None or "distributed" in sys.modules or _configured_scheduler():
            return original(key)
        return lock_maker(None)(key)  # xarray's lock without a Dask scheduler (= under Dask's default)
    return get_write_lock


def _configured_scheduler() -> bool:
    """Whether Dask, if imported, is configured with a scheduler (then xarray's lock follows it)."""
    dask = sys.modules.get("dask")
    config = getattr(dask, "config", None)
    return config is not None and bool(config.get("scheduler", None) or config.get("get", None))
