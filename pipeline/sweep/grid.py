"""The grid of a multirun: one dimension per swept parameter, one job per grid point, built from the sweep's
overrides exactly as Hydra's basic sweeper builds its jobs (the Cartesian product, in command-line order, the last
parameter fastest), so job ``n`` is ``Grid.jobs[n]`` whichever launcher ran it.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import OverrideParseException

from gyrolab.engine.budget import check_sweep_size, sweep_points
from gyrolab.errors import ConfigError, shorten

#: jobs of a multirun (each its own directory and launch): beyond it, gyrolab batch is the tool
MAX_JOBS = 1_000_000


@dataclass(frozen=True)
class Dim:
    """A swept parameter: its override key, the values as typed on the command line, and parsed."""

    key: str
    labels: tuple[str, ...]
    values: tuple[Any, ...]

    def coordinate(self) -> np.ndarray:
        """Numbers stay numbers (float64, or int64 if all are integers); anything else is its label."""
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in self.values)
        if numbers:
            as_int = all(isinstance(v, int) for v in self.values)
            return np.array(self.values, dtype=np.int64 if as_int else np.float64)
        return np.array(self.labels, dtype=object)


@dataclass(frozen=True)
class Grid:
    dims: tuple[Dim, ...]
    jobs: tuple[tuple[str, ...], ...]       # overrides of job n, exactly as the job sees them
    index: tuple[tuple[int, ...], ...]      # grid position of job n

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(d.labels) for d in self.dims)

    @classmethod
    def from_overrides(cls, overrides: Sequence[str], *, repeats: bool = False, max_jobs: float | None = None) -> Grid:
        """ConfigError for a malformed override, a non-discrete sweep, a value given twice (unless ``repeats``: a
        batch's zipped keys), more than ``max_jobs`` jobs (default: the budget's points), counted unexpanded."""
        parser = OverridesParser.create()
        try:
            parsed = parser.parse_overrides(list(overrides))
        except OverrideParseException as error:
            raise ConfigError(f"malformed sweep override: {str(error).strip().splitlines()[0]}") from None
        n, named = sweep_points(parsed)
        if max_jobs is not None and n > max_jobs:
            raise ConfigError(f"{shorten(named)} makes {n:.3g} jobs, beyond the {max_jobs:.0e} jobs of a multirun "
                              "(one directory each); the sweep directory was edited, or run it with gyrolab batch")
        check_sweep_size(parsed)
        choices, typed = _choices(parsed, repeats)
        dims = tuple(Dim(key, tuple(c.split("=", 1)[1] for c in choices[key]), tuple(typed[key]))
                     for key in choices if key in typed)
        lists = list(choices.values())
        jobs = tuple(tuple(job) for job in itertools.product(*lists))
        swept = [i for i, key in enumerate(choices) if key in typed]
        index = tuple(tuple(position[i] for i in swept)
                      for position in itertools.product(*(range(len(values)) for values in lists)))
        return cls(dims=dims, jobs=jobs, index=index)


    @classmethod
    def from_hydra(cls, hydra_cfg: Mapping[str, Any]) -> Grid:
        """The grid of a multirun config's ``hydra`` node (sweeper params first, as the basic sweeper does); a
        stored one (``multirun.yaml``) is untrusted: plain overrides only, within the budget."""
        try:
            params = (hydra_cfg.get("sweeper") or {}).get("params") or {}
            task = hydra_cfg["overrides"]["task"]
            overrides = [f"{k}={v}" for k, v in params.items()] + [str(o) for o in task]
        except Exception:  # noqa: BLE001 - an edited multirun.yaml: any shape but the one Hydra writes
            raise ConfigError("the sweep's hydra.overrides.task and hydra.sweeper.params are not the lists Hydra "
                              "writes; multirun.yaml was edited") from None
        return cls.from_overrides(overrides, max_jobs=MAX_JOBS)


def dim_names(dims: Sequence[Dim], reserved: set[str] | frozenset[str] = frozenset()) -> tuple[str, ...]:
    """Each dimension named by its key's last part (``initial.theta0`` -> ``theta0``), the whole key with dots as
    underscores where two would share a name or it is ``reserved``, prefixed ``sweep_`` while it is still taken."""
    shorts = [d.key.rsplit(".", 1)[-1].lstrip("+~") for d in dims]
    names: list[str] = []
    for dim, short in zip(dims, shorts):
        name = short if shorts.count(short) == 1 and short not in reserved else dim.key.lstrip("+~").replace(".", "_")
        while name in reserved or name in names:
            name = f"sweep_{name}"
        names.append(name)
    return tuple(names)


def _choices(parsed: Sequence[Any], repeats: bool) -> tuple[dict[str, list[str]], dict[str, list[Any]]]:
    """(key -> its job overrides in first-seen order, as Hydra does; swept key -> its typed values); ConfigError
    for a sweep that is not discrete or, unless ``repeats``, gives a value twice."""
    choices: dict[str, list[str]] = {}
    typed: dict[str, list[Any]] = {}
    for o in parsed:
        key = o.get_key_element()
        if not o.is_sweep_override():
            choices[key] = [f"{key}={o.get_value_element_as_str()}"]
            typed.pop(key, None)
            continue
        if not o.is_discrete_sweep():
            raise ConfigError(f"{o.input_line!r} is not a list of values; the basic sweeper runs "
                              "discrete sweeps only (a,b,c or range(...) or choice(...))")
        labels = list(o.sweep_string_iterator())
        choices[key] = [f"{key}={label}" for label in labels]
        typed[key] = list(o.sweep_iterator())
        if not repeats:
            _refuse_repeats(key, labels, typed[key])
    return choices, typed


def _refuse_repeats(key: str, labels: list[str], values: list[Any]) -> None:
    seen: dict[str, str] = {}
    for label, value in zip(labels, values):
        marker = repr(float(value)) if isinstance(value, (int, float)) and not isinstance(value, bool) else label
        if marker in seen:
            raise ConfigError(f"{key} sweeps the value {label} twice (as {seen[marker]} and {label}); "
                              "give each value once")
        seen[marker] = label
