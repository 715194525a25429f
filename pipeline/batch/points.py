"""An explicit list of points from a CSV file (``batch.points_file=PATH``; docs/batch.md, "A list of points instead
of a grid"): the header names config keys, each row is one point; the file is read whole (its SHA-256 goes into the
batch's identity); any problem is one sentence (ConfigError), before anything is written.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from gyrolab.engine.config import MAX_MAGNITUDE
from gyrolab.errors import ConfigError, shorten
from gyrolab.sweep.grid import Dim


MAX_POINTS_FILE_BYTES = 256 * 1024**2


def read_points_file(path: str | Path, plain: dict[str, Any], sections: Sequence[str]) -> tuple[tuple[Dim, ...], str]:
    """(one Dim per column: its key and its value at every point, labels empty; the file's SHA-256)."""
    where = f"batch.points_file={shorten(str(path))}"
    try:
        file = Path(path).expanduser()
        if not file.is_file():
            raise IsADirectoryError(21, "not a regular file")
        if file.stat().st_size > MAX_POINTS_FILE_BYTES:
            raise ConfigError(f"{where} is larger than {MAX_POINTS_FILE_BYTES // 1024**2} MiB; a points file is a CSV "
                              "of numbers, one line per point")
        data = file.read_bytes()
        if b"\0" in data:
            raise UnicodeDecodeError("utf-8", data, 0, 1, "NUL byte")
        text = data.decode("utf-8-sig")
    except OSError as error:
        raise ConfigError(f"{where} cannot be read ({error.strerror or error}); give a CSV file whose header names "
                          "config keys and whose rows are points") from None
    except UnicodeDecodeError:
        raise ConfigError(f"{where} is not UTF-8 text; give a CSV file whose header names config keys") from None
    rows = [(number, row) for number, row in enumerate(csv.reader(io.StringIO(text)), start=1)
            if row and any(cell.strip() for cell in row)]
    if not rows:
        raise ConfigError(f"{where} is empty; its first line names config keys (e.g. initial.r0,body.a), each "
                          "further line is a point")
    keys = [cell.strip() for cell in rows[0][1]]
    for key in keys:
        _check_key(key, keys, plain, sections, where)
    if len(rows) == 1:
        raise ConfigError(f"{where} has a header but no points; add one line of values per point")
    columns: list[list[float]] = [[] for _ in keys]
    for number, row in rows[1:]:
        if len(row) != len(keys):
            raise ConfigError(f"{where}, line {number}: {len(row)} value{'s' * (len(row) != 1)}, but the header names "
                              f"{len(keys)} keys")
        for column, key, cell in zip(columns, keys, row):
            column.append(_number(cell, f"{where}, line {number}, {key}"))
    digest = hashlib.sha256(data).hexdigest()
    return tuple(Dim(key, (), tuple(column)) for key, column in zip(keys, columns)), digest


#: what a header cell or a value may look like to be quoted in a message: the file's other contents are never echoed
_QUOTABLE_KEY = re.compile(r"^[A-Za-z_][A-Za-z0-9_.]{0,79}$")
_QUOTABLE_VALUE = re.compile(r"^[0-9A-Za-z_.+-]{1,24}$")


def _check_key(key: str, keys: list[str], plain: dict[str, Any], sections: Sequence[str], where: str) -> None:
    column = repr(key) if _QUOTABLE_KEY.match(key) else f"{keys.index(key) + 1} (not a dotted key name)"
    if not key:
        raise ConfigError(f"{where}: the header has an empty column name; name a config key in every column")
    if keys.count(key) > 1:
        raise ConfigError(f"{where}: the header names {column} twice; give each key once")
    if not key.startswith(tuple(sections)):
        raise ConfigError(f"{where}: header column {column} is not a body, initial or force parameter (its first "
                          "line must name keys such as initial.r0,body.a); give a CSV file of points")
    node: Any = plain
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            raise ConfigError(f"{where}: header column {column} is not a key of this config (its forces included)")
        node = node[part]
    if isinstance(node, (dict, list)):
        raise ConfigError(f"{where}: header column {column} is a group of settings, not one number")


def _number(cell: str, where: str) -> float:
    try:
        value = float(cell.strip())
    except ValueError:
        shown = repr(cell.strip()) if _QUOTABLE_VALUE.match(cell.strip()) else "the value"
        raise ConfigError(f"{where}: {shown} is not a number") from None
    if not math.isfinite(value):
        raise ConfigError(f"{where}: the value is not a finite number")
    if abs(value) > MAX_MAGNITUDE:  # beyond it products of settings overflow
        raise ConfigError(f"{where}: the value is too large; gyrolab takes numbers up to {MAX_MAGNITUDE:.0e} in "
                          "magnitude")
    return value
