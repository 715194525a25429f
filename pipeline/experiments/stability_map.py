"""``gyrolab experiment=stability_map``: the chaos indicator over a grid θ0 × r0 as one resumable batch
(docs/batch.md, "experiment=stability_map"; docs/stability_map.md).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.engine.budget import check_points
from gyrolab.engine.safety import confined_output_path
from gyrolab.engine.scene import Scene
from gyrolab.errors import ConfigError, OutputError, as_number, shorten
from gyrolab.figures.redraw import draw_figures
from gyrolab.output.cf import conform

#: what the index dimensions of the Poincaré sections count (they have no coordinate: an index is all they are)
SECTION_DIMENSIONS = {
    "section_point_description": "dimension section_point: one entry per stability_map.sections initial condition "
                                 "[theta0, r0], in the config's order",
    "crossing_description": "dimension crossing: the upward crossings of the section by that point's trajectory, "
                            "in time order (NaN past its last crossing)",
}
from gyrolab.analysis.chaos import section_dataset
from gyrolab.batch.sweep import run_batch
from gyrolab.engine import schemas
from gyrolab.engine.schemas import Task
from gyrolab.output.dataset import write_dataset
from gyrolab.sweep.grid import Dim

log = logging.getLogger(__name__)


def grid(cfg: DictConfig) -> list[Dim]:
    """The (θ0, r0) grid of the config as two swept dimensions (evenly spaced, both ends included)."""
    settings = cfg.stability_map
    points = (cfg.get("batch") or {}).get("points")
    if points is not None:
        if isinstance(points, bool) or not isinstance(points, int) or points < 1:
            raise ConfigError(f"batch.points={points!r} must be a positive integer (the map's number of points)")
        check_points(points, f"batch.points={points}", allow_large=cfg.get("allow_large") is True)
        n_theta = n_r = max(1, round(math.sqrt(points)))
    else:
        n_theta, n_r = settings.n_theta0, settings.n_r0
    dims = []
    for key, span, n in (("theta0", settings.theta0, n_theta), ("r0", settings.r0, n_r)):
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ConfigError(f"stability_map.n_{key}={n!r} must be a positive integer")
        if points is None and key == "r0":
            check_points(float(n_theta) * n_r, f"stability_map.n_theta0={n_theta} × n_r0={n_r}",
                         allow_large=cfg.get("allow_large") is True)
        values = _axis_values(settings, key, span, n)
        dims.append(Dim(f"initial.{key}", tuple(repr(float(v)) for v in values), tuple(float(v) for v in values)))
    return dims


def _axis_values(settings: DictConfig, key: str, span: Any, n: int) -> np.ndarray:
    """The ``n`` values of axis ``key`` from ``span`` = [first, last], linear or log spaced; ConfigError if a
    setting is wrong."""
    if len(span) != 2:
        raise ConfigError(f"stability_map.{key}={list(span)!r} must be [first, last]")
    first, last = (as_number(v, f"stability_map.{key}") for v in span)
    if n > 1 and first == last:
        raise ConfigError(f"stability_map.{key}={list(span)!r} is one value, but n_{key}={n} points are asked; "
                          f"give [first, last] with first ≠ last, or n_{key}=1")
    spacing = settings.get(f"{key}_spacing", "linear")
    if spacing not in ("linear", "log") or (spacing == "log" and not 0 < first < last):
        raise ConfigError(f"stability_map.{key}_spacing={spacing!r} must be linear or log (log: 0 < first < last)")
    spaced = np.geomspace if spacing == "log" else np.linspace
    return spaced(first, last, n) if n > 1 else np.array([first])


TASK = Task("stability_map", reads=("batch",), section="stability_map", settings=schemas.StabilityMap).sets_all(
    ("initial.theta0", "initial.r0"),
    "the map's grid sets it, from stability_map.theta0, stability_map.r0 and their n_ and _spacing settings")


def check(cfg: DictConfig, out_dir: Path) -> None:
    """The refusals of :func:`run` that need no integration, made by the preflight before the run directory exists:
    the grid (its size against the budget) and the map's file name (inside the run directory)."""
    grid(cfg)
    confined_output_path(out_dir, cfg.stability_map.get("file"), "stability_map.file")
    sections = _sections(cfg)
    if sections:
        t_end = as_number(cfg.stability_map.get("section_time"), "stability_map.section_time")
        if not t_end > 0:
            raise ConfigError(f"stability_map.section_time={t_end!r} must be a positive time")
        for n, point in enumerate(sections):
            if isinstance(point, (str, bytes)) or not hasattr(point, "__len__") or len(point) != 2:
                raise ConfigError(f"stability_map.sections[{n}]={shorten(repr(point))} must be [theta0, r0]")
            for v in point:
                as_number(v, f"stability_map.sections[{n}]")


def _sections(cfg: DictConfig) -> list:
    """The Poincaré sections to draw: the config's, for the heavy body about a fixed point only (the section
    γ3 = const and its coordinates φ, r are that system's; another system's map has none, said once in the log)."""
    sections = list(cfg.stability_map.get("sections") or [])
    if sections and not str((cfg.get("system") or {}).get("_target_", "")).endswith(".FixedPoint"):
        log.info("stability map: Poincaré sections (γ3 = const) are drawn for the body about a fixed point only; "
                 "none for this system")
        return []
    return sections


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    plain = OmegaConf.to_container(cfg, resolve=True)
    plain.pop("hydra", None)
    path = confined_output_path(out_dir, cfg.stability_map.file, "stability_map.file")
    run_batch([], grid(cfg), path, plain=plain, lock=False)   # the app holds the run directory's lock
    sections = _sections(cfg)
    if sections:
        try:
            _add_sections(path, plain, sections,
                          as_number(cfg.stability_map.section_time, "stability_map.section_time"))
        except OutputError as error:   # a full disk: the map is complete on disk; the rerun adds the sections
            raise OutputError(f"{str(error).rstrip('.')}; the map itself is kept: free some space and rerun the "
                              "same command to add its Poincaré sections") from None
    with xr.open_dataset(path) as ds:
        return [path, *draw_figures("stability_map.nc", ds.load(), out_dir, cfg.get("output"))]


def _add_sections(path: Path, plain: dict, points: Sequence[Sequence[float]], t_end: float) -> None:
    """Poincaré sections of the chosen (θ0, r0) points, integrated by the chaos kernel with the map's step, added to
    the map's file (rewritten atomically; a rerun replaces them)."""
    if not t_end > 0:
        raise ConfigError(f"stability_map.section_time={t_end!r} must be a positive time")
    scenes = []
    for n, point in enumerate(points):
        if len(point) != 2:
            raise ConfigError(f"stability_map.sections[{n}]={list(point)!r} must be [theta0, r0]")
        cfg = OmegaConf.create(plain)
        cfg.initial.theta0, cfg.initial.r0 = (as_number(v, f"stability_map.sections[{n}]") for v in point)
        scenes.append(Scene.from_config(cfg))
    compiled = scenes[0].compiled_model
    step = as_number(plain["integrator"].get("step") or 0.01, "integrator.step")
    theta0, r0 = (np.array([float(p[k]) for p in points]) for k in (0, 1))
    with xr.open_dataset(path) as stored:
        ds = stored.drop_vars([v for v in stored.variables if str(v).startswith("section_")]).load()
    sections = section_dataset(compiled, np.stack([s.system.initial_state() for s in scenes]), theta0, r0, t_end,
                               step, np.stack([s.compiled_model.params for s in scenes]),
                               rate_units=ds.r0.attrs.get("units", "1"))
    # conform: the rewrite must stay CF-1.8 like the store's file (no _FillValue on the coordinates, history)
    merged = ds.merge(sections, combine_attrs="drop_conflicts")
    merged.attrs.update(SECTION_DIMENSIONS)
    write_dataset(conform(merged, source="Poincaré sections added"), path)
