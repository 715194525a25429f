"""Datasets given to ``--plot`` and ``--reproduce`` read as what they claim to be: gyrolab's netCDF files.

A path may be anything a user can type: a text file named ``run.nc``, an empty file, a
directory, a device, a loop of symbolic links, someone else's netCDF file. Each is one
ConfigError sentence naming the path and what was expected; the file's contents are never
echoed (a reader's message quotes at most a variable's name).
"""

from __future__ import annotations

import os
import stat
import warnings
from pathlib import Path

import xarray as xr

from gyrolab.errors import ConfigError, shorten

#: what a figure module or a rerun raises when a dataset lacks what gyrolab's datasets have
FOREIGN_ERRORS = (LookupError, ValueError, TypeError, AttributeError, ArithmeticError)


def load_dataset(path: str | os.PathLike[str], expected: str, **options) -> xr.Dataset:
    """The netCDF dataset at ``path``, loaded; ConfigError (one sentence) when it is not a readable netCDF file."""
    path = Path(path)
    where = shorten(str(path))
    try:
        mode = os.stat(path).st_mode
    except OSError as error:
        reason = "a loop of symbolic links" if error.errno == 40 else (error.strerror or "cannot be read")
        raise ConfigError(f"cannot read {where!r} ({reason}); give {expected}") from None
    if not stat.S_ISREG(mode):
        raise ConfigError(f"{where!r} is not a regular file; give {expected}")
    if os.stat(path).st_size == 0:
        raise ConfigError(f"{where!r} is empty; give {expected}")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # xarray's "fails while guessing" warnings are the same news
            return xr.load_dataset(path, **options)
    except Exception:  # noqa: BLE001 - any reader failure means the same thing to the user
        raise ConfigError(f"cannot read {where!r} as a netCDF dataset (it is not a netCDF file gyrolab can read); "
                          f"give {expected}") from None


def not_gyrolabs(path: str | os.PathLike[str], error: BaseException, expected: str) -> ConfigError:
    """The sentence for a readable dataset that lacks what gyrolab's have (``error``: what using it raised)."""
    missing = ""
    if isinstance(error, KeyError) and error.args:
        name = str(error.args[0]).split("'")
        missing = f" (it has no {shorten(name[1] if len(name) > 2 else name[0], 40)!r})"
    return ConfigError(f"{shorten(str(path))!r} is not a dataset gyrolab wrote, or it was edited{missing}; "
                       f"give {expected}")
