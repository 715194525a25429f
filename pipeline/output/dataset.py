"""The run dataset: trajectory, invariants and Euler angles with CF metadata and provenance. Attributes hold only
netCDF-safe values: the resolved config is one YAML string, so a run can be rebuilt from its own dataset
(``Scene.from_config(OmegaConf.create(ds.attrs["config"]))``).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np
import pandas as pd
import xarray as xr
from xarray.indexes import PandasIndex

from gyrolab.compat import direct_dataset, install_dask_free_writes
from gyrolab.contracts.integrator import Integrator, Solution
from gyrolab.output.atomic import atomic_path
from gyrolab.output.cf import conform, unit_attributes
from gyrolab.output.invariant_check import max_drift, violated_invariants, violation_sentence
from gyrolab.output.provenance import provenance

if TYPE_CHECKING:
    from gyrolab.engine.scene import Scene
    from gyrolab.physics.body import ModelUnits

log = logging.getLogger(__name__)

# a run dataset holds numpy arrays: building and writing it need not import Dask (~0.4 s when it is installed)
install_dask_free_writes()

#: labels of the ``frame_axis`` dimension (the orbiting gyrostat's orbital and inertial frames)
FRAME_AXES = ("x_radial", "y_along_track", "z_normal")
#: the label coordinates of run datasets with their indexes, built once (a dataset copies them: ~0.1 ms a run less)
LABELS = xr.Coordinates({
    "axis": ("axis", np.array(["x", "y", "z"]), {"units": "1", "long_name": "principal body axis"}),
    "frame_axis": ("frame_axis", np.array(FRAME_AXES), {
        "units": "1", "long_name": "frame axis: orbital (radial, along-track, orbit normal) or inertial (X, Y, Z: the "
                                   "orbital axes at t = 0)"})})


def build_dataset(scene: Scene, solution: Solution, add: Callable[[dict[str, xr.Variable]], tuple[
        dict[str, xr.Variable], dict[str, Any]]] | None = None, integrator: Integrator | None = None) -> xr.Dataset:
    """The run dataset of ``scene`` from ``solution``; ``add`` (given the trajectory's variables) returns more
    variables and attributes to put in while it is assembled (``Scene.run``'s error estimate; cheaper than merging
    into a built dataset). ``integrator``: the one that ran, when not the scene's own (``auto`` run again)."""
    system, integrator = scene.system, integrator or scene.integrator
    # each state component contiguous (column-major): the derived variables' arithmetic runs faster, same values
    variables = system.variables(solution.t, np.asfortranarray(solution.y))
    invariants = system.invariants  # each one's (first, largest, smallest) value: its drift and the check read them
    found = {k: (float(v[0]), float(v.max()), float(v.min())) for k in invariants
             for v in [np.asarray(variables[k].values, dtype=float)]}
    for name, values in found.items():
        variables[name].attrs["max_abs_drift"] = max_drift(*values)
    added, added_attrs = add(variables) if add is not None else ({}, {})
    variables.update(added)
    ds = _assembled(scene, variables, solution.t)
    before, after = scene.dataset_attributes  # the scene's own, once per scene
    ds.attrs.update({**before, **integrator.attributes(), **solution.stats.attributes(), **after, **added_attrs})
    flag_violated_invariants(ds, invariants, integrator.adaptive, found, float(solution.t[-1] - solution.t[0]))
    return conform(ds, source=f"run of system {system.name} with integrator {integrator.name}")


def _assembled(scene: Scene, variables: dict[str, xr.Variable], t: np.ndarray) -> xr.Dataset:
    """The dataset of ``variables`` at output times ``t``. xarray's constructor aligns and merges (~0.25 ms on the
    reference scene, ~2x that after other work has taken the caches): the scene keeps its last results' coordinates
    (their variables and indexes), and a run with the same variables at the same times (bit for bit) is assembled from
    them and its own variables (``gyrolab.compat.direct_dataset``: ~0.01 ms; a template's ``copy(data=...)`` took
    ~0.1)."""
    t = np.asarray(t)
    layout = [(t.dtype, t.shape, t.tobytes())] + [(k, v.dims, v.shape, v.dtype) for k, v in variables.items()]
    for kept, (order, coords, indexes, sizes) in scene.dataset_layouts:
        if kept == layout:  # (each coordinate's variable copied: its attributes and encoding are the dataset's own)
            return direct_dataset({name: coords[name].copy(deep=False) if name in coords else variables[name]
                                   for name in order}, set(coords), sizes, indexes)
    labels = ["axis"] + [name for name in ("frame_axis",) if any(name in v.dims for v in variables.values())]
    time = PandasIndex(pd.Index(t), "time")  # given with its index: xarray builds no index for the labels
    coords = xr.Coordinates({**time.create_variables({"time": xr.Variable("time", t, time_attributes(
        scene.system.body))}), **{name: LABELS.variables[name] for name in labels}},
                            indexes={"time": time, **{name: LABELS.xindexes[name] for name in labels}})
    ds = xr.Dataset(variables, coords=coords)
    kept = (list(ds.variables), {name: ds.variables[name].copy(deep=False) for name in ds.coords}, dict(ds.xindexes),
            dict(ds.sizes))
    scene.dataset_layouts[:] = [(layout, kept), *scene.dataset_layouts[:3]]  # a few
    return ds


def flag_violated_invariants(ds: xr.Dataset, invariants: tuple[str, ...], adaptive: bool,
                             seen: dict[str, tuple[float, float, float]], span: float) -> None:
    """Flag each monitored invariant whose drift the integration error does not explain (``invariant_check``; ``seen``:
    their extremes): a warning, ``invariant_check = "violated"`` and a ``comment`` on its variable, its name in the
    attribute ``violated_invariants`` (the figures do not draw it as conserved)."""
    found = violated_invariants(seen, invariants, ds.attrs, adaptive, span)
    for name, (drift, allowed) in found.items():
        sentence = violation_sentence(name, drift, allowed)
        log.warning("%s", sentence)
        ds[name].attrs.update({"invariant_check": "violated", "invariant_allowed_drift": allowed,
                               "comment": sentence})
    if found:
        ds.attrs["violated_invariants"] = " ".join(found)


def scene_attributes(scene: Scene) -> tuple[dict[str, Any], dict[str, Any]]:
    """The run dataset's global attributes that depend on the scene alone (those before the integrator's record,
    those after it), computed once per scene and shared by its runs' datasets: arrays among them are read-only."""
    system = scene.system
    before: dict[str, Any] = {
        "title": system.title(),
        "config": scene.config_yaml,
        "monitored_invariants": " ".join(system.invariants),
        "integrator": scene.integrator.name,
    }
    before.update(provenance())
    before.update(system.attributes())
    after = unit_attributes(system.body)
    after.update(scene.sampling_attributes())
    for part in (before, after):
        for key, value in part.items():
            if isinstance(value, np.ndarray):
                part[key] = value = value.copy()  # not the system's own array (its initial state, say)
                value.flags.writeable = False
    return before, after


def time_attributes(body: ModelUnits) -> dict[str, str]:
    """CF attributes of a time coordinate in ``body``'s model units: elapsed time, not a calendar date, so the
    T axis without ``standard_name: time`` (docs/datasets.md, "The expected CF finding")."""
    return {"units": body.time_unit, "long_name": f"time [{body.time_label}]", "axis": "T"}


def write_dataset(ds: xr.Dataset, path: Path) -> Path:
    """Write ``ds`` to ``path`` atomically (``gyrolab.output.atomic``: a failed write is one ``OutputError``
    sentence naming the file and the reason, and leaves no file at ``path``)."""
    path = Path(path)
    with atomic_path(path, expected_bytes=int(ds.nbytes)) as tmp:
        ds.to_netcdf(tmp, engine="netcdf4")
    return path
