"""The run dataset: trajectory, invariants and Euler angles with CF metadata and provenance.

Attributes hold only netCDF-safe values (str, numbers, numeric arrays): the
resolved config is stored as one YAML string, so a run can be rebuilt from
its own dataset (``Scene.from_config(OmegaConf.create(ds.attrs["config"]))``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from gyrolab.contracts.integrator import Solution
from gyrolab.errors import ConfigError
from gyrolab.output.atomic import atomic_path
from gyrolab.output.provenance import provenance

if TYPE_CHECKING:
    from gyrolab.engine.scene import Scene


def build_dataset(scene: Scene, solution: Solution) -> xr.Dataset:
    system, integrator = scene.system, scene.integrator
    body = system.body
    variables = system.variables(solution.t, solution.y)
    for name in system.invariants:
        values = variables[name].values
        variables[name].attrs["max_abs_drift"] = float(np.max(np.abs(values - values[0])))
    coords = {
        "time": ("time", solution.t, {"units": body.time_unit, "long_name": f"time [{body.time_label}]",
                                      "standard_name": "time"}),
        "axis": ("axis", np.array(["x", "y", "z"]), {"units": "1", "long_name": "principal body axis"}),
    }
    ds = xr.Dataset(variables, coords=coords)
    attrs: dict[str, Any] = {
        "title": system.title(),
        "Conventions": "CF-1.8",
        "config": scene.config_yaml,
        "monitored_invariants": " ".join(system.invariants),
        "integrator": integrator.name,
    }
    attrs.update(provenance())
    attrs.update(system.attributes())
    attrs.update(integrator.attributes())
    attrs.update(solution.stats.attributes())
    ds.attrs.update(attrs)
    return ds


def write_dataset(ds: xr.Dataset, path: Path) -> Path:
    """Write ``ds`` to ``path`` atomically (``gyrolab.output.atomic``).

    A full disk, a quota or a file-size limit (which netCDF reports as "HDF error") is one
    ``OutputError`` naming the file and the reason, and leaves no file at ``path``.
    """
    path = Path(path)
    with atomic_path(path, expected_bytes=int(ds.nbytes)) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")
    return path
