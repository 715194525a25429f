"""Datasets gyrolab reads (``plot``, ``--animate``, ``reproduce``, ``aggregate``) read as what they claim to be:
gyrolab's netCDF files. Every reader goes through ``load_dataset``.

Anything else a user can type (a text file named ``run.nc``, a directory, a device, a loop of links, someone
else's netCDF file) is one ConfigError sentence naming the path and what was expected, never echoing the file's
contents. A dataset is untrusted input: its declared sizes are checked against what gyrolab writes and the memory
available before anything is read, and every variable along ``time`` (or ``sample``) must hold numbers.
"""

from __future__ import annotations

import math
import os
import stat
import warnings
from pathlib import Path

import xarray as xr

from gyrolab.errors import ConfigError, shorten
from gyrolab.output.atomic import _size
from gyrolab.output.trust import proc_number

#: what a figure module or a rerun raises when a dataset lacks what gyrolab's datasets have
FOREIGN_ERRORS = (LookupError, ValueError, TypeError, AttributeError, ArithmeticError)


def load_dataset(path: str | os.PathLike[str], expected: str, **options) -> xr.Dataset:
    """The netCDF dataset at ``path``, loaded; ConfigError (one sentence) when it is not a readable netCDF file."""
    path = Path(path)
    where = shorten(str(path))
    try:
        info = os.stat(path)
    except OSError as error:
        reason = "a loop of symbolic links" if error.errno == 40 else (error.strerror or "cannot be read")
        raise ConfigError(f"cannot read {where!r} ({reason}); give {expected}") from None
    if not stat.S_ISREG(info.st_mode):
        raise ConfigError(f"{where!r} is not a regular file; give {expected}")
    size = info.st_size
    if size == 0:
        raise ConfigError(f"{where!r} is empty; give {expected}")
    unreadable = ConfigError(f"cannot read {where!r} as a netCDF dataset (it is not a netCDF file gyrolab can read); "
                             f"give {expected}")
    try:
        declared = declared_bytes(path)
    except Exception:  # noqa: BLE001 - any reader failure means the same thing to the user
        raise unreadable from None
    check_declared(declared, size, where, expected)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # xarray's "fails while guessing" warnings are the same news
            ds = xr.load_dataset(path, **options)
    except Exception:  # noqa: BLE001 - any reader failure means the same thing to the user
        raise unreadable from None
    for name, variable in ds.variables.items():
        if {"time", "sample"} & set(variable.dims) and variable.dtype.kind not in "fiub":
            raise ConfigError(f"{where!r}: variable {shorten(str(name), 40)!r} holds "
                              f"{'text' if variable.dtype.kind in 'OSU' else variable.dtype.name} where gyrolab "
                              f"writes numbers; the dataset was edited; give {expected}")
    return ds


#: a dataset declaring more than this many times its file size (plus MARGIN_BYTES) was edited: gyrolab writes every
#: value it declares, uncompressed (HDF5 reads values never written as fill values: a small file could make any size)
SPARSE_FACTOR = 4
MARGIN_BYTES = 16 * 1024**2


def declared_bytes(path: Path) -> int:
    """The bytes the variables of the netCDF file ``path`` declare, from its header (nothing is read)."""
    import netCDF4  # start-up: netCDF4 only when a file is read

    total = 0
    with netCDF4.Dataset(path, "r") as nc:
        groups = [nc]
        while groups:
            group = groups.pop()
            groups.extend(group.groups.values())
            for variable in group.variables.values():
                itemsize = getattr(variable.dtype, "itemsize", 8) or 8   # text (vlen): one pointer per value
                total += math.prod(variable.shape) * itemsize
    return total


def check_declared(declared: int, size: int, where: str, expected: str) -> None:
    """ConfigError (naming the limit) when a dataset declares more data than its file holds or memory can take."""
    if declared > SPARSE_FACTOR * size + MARGIN_BYTES:
        raise ConfigError(f"{where!r} declares {_size(declared)} of data in a file of {_size(size)}; gyrolab stores "
                          f"every value it declares (at most {SPARSE_FACTOR}× the file's size), so the dataset was "
                          f"edited; give {expected}")
    available = proc_number("/proc/meminfo", "MemAvailable:")  # kB (Linux); elsewhere the limit is 4 GiB
    limit = available * 1024 // 2 if available is not None else 4 * 1024**3
    if declared > limit:
        raise ConfigError(f"{where!r} declares {_size(declared)} of data, more than the limit of {_size(limit)} "
                          f"(half the memory available); give {expected}, or read it on a larger machine")


RUN = "a run.nc that gyrolab wrote"


def load_run(path: str | os.PathLike[str]) -> xr.Dataset:
    """A run's dataset (``run.nc``) for ``reproduce`` and ``--animate``: one sentence for a sweep's or another file."""
    path = Path(path)
    ds = load_dataset(path, RUN, decode_times=False, decode_timedelta=False)
    if "config" not in ds.attrs and "job_status" in ds:
        raise ConfigError(f"{shorten(str(path))!r} is a sweep dataset, not a run; give one job's run.nc (sweep.nc's "
                          "job_dir variable names each job's directory)")
    if "config" not in ds.attrs:
        raise ConfigError(f"{shorten(str(path))!r} has no 'config' attribute; give {RUN}")
    return ds


def not_gyrolabs(path: str | os.PathLike[str], error: BaseException, expected: str) -> ConfigError:
    """The sentence for a readable dataset that lacks what gyrolab's have (``error``: what using it raised)."""
    missing = ""
    if isinstance(error, KeyError) and error.args:
        name = str(error.args[0]).split("'")
        missing = f" (it has no {shorten(name[1] if len(name) > 2 else name[0], 40)!r})"
    return ConfigError(f"{shorten(str(path))!r} is not a dataset gyrolab wrote, or it was edited{missing}; "
                       f"give {expected}")
