"""What the figures say about an integrator's work, asked of the integrator, never read from a table of names.

A run stores its integrator's ``evaluation_label`` (what ``integrator_nfev`` counts where that is not right-hand-side
calls: "Taylor series evaluations") as the attribute ``integrator_nfev_counts``; a sweep keeps it as a global
attribute or a per-job variable. Datasets written before that attribute existed are answered by the registered
integrator class of that name (``""``: right-hand-side calls, or an integrator no longer installed).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts import registry
from gyrolab.contracts.integrator import CHOOSES_METHOD, NFEV_COUNTS_ATTRIBUTE
from gyrolab.errors import GyrolabError


def integrator_class(name: str) -> Any:
    """The registered integrator class called ``name``, or None (unknown, or its package fails to import)."""
    try:
        return registry.load("integrator", name)
    except (GyrolabError, ImportError, AttributeError):
        return None


def nfev_counts(name: str) -> str:
    """What integrator ``name``'s evaluation count counts where it is not right-hand-side calls ('' otherwise)."""
    cls = integrator_class(name)
    return (getattr(cls, "evaluation_label", None) or "") if cls is not None else ""


def chooses_method(name: str) -> bool:
    """Whether integrator ``name`` chooses its own method (its runs include that choice's pilot)."""
    cls = integrator_class(name)
    return bool(cls is not None and cls.supports(CHOOSES_METHOD))


def nfev_notes(ds: xr.Dataset) -> dict[str, str]:
    """Integrator name -> what its ``integrator_nfev`` counts, for the runs of ``ds`` whose count is not
    right-hand-side calls (the runs' own record when the dataset has it, else the integrator classes)."""
    names = _run_attribute(ds, "integrator")
    if names is None:
        return {}
    labels = _run_attribute(ds, NFEV_COUNTS_ATTRIBUTE)
    if labels is None:   # written before runs recorded it (or no run's count needs a note): ask the classes
        notes = {str(n): nfev_counts(str(n)) for n in np.unique(names.values.astype(str))}
    else:
        names, labels = xr.broadcast(names, labels)
        notes = {str(n): str(label) for n, label in zip(names.values.ravel(), labels.values.ravel())}
    return {name: label for name, label in notes.items() if label and label != "nan"}


def _run_attribute(ds: xr.Dataset, key: str) -> xr.DataArray | None:
    """A run attribute over a dataset's runs: global (equal in every run), per run (``run_KEY`` or ``KEY``), or the
    swept coordinate ``KEY``."""
    if key in ds.attrs:
        return xr.DataArray(ds.attrs[key])
    return next((ds[name] for name in (f"run_{key}", key) if name in ds.variables), None)
