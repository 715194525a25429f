"""Writing an in-memory dataset without importing Dask only to learn that nothing in it is Dask's.

When Dask is installed (the ``cluster`` and ``test`` extras), xarray's ``to_netcdf`` imports it for any
dataset: its string coder asks whether a char array is a Dask array (``pycompat.array_type("dask")``,
which imports ``dask.array``, and ``utils.is_dask_collection``, which imports ``dask.base``), and it asks
Dask's scheduler whether to close the file after every write (``writers._get_netcdf_autoclose``) and
which write lock to take (``locks.get_write_lock``), which imports ``distributed``. That is ~0.43 CPU s
for the first file a process writes (``dask.array`` 0.33 s, ``distributed`` 0.1 s), more than a short
run itself and a fifth of a 20-job sweep's overhead.

:func:`install_dask_free_writes` puts a guard in front of each of the four that gives Dask's or xarray's
own answer without the import where the answer cannot depend on Dask, and asks otherwise:

* ``array_type("dask")`` while ``dask.array`` is not imported: no object can be an instance of its
  ``Array`` class, so there is no type to test against (``()``, xarray's answer without Dask);
* ``is_dask_collection(x)`` for an ``x`` without a ``__dask_graph__`` method: False (Dask's first test);
* autoclose for a dataset without chunks: False (xarray: ``have_chunks and ...``);
* the write lock while ``distributed`` is not imported (so no Dask client exists) and Dask's config
  names no scheduler: xarray's threaded lock (what it takes without Dask and under Dask's default).
  While Dask itself is not imported no Dask computation runs in this process, and the threaded lock
  is taken whatever a Dask config file might name: nothing Dask could contend for the file.

Once Dask is in use (a batch on a Dask scheduler, a chunked dataset), xarray decides as before. An
xarray without one of these functions keeps it unguarded.
"""

from __future__ import annotations

import sys
from typing import Any

_GUARD = "_gyrolab_scheduler_guard"


def install_dask_free_writes() -> bool:
    """Install the four guards (once per process); whether all four are in place."""
    from xarray.backends import locks, netCDF4_, writers
    from xarray.namedarray import pycompat, utils

    return all([
        _guard(pycompat, "_get_cached_duck_array_module", _no_dask_arrays_before_dask),
        _guard(utils, "is_dask_collection", _no_graph_no_collection),
        _guard(writers, "_get_netcdf_autoclose", _unchunked_autoclose),
        _guard(netCDF4_, "get_write_lock", lambda original: _lock_without_dask(original, locks)),
    ])


def _guard(module: Any, name: str, make: Any) -> bool:
    original = getattr(module, name, None)
    if original is None:
        return False
    if not getattr(original, _GUARD, False):
        guarded = make(original)
        setattr(guarded, _GUARD, True)
        guarded.__wrapped__ = original
        setattr(module, name, guarded)
    return True


class _DaskNotImported:
    """xarray's record of the ``dask`` duck-array module, asked before ``dask.array`` is imported: no type yet
    (nothing can be an instance of a class not loaded); anything else is xarray's own answer."""

    type: tuple = ()

    def __init__(self, original: Any) -> None:
        self._original = original

    def __getattr__(self, name: str) -> Any:
        return getattr(self._original("dask"), name)


def _no_dask_arrays_before_dask(original: Any) -> Any:
    def cached_duck_array_module(mod: Any) -> Any:
        if mod == "dask" and "dask.array" not in sys.modules:
            return _DaskNotImported(original)  # not cached: once dask.array is imported, xarray's record
        return original(mod)
    return cached_duck_array_module


def _no_graph_no_collection(original: Any) -> Any:
    def is_dask_collection(x: object) -> bool:
        if "dask" not in sys.modules and not callable(getattr(x, "__dask_graph__", None)):
            return False  # dask.base.is_dask_collection's answer for an object without a graph method
        return original(x)
    return is_dask_collection


def _unchunked_autoclose(original: Any) -> Any:
    def autoclose(dataset: Any, engine: Any) -> bool:
        if all(variable.chunks is None for variable in dataset.variables.values()):
            return False  # xarray's answer without chunks
        return original(dataset, engine)
    return autoclose


def _lock_without_dask(original: Any, locks: Any) -> Any:
    lock_maker = getattr(locks, "_get_lock_maker", None)

    def get_write_lock(key: str) -> Any:
        if lock_maker is None or "distributed" in sys.modules or _configured_scheduler():
            return original(key)
        return lock_maker(None)(key)  # xarray's lock without a Dask scheduler (= under Dask's default)
    return get_write_lock


def _configured_scheduler() -> bool:
    """Whether Dask, if imported, is configured with a scheduler (then xarray's lock follows it)."""
    dask = sys.modules.get("dask")
    config = getattr(dask, "config", None)
    return config is not None and bool(config.get("scheduler", None) or config.get("get", None))
