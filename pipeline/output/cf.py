"""CF-1.8 conventions for every dataset gyrolab writes (checked by compliance-checker's ``cf:1.8`` suite).

``conform(ds, title, source)`` is the last step of every dataset builder (run, regime run, sweep, experiments): it
makes the netCDF file a CF-1.8 file without changing what the dataset holds (global attributes, coordinates
without ``_FillValue``, text coordinates as characters, 32-bit integers, no ``standard_name: time`` without an
epoch, a ``long_name`` everywhere; each with its CF section: docs/datasets.md, "Conventions common to every
dataset" and "The expected CF finding"). ``unit_attributes(body)`` gives the machine-readable scales of a body's
model units.
"""

from __future__ import annotations

import logging
import math
import re
from datetime import datetime, timezone
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.output.provenance import gyrolab_version, provenance

log = logging.getLogger(__name__)

CONVENTIONS = "CF-1.8"
_SINCE = re.compile(r"^\s*\S+\s+since\s+\S")
_INT32 = np.iinfo(np.int32)


def now_iso() -> str:
    """The current UTC time in ISO 8601, to the second (``date_created``)."""
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def conform(ds: xr.Dataset, title: str | None = None, source: str = "") -> xr.Dataset:
    """Make ``ds`` a CF-1.8 dataset in place (see the module docstring) and return it.

    ``title`` is used only when ``ds`` has none; ``source`` says what made the file (``history``).
    """
    for name in list(ds.variables):
        _conform_variable(ds, name)
    created = now_iso()
    ds.attrs["Conventions"] = CONVENTIONS
    ds.attrs["title"] = ds.attrs.get("title") or title or "gyrolab dataset"
    ds.attrs["date_created"] = created
    ds.attrs["history"] = f"{created} written by gyrolab {gyrolab_version()}" + (f": {source}" if source else "")
    return ds


def experiment_dataset(ds: xr.Dataset, cfg: DictConfig, source: str) -> xr.Dataset:
    """An experiment's ``ds`` with its resolved config and the provenance as its last attributes, made CF."""
    ds.attrs.update({"config": OmegaConf.to_yaml(cfg, resolve=True), **provenance()})
    return conform(ds, source=source)


def _conform_variable(ds: xr.Dataset, name: Any) -> None:
    """One variable made CF: 64-bit integers narrowed (netCDF3-safe), a time standard_name only with a "since"
    unit, a long_name always, coordinates without fill values (text as characters)."""
    variable = ds.variables[name]
    if variable.dtype.kind in "iu" and variable.dtype.itemsize > 4:
        values = variable.values
        fits = not values.size or (values.min() >= _INT32.min and values.max() <= _INT32.max)
        ds[name] = variable.astype(np.int32 if fits else np.float64)
        variable = ds.variables[name]
    attrs = variable.attrs
    if attrs.get("standard_name") == "time" and not _SINCE.match(str(attrs.get("units", ""))):
        del attrs["standard_name"]
    if not attrs.get("long_name") and not attrs.get("standard_name"):
        log.info("dataset variable %r has no long_name; its name stands in", name)
        attrs["long_name"] = str(name)
    if name in ds.coords:
        if name == "time":  # elapsed model time is the T axis (no calendar claimed: see the docstring)
            attrs.setdefault("axis", "T")
        variable.encoding["_FillValue"] = None
        kind = variable.dtype.kind
        if kind == "U" or (kind == "O" and all(isinstance(v, str) for v in variable.values.ravel())):  # text
            variable.encoding["dtype"] = "S1"


def unit_attributes(body: Any) -> dict[str, Any]:
    """Machine-readable model units of ``body`` (netCDF-safe global attributes): ``time_unit``, ``rate_unit``,
    ``energy_unit``, ``time_unit_description`` and, for an SI fixed-point body, the papers' scales ``time_scale_s``
    = 1/c and ``energy_scale_J`` = C c² (docs/datasets.md, "Conventions common to every dataset")."""
    time_label, rate_label = body.time_label, body.rate_label
    attrs: dict[str, Any] = {"time_unit": time_label, "rate_unit": rate_label}
    nondim = body.nondimensional() if hasattr(body, "nondimensional") else {}
    c2 = nondim.get("c2")
    if body.units == "si":
        attrs["energy_unit"] = "J"
        if c2 is not None and c2 > 0:
            attrs["time_scale_s"] = 1.0 / math.sqrt(c2)
            attrs["energy_scale_J"] = float(body.inertia[2]) * c2
            attrs["time_unit_description"] = ("model time in s; the papers' nondimensional time is t c with "
                                              "c = sqrt(M g l / C) = 1/time_scale_s, their energy E/(C c2) "
                                              "= E/energy_scale_J")
        else:
            attrs["time_unit_description"] = "model time in s"
    elif time_label == "1/c":
        attrs["energy_unit"] = "C c2"
        attrs["time_unit_description"] = ("nondimensional: time in units of 1/c, c = sqrt(M g l / C), energy in "
                                          "units of C c2 (scale-free: no SI scale)")
    else:  # the orbiting gyrostat: the orbit's rate is the unit of rate when it is 1
        rate = "Ω" if rate_label == "Ω" else "W"
        attrs["energy_unit"] = f"I0 {rate}2"
        attrs["time_unit_description"] = (f"nondimensional: time in units of {time_label}, energy in units of "
                                          f"I0 {rate}2 with I0 the unit of body.inertia"
                                          + ("" if rate == "Ω" else " and W the unit of body.orbit_rate")
                                          + " (scale-free: no SI scale)")
    return attrs
