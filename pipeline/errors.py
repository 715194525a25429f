"""Errors gyrolab reports to its users.

Every message is one sentence naming the bad value and what would be valid;
the command-line app prints it as ``gyrolab: error: <message>`` and exits
non-zero before any ``run.nc`` is written.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from typing import Any


class GyrolabError(Exception):
    """Base class of the errors the app turns into a one-line message."""

    exit_code = 1


class ConfigError(GyrolabError, ValueError):
    """The scene's configuration is invalid (bad input from the user)."""

    exit_code = 2


class IntegrationError(GyrolabError, RuntimeError):
    """An integrator could not produce a trustworthy trajectory."""

    exit_code = 3


class OutputError(GyrolabError, OSError):
    """A result could not be written (no space, file too large, read-only, permission denied)."""

    exit_code = 3


class GyrolabWarning(UserWarning):
    """A warning the command line prints as one line, ``gyrolab: warning: <message>``."""


#: the largest integer a float64 can hold (a longer integer cannot be used as a number)
MAX_FLOAT_INT = int(1.7976931348623157e308)


def shorten(text: str, limit: int = 80) -> str:
    """``text`` cut to ``limit`` characters (with its length) so that a one-sentence error stays readable."""
    text = str(text).replace("\n", " ")
    return text if len(text) <= limit else f"{text[:limit // 2]}…{text[-limit // 4:]} ({len(text)} characters)"


def choices(names: Iterable[str]) -> str:
    """Format valid choices for an error message."""
    names = sorted(names)
    return ", ".join(names) if names else "(none registered)"


def leaves(node: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    """(dotted path, value) of every value that is neither a mapping nor a list, at any depth (``a.b[0]``)."""
    if isinstance(node, Mapping):
        for key, value in node.items():
            yield from leaves(value, f"{prefix}.{key}" if prefix else str(key))
    elif isinstance(node, (list, tuple)):
        for i, value in enumerate(node):
            yield from leaves(value, f"{prefix}[{i}]")
    else:
        yield prefix, node


def require_finite(value: Any, where: str) -> None:
    """Raise ConfigError if a number (or any number nested in lists/dicts) is NaN or inf."""
    for path, item in leaves(value, where):
        if isinstance(item, int) and not isinstance(item, bool) and abs(item) > MAX_FLOAT_INT:
            raise ConfigError(f"{path}={shorten(str(item))} is too large to be represented as a 64-bit float "
                              f"({len(str(abs(item)))} digits); every numeric setting must be below 1.8e308")
        if isinstance(item, float) and not math.isfinite(item):
            raise ConfigError(f"{path}={item} is not a finite number; every numeric setting must be finite")


def as_vector3(value: Any, where: str) -> tuple[float, float, float]:
    """Read a 3-vector from a config value, with a one-sentence error otherwise."""
    try:
        items = [float(v) for v in value]
    except (TypeError, ValueError, OverflowError):
        raise ConfigError(f"{where}={value!r} must be a list of three numbers") from None
    if len(items) != 3:
        raise ConfigError(f"{where}={list(value)!r} must have exactly three components")
    for item in items:
        if not math.isfinite(item):
            raise ConfigError(f"{where}={list(value)!r} contains a non-finite number; all three must be finite")
    return items[0], items[1], items[2]


def as_number(value: Any, where: str, *, positive: bool = False, nonnegative: bool = False) -> float:
    """Read a finite float from a config value, optionally requiring a sign."""
    if isinstance(value, bool):
        raise ConfigError(f"{where}={value!r} must be a number, not a boolean")
    try:
        number = float(value)
    except OverflowError:
        raise ConfigError(f"{where}={shorten(str(value))} is too large to be represented as a 64-bit float") from None
    except (TypeError, ValueError):
        raise ConfigError(f"{where}={value!r} must be a number") from None
    if not math.isfinite(number):
        raise ConfigError(f"{where}={value} is not a finite number; it must be finite")
    if positive and number <= 0:
        raise ConfigError(f"{where}={value} must be positive")
    if nonnegative and number < 0:
        raise ConfigError(f"{where}={value} must be zero or positive")
    return number
