"""The only door to Hydra's private API (``hydra._internal``): every use in gyrolab goes through these names.

Why gyrolab needs it, and why ``pyproject.toml`` pins ``hydra-core>=1.3,<1.4``:

* ``create_automatic_config_search_path`` and ``Hydra.create_main_hydra2``: the preflight composes exactly
  the config ``@hydra.main`` will run (same search path for ``--config-dir``/``--config-path``), so a bad
  command line is refused in one sentence before Hydra makes a run directory;
* ``get_args_parser``: the preflight reads Hydra's own command-line options as Hydra will;
* ``ConfigLoaderImpl._apply_overrides_to_config`` and ``BasicSweeper.split_arguments``: gyrolab's sweeper
  applies each job's value overrides as Hydra does, without composing every job;
* ``ConfigLoaderImpl``'s composition steps, ``create_defaults_list`` and ``get_overrides_dirname``:
  ``gyrolab.engine.composition`` composes once per command and serves every later request from it.

These are stable across Hydra 1.3.x but carry no promise; a new minor version is checked here first
(``tests/test_config.py``, ``tests/test_resume_sweeper.py`` and ``tests/test_cli.py`` exercise each one).
"""

from __future__ import annotations

from hydra._internal.config_loader_impl import ConfigLoaderImpl, get_overrides_dirname
from hydra._internal.defaults_list import create_defaults_list
from hydra._internal.utils import create_automatic_config_search_path, get_args_parser

# BasicSweeper and Hydra are served by __getattr__ below
__all__ = ["ConfigLoaderImpl", "create_automatic_config_search_path", "create_defaults_list", "get_args_parser",
           "get_overrides_dirname"]


def __getattr__(name: str):
    # the two heavier classes are imported when first asked for, as their callers did before
    if name == "Hydra":
        from hydra._internal.hydra import Hydra

        return Hydra
    if name == "BasicSweeper":
        from hydra._internal.core_plugins.basic_sweeper import BasicSweeper

        return BasicSweeper
    raise AttributeError(name)
