"""Which Dask scheduler a batch trusts, and where its address came from.

Connecting to a Dask scheduler trusts it with code execution: the client unpickles what the scheduler and
its workers send back. So a scheduler's address is taken only from places the user controls for this
invocation — the command line (``gyrolab batch --scheduler ADDRESS``, ``gyrolab --batch --scheduler ...``),
the environment (``DASK_SCHEDULER_ADDRESS``) and Dask's own configuration (``scheduler-address`` in
``~/.config/dask/*.yaml`` or ``DASK_SCHEDULER_ADDRESS``) — never from a config file, an experiment or an
override of ``batch.scheduler``, which a shared experiment file could set. ``batch.scheduler`` keeps the
two values that trust nobody: ``process`` (this process) and ``local`` (a Dask cluster this process starts).

``resolve(configured)`` gives the choice and its source (the log names it; error messages name it).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from importlib.util import find_spec

from gyrolab.errors import ConfigError, shorten

#: Dask's own environment variable for a scheduler's address (``distributed.Client()`` reads it too)
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"
#: the key of Dask's configuration that holds a scheduler's address
DASK_CONFIG_KEY = "scheduler-address"
#: the values of ``batch.scheduler`` a config may give: they connect to nobody
CONFIG_VALUES = ("process", "local")

COMMAND_LINE = "the command line (--scheduler)"
ENVIRONMENT = f"the environment ({SCHEDULER_ENV})"
DASK_CONFIG = f"Dask's configuration ({DASK_CONFIG_KEY})"
CONFIG = "batch.scheduler"
DEFAULT = "the default"

_command_line: str | None = None


@dataclass(frozen=True)
class Choice:
    """Where the chunks run (None: this process) and the source that said so."""

    scheduler: str | None
    source: str


def use_command_line_scheduler(address: str | None) -> None:
    """The scheduler the command line gives (``--scheduler ADDRESS``); None: the command line gives none."""
    global _command_line
    _command_line = None if address is None else str(address).strip() or None


def command_line_scheduler() -> str | None:
    return _command_line


def parse_scheduler_option(argv: list[str]) -> tuple[str | None, list[str]]:
    """``--scheduler ADDRESS`` or ``--scheduler=ADDRESS`` taken out of ``argv``: (the address, the rest).

    For command lines parsed by hand (``gyrolab --batch ...`` without a subcommand parser); a parser
    (argparse) that has its own ``--scheduler`` option passes its value to ``use_command_line_scheduler``.
    """
    rest: list[str] = []
    address = None
    items = iter(argv)
    for item in items:
        if item == "--scheduler":
            address = next(items, None)
            if address is None or address.startswith("-"):
                raise ConfigError("--scheduler needs a value: process, local or a Dask scheduler's address "
                                  "(tcp://HOST:PORT or tls://HOST:PORT)")
        elif item.startswith("--scheduler="):
            address = item.split("=", 1)[1]
        else:
            rest.append(item)
    return address, rest


def resolve(configured: str | None) -> Choice:
    """The scheduler to use given ``batch.scheduler`` (``configured``) and this invocation's trusted sources.

    The command line wins; then a config's ``process`` or ``local``; then the environment; then Dask's
    configuration; else this process. A config (or experiment, or override) giving an address is refused
    in one sentence that says where the address belongs.
    """
    if _command_line is not None:
        return Choice(_command_line, COMMAND_LINE)
    text = "" if configured is None else str(configured).strip()
    if text:
        if text in CONFIG_VALUES:
            return Choice(text, CONFIG)
        refuse_configured(text)
    environment = os.environ.get(SCHEDULER_ENV, "").strip()
    if environment:
        return Choice(environment, ENVIRONMENT)
    from_dask = _dask_config_address()
    if from_dask:
        return Choice(from_dask, DASK_CONFIG)
    return Choice(None, DEFAULT)


def refuse_configured(text: str) -> None:
    raise ConfigError(f"batch.scheduler={shorten(text)!r} is refused: connecting to a Dask scheduler trusts it to run "
                      "code in this process, so a config, an experiment or an override may only say process or local, "
                      "and an address goes on the command line (gyrolab batch --scheduler ADDRESS), in "
                      f"{SCHEDULER_ENV} or in Dask's configuration ({DASK_CONFIG_KEY}; docs/cluster.md)")


def _dask_config_address() -> str | None:
    """``scheduler-address`` of Dask's configuration (its YAML files and ``DASK_*`` variables), if Dask is here."""
    if find_spec("dask") is None:
        return None
    import dask.config

    value = dask.config.get(DASK_CONFIG_KEY, default=None) or dask.config.get("scheduler_address", default=None)
    return str(value).strip() or None if value else None


__all__ = ["Choice", "command_line_scheduler", "parse_scheduler_option", "refuse_configured", "resolve",
           "use_command_line_scheduler"]
