"""A batch's plan: the grid of points as arrays (initial states, compiled-model parameters), validated
(docs/batch.md, "How a grid becomes arrays": combos, the vectorised hook, and why validation stays exact).
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from omegaconf import OmegaConf

from gyrolab.batch.points import read_points_file
from gyrolab.engine import scene as scene_module
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene, body_and_forces, fastest_rate
from gyrolab.engine.unread import ACCURACY_IGNORED_ATTRIBUTE, ignored_accuracy
from gyrolab.errors import ConfigError, GyrolabError, require_finite
from gyrolab.sweep.grid import Dim, Grid, _refuse_repeats, dim_names
from gyrolab.output.cf import unit_attributes
from gyrolab.sweep.identity import canonical_config, job_code, plain_config

log = logging.getLogger("gyrolab.batch")

VARIABLE_SECTIONS = ("body.", "initial.", "force.")
PARAM_SECTIONS = ("body.", "force.")
#: the batch's settings that do not change its result (left out of its identity)
NOT_IN_IDENTITY = ("scheduler", "progress", "points_file")   # a points file by its contents, not its path
SCHEME = "gyrolab-batch-2"
#: the stored dimension of an explicit list of points (``batch.points_file``, ``batch.zip``)
POINT = "point"


@dataclass
class Plan:
    """Every point of the batch as arrays; point ``n`` is grid position ``np.unravel_index(n, shape)`` (a list of
    points: its n-th point)."""

    dims: tuple[Dim, ...]             # the swept keys (grid: its dimensions; a list: each key's value per point)
    names: tuple[str, ...]            # the swept keys' coordinate names in the stored dataset
    plain: dict[str, Any]             # the composed config (resolved, plain), swept keys at their first values
    base: dict[str, Any] | None       # the config of the first valid point (what a worker rebuilds), None: none
    times: np.ndarray
    y0: np.ndarray                    # (N, state size), NaN rows where a point failed
    combo: np.ndarray                 # (N,) int32: the point's combination of body/force values
    combo_values: list[dict[str, Any]]  # per combo: swept key -> value
    combo_params: np.ndarray          # (combos, n params): the compiled model's parameters, NaN rows if invalid
    error: np.ndarray                 # (N,) int32: index into ``messages``, -1 where the point is valid
    messages: list[str] = field(default_factory=list)
    #: the system's dataset attributes (``System.attributes``, unit attributes) equal for every point
    attributes: dict[str, Any] = field(default_factory=dict)
    #: None: a grid (the outer product of the swept values); else how the explicit list of points was given
    #: (``zip``, or ``points_file`` with the file's path and SHA-256): the stored dimension is then ``point``
    points: dict[str, str] | None = None
    #: per combination: the system the plan built for it (this process only; chunks run here reuse them)
    systems: dict[int, Any] = field(default_factory=dict, repr=False)

    @property
    def size(self) -> int:
        return int(self.y0.shape[0])

    @property
    def shape(self) -> tuple[int, ...]:
        """The stored grid's shape: one dimension per swept key, or (points,) for a list of points."""
        return (len(self.dims[0].values),) if self.points is not None else tuple(len(d.values) for d in self.dims)

    @property
    def grid_dims(self) -> tuple[str, ...]:
        """The stored dataset's per-point dimensions: the swept keys' names, or ``point``."""
        return (POINT,) if self.points is not None else self.names

    @property
    def valid(self) -> np.ndarray:
        return self.error < 0

    @cached_property
    def base_key(self) -> str:
        """The base config as canonical JSON (a worker's cache key for the scene it rebuilds)."""
        return json.dumps(self.base, sort_keys=True, default=str) if self.base is not None else ""

    @property
    def integrator_class(self) -> type:
        """The integrator plugin's class (what the batch asks for capabilities)."""
        node = OmegaConf.create(self.plain).integrator
        cls = scene_module._plugin_class("integrator", node, "integrator")
        if cls.__new__ is not object.__new__:
            # a plugin whose construction picks a class by its settings (taylor's integrator.precision): that class,
            # without running its __init__
            settings = {k: v for k, v in (self.plain.get("integrator") or {}).items() if not k.startswith("_")}
            return type(cls.__new__(cls, **settings))
        return cls

    def identity(self, chunk: int) -> str:
        """20 hex digits over the code it loads (``job_code``), the composed config (without the settings that do not
        change the result), the grid and the chunk size: the same command gives the same identity."""
        plain = copy.deepcopy(self.plain)
        for key in NOT_IN_IDENTITY:
            (plain.get("batch") or {}).pop(key, None)
        grid = [[d.key, list(d.labels)] for d in self.dims]
        if self.points is not None:   # a list: its kind, and a points file's contents (SHA-256)
            grid.append(sorted((k, v) for k, v in self.points.items() if k != "points_file"))
        text = "\n".join((SCHEME, job_code(plain), canonical_config(plain), json.dumps(grid), str(chunk)))
        return hashlib.sha256(text.encode()).hexdigest()[:20]


def split_overrides(overrides: Sequence[str]) -> tuple[list[str], list[Dim]]:
    """(the fixed overrides, the swept dimensions) of a command line, each override parsed as the multirun's grid
    parses it (``Grid.from_overrides``; a value given twice is refused by ``make_plan`` for a grid, not a zip)."""
    fixed, dims = [], []
    for override in overrides:
        grid = Grid.from_overrides([override], repeats=True)
        if grid.dims:
            dims.extend(grid.dims)
        else:
            fixed.append(override)
    keys = [d.key for d in dims]
    repeated = next((k for k in keys if keys.count(k) > 1), None)
    if repeated:
        raise ConfigError(f"{repeated} is swept twice; give each swept key once")
    for dim in dims:
        if not dim.key.lstrip("+~").startswith(VARIABLE_SECTIONS):
            raise ConfigError(f"a batch sweep varies body, initial and force parameters only, not {dim.key!r}; "
                              "sweep it with gyrolab -m instead")
    return fixed, dims


def make_plan(fixed: Sequence[str], dims: Sequence[Dim], *, plain: dict[str, Any] | None = None) -> Plan:
    """The plan of the swept keys ``dims`` over the config composed from ``fixed`` (or given as ``plain``): their
    grid, or the explicit list of points of ``batch.zip``/``batch.points_file``."""
    start = time.perf_counter()
    dims = tuple(dims)
    ignored = None
    if plain is None:
        first = [f"{d.key}={d.labels[0]}" for d in dims]
        composed = compose_config(list(fixed) + first)  # refuses an accuracy given and not read
        ignored = ignored_accuracy(composed, fixed)  # a config file's: said once, and recorded in sweep.nc
        plain = plain_config(composed)
    dims, points = _points(dims, plain)
    if points is None:
        shape = tuple(len(d.values) for d in dims)
        axes = [(list(d.values), codes.ravel()) for d, codes in zip(dims, np.indices(shape, dtype=np.int32))]
    else:
        shape = (len(dims[0].values),)
        axes = [_distinct(d) for d in dims]
    n_points = math.prod(shape)
    param_axes = [i for i, d in enumerate(dims) if _key(d).startswith(PARAM_SECTIONS)]
    initial_axes = [i for i, d in enumerate(dims) if not _key(d).startswith(PARAM_SECTIONS)]
    errors = _Errors(n_points)

    def values_of(n: int) -> dict[str, Any]:
        return {d.key: values[codes[n]] for d, (values, codes) in zip(dims, axes)}

    suspect = np.zeros(n_points, dtype=bool)   # a swept value that is not a finite number: the single run decides
    for values, codes in axes:
        odd = np.array([not _finite_number(v) for v in values], dtype=bool)
        if odd.any():
            suspect |= odd[codes]

    # body and forces once per combination of their swept values
    combo, combo_values = _combos([dims[i] for i in param_axes], [axes[i] for i in param_axes], n_points)
    builds = [_build_combo(plain, values) for values in combo_values]
    systems = {}
    for c, built in enumerate(builds):
        in_combo = combo == c
        if isinstance(built, _Failure):
            if built.exact:     # body or forces refused: the single run says the same, unless a NaN comes first
                errors.set(in_combo & ~suspect, built.message)
            else:
                suspect |= in_combo
        else:
            systems[c] = built
    reference = next(iter(systems.values()), None)
    if len({(b.compiled.form, b.compiled.params.size) for b in systems.values()}) > 1:
        raise ConfigError("the swept values change the compiled model's form (its torques or state), which one batch "
                          "cannot integrate together; sweep them with gyrolab -m")

    # initial states: vectorised over the points, or one system per distinct point
    y0 = np.full((n_points, reference.system.state_size if reference else 0), np.nan)
    combo_params = np.full((len(combo_values), reference.compiled.params.size if reference else 0), np.nan)
    for c, built in systems.items():
        combo_params[c] = built.compiled.params
    todo = ~suspect & ~errors.failed & np.isin(combo, list(systems))
    if reference is not None and todo.any():
        hook = getattr(reference.system, "initial_states", None)
        initial = plain.get("initial") or {}
        if hook is not None:
            columns = {_key(dims[i])[len("initial."):]: _column(axes[i], todo) for i in initial_axes}
            states, ok = hook(initial, columns)
            rows = np.flatnonzero(todo)
            if not columns:   # no initial key swept: one state for every point
                states, ok = np.broadcast_to(states, (rows.size, states.shape[1])), np.broadcast_to(ok, rows.shape)
            y0[rows[ok]] = states[ok]
            suspect[rows[~ok]] = True
        else:
            suspect |= todo   # a system without the vectorised hook: one system per point
    # everything the fast checks could not vouch for: the single run's own code
    for n in np.flatnonzero(suspect & ~errors.failed):
        built = _scalar_point(plain, values_of(int(n)), int(n), errors)
        if built is None:
            continue
        state, params = built
        if not y0.shape[1]:   # no combo was valid with the base initial state: the first valid point says
            y0 = np.full((n_points, state.size), np.nan)
            combo_params = np.full((len(combo_values), params.size), np.nan)
        if (state.size, params.size) != (y0.shape[1], combo_params.shape[1]):
            raise ConfigError(f"the batch's points have states of different sizes ({y0.shape[1]} and {state.size}) "
                              "or models of different forms; sweep them with gyrolab -m")
        y0[n] = state
        if np.isnan(combo_params[combo[n]]).all():
            combo_params[combo[n]] = params

    valid = ~errors.failed
    base = _with_values(plain, values_of(int(np.argmax(valid)))) if valid.any() else None
    times = _batch_times(plain, systems, y0, combo, valid)
    layout = " × ".join(f"{name} {n}" for name, n in zip(dim_names(dims), shape)) if points is None else \
        f"a list ({points['kind']}) over {', '.join(d.key for d in dims)}"
    log.info("batch plan: %d points (%s), %d valid, %d combinations of body/force values, %.2f s", n_points,
             layout, int(valid.sum()), len(combo_values), time.perf_counter() - start)
    attributes = _common_attributes(systems, swept_initial=bool(initial_axes))
    if ignored:
        log.warning("%s", ignored)
        attributes[ACCURACY_IGNORED_ATTRIBUTE] = ignored
    return Plan(dims=dims, names=dim_names(dims), plain=plain, base=base, times=times, y0=y0, combo=combo,
                combo_values=combo_values, combo_params=combo_params, error=errors.index, messages=list(errors.codes),
                attributes=attributes, points=points,
                systems={c: built.system for c, built in systems.items()})


def _points(dims: tuple[Dim, ...], plain: dict[str, Any]) -> tuple[tuple[Dim, ...], dict[str, str] | None]:
    """(the swept keys, how they give a list of points or None for a grid): ``batch.points_file`` (a CSV file's
    columns), ``batch.zip`` (the command line's swept keys point by point), else the grid of ``dims``."""
    node = plain.get("batch") or {}
    path, zipped = node.get("points_file"), node.get("zip", False)
    if not isinstance(zipped, bool):
        raise ConfigError(f"batch.zip={zipped!r} must be true or false")
    if path is not None:
        if dims:
            raise ConfigError(f"batch.points_file gives the batch's points, so no key may be swept on the command line "
                              f"too ({dims[0].key}); add it to the file as a column")
        if zipped:
            raise ConfigError("batch.zip=true zips command-line sweeps and batch.points_file is a list already; "
                              "give one of them")

        columns, digest = read_points_file(path, plain, VARIABLE_SECTIONS)
        return columns, {"kind": "points_file", "points_file": str(path), "points_file_sha256": digest}
    if not dims:
        raise ConfigError("a batch needs at least one swept key, e.g. initial.r0=1,2,5 (or a list of points: "
                          "batch.points_file=PATH)")
    if zipped:
        counts = {d.key: len(d.values) for d in dims}
        if len(set(counts.values())) > 1:
            raise ConfigError("batch.zip=true takes the swept keys' values point by point, so each needs as many "
                              f"values; got {', '.join(f'{k} {n}' for k, n in counts.items())}")
        return dims, {"kind": "zip"}
    for dim in dims:
        _refuse_repeats(dim.key, list(dim.labels), list(dim.values))
    return dims, None


def _distinct(dim: Dim) -> tuple[list[Any], np.ndarray]:
    """(the distinct values of a list's column, each point's index into them)."""
    if not dim.labels:   # a points file's column: floats
        values, codes = np.unique(np.asarray(dim.values, dtype=float), return_inverse=True)
        return values.tolist(), codes.astype(np.int32).ravel()
    index: dict[str, int] = {}   # each distinct label's number, in order of first appearance
    codes = np.array([index.setdefault(label, len(index)) for label in dim.labels], dtype=np.int32)
    return [dim.values[n] for n in np.unique(codes, return_index=True)[1]], codes


def _combos(dims: Sequence[Dim], axes: Sequence[tuple[list[Any], np.ndarray]], n_points: int
            ) -> tuple[np.ndarray, list[dict[str, Any]]]:
    """((N,) each point's combination of body/force values, the values of each combination); a grid's
    combinations in C order over its body/force dimensions."""
    if not dims:
        return np.zeros(n_points, dtype=np.int32), [{}]
    sizes = [len(values) for values, _ in axes]
    if math.prod(sizes) < 2**62:
        distinct, combo = np.unique(np.ravel_multi_index([codes for _, codes in axes], sizes), return_inverse=True)
        positions = np.unravel_index(distinct, sizes)
    else:   # too many distinct values to number their product
        distinct, combo = np.unique(np.stack([codes for _, codes in axes], axis=1), axis=0, return_inverse=True)
        positions = distinct.T
    combo_values = [{d.key: values[int(position[c])] for d, (values, _), position in zip(dims, axes, positions)}
                    for c in range(len(distinct))]
    return combo.astype(np.int32).ravel(), combo_values


@dataclass
class _Built:
    system: Any
    compiled: Any


@dataclass
class _Failure:
    message: str
    exact: bool   # the same message for every point of the combo


class _Errors:
    """Per-point error indices into a list of distinct messages."""

    def __init__(self, n: int) -> None:
        self.index = np.full(n, -1, dtype=np.int32)
        self.codes: dict[str, int] = {}   # message -> its index, in order of first appearance

    def set(self, where: np.ndarray | int, message: str) -> None:
        self.index[where] = self.codes.setdefault(message, len(self.codes))

    @property
    def failed(self) -> np.ndarray:
        return self.index >= 0


def _key(dim: Dim) -> str:
    return dim.key.lstrip("+~")


def _finite_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
        and abs(value) < 1.7e308


def _column(axis: tuple[list[Any], np.ndarray], rows: np.ndarray) -> np.ndarray:
    """A swept key's values (floats, NaN for any other) at ``rows`` of the points."""
    values, codes = axis
    return np.array([float(v) if _finite_number(v) else np.nan for v in values])[codes[rows]]


def _with_values(plain: dict[str, Any], values: Mapping[str, Any]) -> dict[str, Any]:
    out = copy.deepcopy(plain)
    for key, value in values.items():
        node, parts = out, key.lstrip("+~").split(".")
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return out


def _build_combo(plain: dict[str, Any], values: Mapping[str, Any]) -> _Built | _Failure:
    """The system of one combination of body/force values with the base initial state (Scene.from_config's
    order: body, forces, then the system; only the first two stages' errors hold for every point)."""
    point = _with_values(plain, values)
    try:
        require_finite({k: v for k, v in point.items() if k != "initial"}, "")
        cfg = OmegaConf.create(point)
        body_and_forces(cfg, point)   # built for their errors only; the scene builds its own
    except GyrolabError as error:
        return _Failure(str(error), exact=True)
    try:
        scene = Scene.from_config(cfg)   # the rest of the single run's checks, on the base initial state
    except GyrolabError as error:
        return _Failure(str(error), exact=False)
    return _Built(scene.system, _compiled(scene))


def _compiled(scene: Scene) -> Any:
    compiled = scene.compiled_model
    if compiled is None:
        reason = getattr(scene.system, "compile_error", None) or f"system {scene.system.name!r} has no compiled form"
        raise ConfigError(f"a batch runs the compiled batch kernels, and {reason}; sweep this scene with gyrolab -m")
    return compiled


def _scalar_point(plain: dict[str, Any], values: Mapping[str, Any], n: int,
                  errors: _Errors) -> tuple[np.ndarray, np.ndarray] | None:
    """Point ``n`` (its swept ``values``) checked and built by the single run's code: (its initial state,
    compiled parameters), or None with its error recorded."""
    try:
        scene = Scene.from_config(OmegaConf.create(_with_values(plain, values)))
    except GyrolabError as error:
        errors.set(n, str(error))
        return None
    return scene.system.initial_state(), _compiled(scene).params


def _common_attributes(systems: Mapping[int, _Built], swept_initial: bool) -> dict[str, Any]:
    """The attributes a single run's dataset gets from its system and body that are the same for every point
    (those of the initial state only when no initial key is swept)."""

    if not systems:
        return {}
    per = [{**b.system.attributes(), **unit_attributes(b.system.body)} for b in systems.values()]
    first = per[0]
    return {k: v for k, v in first.items()
            if not (swept_initial and k.startswith("initial_"))
            and all(k in other and np.array_equal(np.asarray(other[k]), np.asarray(v)) for other in per[1:])}


def _batch_times(plain: dict[str, Any], systems: Mapping[int, _Built], y0: np.ndarray, combo: np.ndarray,
                 valid: np.ndarray) -> np.ndarray:
    """One output grid for the batch: ``time.n_output: auto`` takes the densest any point needs (the fastest
    rate over the combos, each with its most energetic initial ω)."""
    time_cfg = plain["time"]
    rate = None
    if time_cfg.get("n_output", "auto") == "auto":
        rates = []
        for c, built in systems.items():
            omega = y0[valid & (combo == c), :3]
            if len(omega):
                inertia = np.asarray(getattr(built.system.body, "inertia", np.ones(3)), dtype=float)
                energetic = omega[int(np.argmax(np.einsum("ij,j,ij->i", omega, inertia, omega)))]
                rates.append(fastest_rate(built.system, energetic))
        rates = [r for r in rates if r is not None]
        rate = max(rates) if rates else None
    return scene_module._output_times(time_cfg, rate)


def plan_from_overrides(overrides: Sequence[str]) -> Plan:
    fixed, dims = split_overrides(overrides)
    return make_plan(fixed, dims)
