"""``gyrolab reproduce PATH/sweep.nc`` for a batch: the plan rebuilt from the stored ``config`` and ``batch_grid``, the
chunks holding the chosen points (``--points``) run again in this process, and those points compared bit for bit.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import OmegaConf

from gyrolab.batch.plan import POINT, Dim, make_plan
from gyrolab.batch.runner import Settings, chunk_size, chunks, run_plan
from gyrolab.batch.sweep import check_integrator
from gyrolab.engine.safety import check_stored_config
from gyrolab.errors import ConfigError, shorten
from gyrolab.sweep.grid import Grid, dim_names
from gyrolab.sweep.reproduce import Comparison, compare, parse_points

log = logging.getLogger("gyrolab.batch")


def is_batch(stored: xr.Dataset) -> bool:
    """Whether a dataset is a batch's ``sweep.nc`` (``gyrolab batch``)."""
    return stored.attrs.get("sweep_launcher") == "batch" and "batch_grid" in stored.attrs


def reproduce_batch(path: Path, stored: xr.Dataset, points: str | None = None) -> tuple[Comparison, list[str]]:
    """(the comparison of the chosen points, the report's head lines) of rerunning the batch stored at ``path``."""
    where = f"{path}'s config attribute"
    plain = OmegaConf.to_container(check_stored_config(stored.attrs["config"], where), resolve=True)
    if points is not None and "n_points" in stored.attrs:   # a mistyped --points before the plan is built
        parse_points(points, int(stored.attrs["n_points"]))
    plan = make_plan([], _dims(stored, plain), plain=plain)
    settings = dataclasses.replace(Settings.from_config(plain.get("batch")), scheduler=None,
                                   scheduler_source="gyrolab reproduce (this process)")
    check_integrator(plan, settings)
    if any(stored.sizes.get(d) != n for d, n in zip(plan.grid_dims, plan.shape)):
        raise ConfigError(f"{path} does not hold the grid its batch_grid attribute describes; give a sweep.nc that "
                          "gyrolab batch wrote, unchanged")
    chosen = parse_points(points, plan.size)
    size = chunk_size(plan, settings)
    blocks = chunks(plan.shape, size)
    selected = np.arange(plan.size) if chosen is None else np.asarray(chosen)
    needed = {i for i, block in enumerate(blocks)
              if np.any((selected >= block.start) & (selected < block.stop))}
    same_batch = stored.attrs.get("batch_identity") == plan.identity(size)
    head = [f"reproducing {path} ({stored.attrs.get('title', '?')}; {plan.integrator_class.name}): "
            f"{'all ' if chosen is None else ''}{selected.size} of {plan.size} points, in {len(needed)} of "
            f"{len(blocks)} chunks of ≤ {size}",
            f"  batch identity {'the same' if same_batch else 'differs'} (stored "
            f"{stored.attrs.get('batch_identity', '?')}, now {plan.identity(size)})"]
    with tempfile.TemporaryDirectory(prefix="gyrolab-reproduce-") as tmp:
        rerun_path = Path(tmp) / "sweep.nc"
        run_plan(plan, rerun_path, settings, only=needed)
        new = xr.load_dataset(rerun_path, decode_times=False, decode_timedelta=False)
    if chosen is None:
        return compare(stored, new), head
    return compare(_points_of(stored, plan.grid_dims, selected), _points_of(new, plan.grid_dims, selected)), head


def _dims(stored: xr.Dataset, plain: dict[str, Any]) -> list[Dim]:
    """The swept keys as the batch's command line gave them: a grid's from ``batch_grid`` (key and values as
    typed), a zipped list's from the ``point`` coordinates; a points file's are read from the file again."""
    try:
        grid = json.loads(stored.attrs["batch_grid"])
    except (TypeError, ValueError):
        grid = None
    if not isinstance(grid, list):
        raise ConfigError(f"batch_grid={shorten(repr(stored.attrs.get('batch_grid')))} is not the list gyrolab "
                          "writes; give a sweep.nc that gyrolab batch wrote, unchanged")
    if (plain.get("batch") or {}).get("points_file") is not None:
        return []   # make_plan reads the file (its SHA-256 is part of the identity compared in the report)
    if all(isinstance(entry, str) for entry in grid):   # a zipped list: the values are the point coordinates
        stubs = [Dim(key, (), ()) for key in grid]
        labels = []
        for key, name in zip(grid, dim_names(stubs)):
            if name not in stored.coords or stored[name].dims != (POINT,):
                raise ConfigError(f"the batch's {key} values are not in its coordinate {name!r}; give a sweep.nc that "
                                  "gyrolab batch wrote, unchanged")
            labels.append((key, [_label(v.item()) for v in stored[name].values]))
    else:
        labels = [(entry[0], [str(label) for label in entry[1]]) for entry in grid]
    dims = []
    for key, values in labels:   # choice(...): a sweep even with one value, parsed as the command line's was
        dims.extend(Grid.from_overrides([f"{key}=choice({','.join(values)})"], repeats=True).dims)
    return dims


def _label(value: Any) -> str:
    """A zipped point's value as it was most likely typed (2.0 as 2: the identity counts the typed labels)."""
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return repr(value) if isinstance(value, float) else str(value)


def _points_of(ds: xr.Dataset, grid_dims: Sequence[str], selected: np.ndarray) -> xr.Dataset:
    """The chosen points (flat C-order numbers) of every variable over the grid, along one ``point`` dimension;
    the variables not over the grid as they are."""
    out = {}
    for name, var in ds.data_vars.items():
        if not set(grid_dims) <= set(var.dims):
            out[name] = var
            continue
        rest = [d for d in var.dims if d not in grid_dims]
        values = var.transpose(*grid_dims, *rest).values
        flat = values.reshape((-1, *values.shape[len(grid_dims):]))[selected]
        out[name] = xr.DataArray(flat, dims=("selected_point", *rest), attrs=var.attrs)
    return xr.Dataset(out, coords={"selected_point": selected}, attrs=ds.attrs)
