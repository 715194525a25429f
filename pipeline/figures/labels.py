"""Notation and units of axis labels, read from a dataset's CF attributes.

Nondimensional bodies: t in units of 1/c, ω in units of c, energies in C c², angular momenta in C c
(the orbiting gyrostat: 1/Ω, Ω, C Ω², C Ω); SI bodies: SI units. A dimensionless quantity gets no
unit. γ's components are γ₁, γ₂, γ₃ (along the body axes x, y, z), never γ, γ′, γ″.
"""

from __future__ import annotations

import re

import xarray as xr

#: CF units string -> how a label writes it
SI = {"s": "s", "rad s-1": "rad/s", "J": "J", "N m": "N m", "kg m2 s-1": "kg m²/s", "rad": "rad"}
#: the kind of a model quantity -> its nondimensional unit, in terms of the scale rate (c or Ω)
KINDS = {"time": "1/{s}", "rate": "{s}", "energy": "C {s}²", "momentum": "C {s}", "torque": "C {s}²"}
GAMMA = ("γ₁", "γ₂", "γ₃")
OMEGA = ("p", "q", "r")


def scale_rate(ds: xr.Dataset) -> str:
    """The rate that makes the dataset's model units (c for a heavy body, Ω for the orbiting gyrostat)."""
    rate = str(ds.attrs.get("rate_unit", ""))  # the machine-readable model unit (gyrolab.output.cf), when present
    if rate and rate not in ("rad/s", "rad s-1"):
        return rate
    if "time" in ds.coords:
        found = re.search(r"\[1/([^\]]+)\]", ds["time"].attrs.get("long_name", ""))
        if found:
            return found.group(1)
    return "Ω" if ds.attrs.get("system") == "orbiting_gyrostat" else "c"


def unit(ds: xr.Dataset, units: str | None, kind: str) -> str:
    """The unit text ('s', 'units of 1/c', '' when dimensionless) of a quantity of ``kind`` (time, rate, energy, momentum, torque, angle, 1)."""
    if units in SI:
        return SI[units]
    if kind in KINDS and units in (None, "1", ""):
        stored = str(ds.attrs.get("energy_unit", "")) if kind == "energy" else ""
        if stored and stored != "J":  # e.g. "C c2", "I0 Ω2" (gyrolab.output.cf)
            return "units of " + stored.replace("2", "²")
        return "units of " + KINDS[kind].format(s=scale_rate(ds))
    return "" if units in (None, "1", "") else units


def label(name: str, unit_text: str) -> str:
    """'name (unit)', or the name alone for a dimensionless quantity."""
    return f"{name} ({unit_text})" if unit_text else name


def time_label(ds: xr.Dataset, symbol: str = "t") -> str:
    return label(f"time {symbol}", unit(ds, ds["time"].attrs.get("units"), "time"))

