"""The ``output`` settings of figures (``output.figure_formats``, ``output.dpi``), checked without matplotlib."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from gyrolab.errors import ConfigError, choices

#: file formats a figure can be written in (``output.figure_formats``)
FORMATS = ("png", "pdf", "svg")
DEFAULT_FORMATS = ("png",)
DEFAULT_DPI = 200


def figure_options(output: Mapping[str, Any] | None) -> tuple[tuple[str, ...], int]:
    """(formats, dpi) of an ``output`` config section; one-sentence ConfigError for a bad value."""
    output = output or {}
    formats = output.get("figure_formats", list(DEFAULT_FORMATS))
    if isinstance(formats, str):
        formats = [formats]
    try:
        formats = [str(f).lower().lstrip(".") for f in formats]
    except TypeError:
        raise ConfigError(f"output.figure_formats={formats!r} must be a list of formats; valid: "
                          f"{choices(FORMATS)}") from None
    for name in formats:
        if name not in FORMATS:
            raise ConfigError(f"output.figure_formats has {name!r}, which gyrolab does not write; valid: "
                              f"{choices(FORMATS)}")
    if not formats:
        raise ConfigError(f"output.figure_formats is empty; give at least one of {choices(FORMATS)} "
                          "(or output.figures=false for no figures)")
    dpi = output.get("dpi", DEFAULT_DPI)
    if isinstance(dpi, bool) or not isinstance(dpi, (int, float)) or not 20 <= dpi <= 2400:
        raise ConfigError(f"output.dpi={dpi!r} must be a number of dots per inch from 20 to 2400")
    return tuple(dict.fromkeys(formats)), int(dpi)
