"""``gyrolab experiment=stability_map``: the chaos indicator over a grid θ0 × r0 as one resumable batch.

The grid (``stability_map.theta0``/``r0`` ranges, ``n_theta0`` × ``n_r0`` points, or ``batch.points`` as a
square grid) is run by ``gyrolab.sweep.batch.run_batch`` with ``batch.output=indicator``
(``gyrolab.physics.chaos.indicator_outputs``: MEGNO and the max nutation deviation per point) into
``stability_map.nc`` with dimensions (``theta0``, ``r0``); rerunning the same command in the same run
directory continues a killed map. The figure is ``gyrolab.figures.stability_map.draw``.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
from omegaconf import DictConfig, OmegaConf

from gyrolab.errors import ConfigError, as_number
from gyrolab.sweep.grid import Dim

log = logging.getLogger(__name__)


def grid(cfg: DictConfig) -> list[Dim]:
    """The (θ0, r0) grid of the config as two swept dimensions (evenly spaced, both ends included)."""
    settings = cfg.stability_map
    points = (cfg.get("batch") or {}).get("points")
    if points is not None:
        if isinstance(points, bool) or not isinstance(points, int) or points < 1:
            raise ConfigError(f"batch.points={points!r} must be a positive integer (the map's number of points)")
        n_theta = n_r = max(1, round(math.sqrt(points)))
    else:
        n_theta, n_r = settings.n_theta0, settings.n_r0
    dims = []
    for key, span, n in (("theta0", settings.theta0, n_theta), ("r0", settings.r0, n_r)):
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ConfigError(f"stability_map.n_{key}={n!r} must be a positive integer")
        if len(span) != 2:
            raise ConfigError(f"stability_map.{key}={list(span)!r} must be [first, last]")
        first, last = (as_number(v, f"stability_map.{key}") for v in span)
        values = np.linspace(first, last, n) if n > 1 else np.array([first])
        dims.append(Dim(f"initial.{key}", tuple(repr(float(v)) for v in values), tuple(float(v) for v in values)))
    return dims


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    from gyrolab.sweep.batch import run_batch

    plain = OmegaConf.to_container(cfg, resolve=True)
    plain.pop("hydra", None)
    path = Path(out_dir) / cfg.stability_map.file
    run_batch([], grid(cfg), path, plain=plain, lock=False)   # the app holds the run directory's lock
    written = [path]
    if cfg.output.get("figures", True):
        written += _figure(path, out_dir, cfg)
    return written


def _figure(path: Path, out_dir: Path, cfg: DictConfig) -> list[Path]:
    # TODO(lead): gyrolab.figures.stability_map is H4's (branch chaos); this runs once it is merged.
    try:
        from gyrolab.figures import stability_map as figure
    except ImportError:
        log.warning("the stability-map figure needs gyrolab.figures.stability_map, which this install lacks; "
                    "%s is written", path)
        return []
    import xarray as xr

    target = Path(out_dir) / "figures" / "stability_map.png"
    with xr.open_dataset(path) as ds:
        figure.draw(ds, target)
    return [target]
