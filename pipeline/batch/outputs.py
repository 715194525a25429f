"""What a batch stores per point (``batch.output``; docs/batch.md, "What is stored per point"), computed from a
chunk's trajectories: each ``Output(dims, data, attrs)`` has one row of ``data`` per point, ``dims`` after the grid's.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.physics.attitude import nutation_and_spin

MODES = ("trajectory", "decimated", "final", "reductions", "indicator")
#: modes whose outputs carry a time dimension
SERIES_MODES = ("trajectory", "decimated")
DRIFT_SUFFIX = "_max_abs_drift"
NUTATION = "max_nutation_deviation"
NUTATION_ATTRS = {"units": "rad", "long_name": "max |θ(t) − θ(0)| over the stored samples (nutation deviation)"}
#: points per block of the reductions' array arithmetic
REDUCTION_BLOCK = 256
#: angles a single run unwraps along its trajectory; a final value alone is wrapped to (−π, π]
WRAPPED = ("phi", "psi")


@dataclass
class Output:
    dims: tuple[str, ...]
    data: np.ndarray
    attrs: dict[str, Any]


def output_times(times: np.ndarray, mode: str, decimate: int) -> np.ndarray:
    """The output times a mode stores (only the series modes store any)."""
    return times[::decimate] if mode == "decimated" else times


def state_outputs(mode: str, decimate: int, times: np.ndarray, y: np.ndarray,
                  groups: Sequence[tuple[Any, np.ndarray]]) -> dict[str, Output]:
    """The outputs of ``mode`` (not ``indicator``) for trajectories ``y`` (points × times × state); ``groups``:
    (system, rows), each system built with its rows' body and forces (energy and units depend on them)."""
    outputs: dict[str, Output] = {}
    for system, index in groups:
        index = np.asarray(index)
        if not index.size:
            continue
        if mode in SERIES_MODES:
            t = output_times(times, mode, decimate)
            part = {}
            for row in index:
                variables = system.variables(t, y[row, ::decimate] if mode == "decimated" else y[row])
                for name, var in variables.items():
                    part.setdefault(name, (tuple(var.dims), [], dict(var.attrs)))[1].append(var.values)
                for name, values in _drifts(system, y[row][None]).items():
                    part.setdefault(name, ((), [], values[1]))[1].append(values[0][0])
            _place(outputs, {k: (d, np.stack(v), a) for k, (d, v, a) in part.items()}, index, len(y))
            continue
        finals = _final_variables(system, times, y[index, -1])
        _place(outputs, finals, index, len(y))
        if mode == "reductions":   # by blocks of points that fit in the cache (numpy streams each operation)
            for lo in range(0, len(index), REDUCTION_BLOCK):
                rows = index[lo:lo + REDUCTION_BLOCK]
                block = y[rows]
                part = {k: ((), v, a) for k, (v, a) in _drifts(system, block).items()}
                theta = nutation_and_spin(block[:, :, 3:6])[0]
                part[NUTATION] = ((), np.max(np.abs(theta - theta[:, :1]), axis=1), dict(NUTATION_ATTRS))
                _place(outputs, part, rows, len(y))
    return outputs


def _final_variables(system: Any, times: np.ndarray, final: np.ndarray) -> dict[str, tuple]:
    """The system's variables at the final states, the points standing in for the time axis (every variable
    is pointwise in time except the unwrapped angles, which are wrapped back)."""
    t = np.full(len(final), times[-1])
    out = {}
    for name, var in system.variables(t, final).items():
        values = np.asarray(var.values, dtype=float)
        attrs = dict(var.attrs)
        if name in WRAPPED:
            values = np.angle(np.exp(1j * values))
            attrs["long_name"] = str(attrs.get("long_name", name)).replace("(unwrapped)", "(wrapped to (−π, π])")
        out[name] = (tuple(var.dims[1:]), values, attrs)
    return out


def _drifts(system: Any, y: np.ndarray) -> dict[str, tuple[np.ndarray, dict[str, Any]]]:
    """Each monitored invariant's max |I(t) − I(0)| per trajectory of ``y`` (points × times × state)."""
    hook = getattr(system, "invariant_values", None)
    if hook is not None:
        values = hook(y)
    else:   # a system without the vectorised hook: its variables, one trajectory at a time
        t = np.arange(y.shape[1], dtype=float)
        per = [system.variables(t, row) for row in y]
        values = {name: np.stack([v[name].values for v in per]) for name in system.invariants}
    units = _units(system)
    out = {}
    for name in system.invariants:
        series = np.asarray(values[name], dtype=float)
        drift = np.max(np.abs(series - series[:, :1]), axis=1)
        out[name + DRIFT_SUFFIX] = (drift, {"units": units.get(name, "1"),
                                            "long_name": f"max |{name}(t) − {name}(0)| over the stored samples"})
    return out


def _units(system: Any) -> dict[str, str]:
    """The units of the system's variables (from a two-sample evaluation at a valid state)."""
    cached = getattr(system, "_batch_units", None)
    if cached is None:
        y = np.tile(system.initial_state(), (2, 1))
        cached = {name: str(var.attrs.get("units", "1")) for name, var in system.variables(np.zeros(2), y).items()}
        system._batch_units = cached
    return cached


def _place(outputs: dict[str, Output], part: Mapping[str, tuple], index: np.ndarray, n_rows: int) -> None:
    """Put one group's rows into the chunk's outputs (NaN rows elsewhere)."""
    for name, (dims, values, attrs) in part.items():
        values = np.asarray(values)
        if name not in outputs:
            data = np.full((n_rows,) + values.shape[1:], np.nan)
            outputs[name] = Output(tuple(dims), data, attrs)
        outputs[name].data[index] = values


def indicator_outputs(compiled: Any, integrator: Any, times: np.ndarray, y0s: np.ndarray,
                      params: np.ndarray) -> dict[str, Output]:
    """The chaos indicator's outputs (``gyrolab.analysis.chaos.indicator_outputs``, imported here only)."""
    # start-up: a compiled kernel's module imports numba, loaded only when such a kernel runs
    from gyrolab.analysis.chaos import indicator_outputs as compute

    out = {}
    for name, (data, attrs) in compute(compiled, integrator, times, y0s, params).items():
        data = np.asarray(data)
        out[name] = Output(tuple(f"{name}_{k}" for k in range(1, data.ndim)), data, dict(attrs))
    return out


def merge_rows(outputs: Mapping[str, Output], rows: np.ndarray, n_rows: int) -> dict[str, Output]:
    """Outputs computed for ``rows`` only, spread over ``n_rows`` (NaN in the others)."""
    merged: dict[str, Output] = {}
    _place(merged, {name: (out.dims, out.data, out.attrs) for name, out in outputs.items()}, rows, n_rows)
    return merged

