"""Summary figures of a sweep, drawn by ``gyrolab.figures.sweep`` (this module picks their formats).

The formats and dpi are the sweep's own ``output.figure_formats`` and ``output.dpi``, read from the
``multirun.yaml`` Hydra writes in the sweep directory (the defaults when there is none).
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import xarray as xr

from gyrolab.figures.options import figure_options
from gyrolab.figures.sweep import save_figures as draw
from gyrolab.output.user_yaml import stored_yaml_file


def save_sweep_figures(ds: xr.Dataset, directory: str | Path, formats: Iterable[str] | None = None,
                       dpi: int | None = None) -> list[Path]:
    """Draw the sweep's summary figures into ``directory`` (``<sweep dir>/figures``)."""
    directory = Path(directory)
    saved = directory.parent / "multirun.yaml"
    output = stored_yaml_file(saved).get("output") if saved.is_file() else None
    default_formats, default_dpi = figure_options(output)
    return draw(ds, directory, tuple(formats) if formats is not None else default_formats,
                dpi if dpi is not None else default_dpi)
