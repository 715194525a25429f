"""Summary figures of a sweep (``sweep.nc``): quantities of interest against the swept parameters.

``sweep_final_state`` (ω and γ at the last output time), ``sweep_invariant_drift`` (each monitored
invariant's max |I(t) − I(0)|, log scale) and ``sweep_cost`` (integrator evaluations, wall time). The x
axis is the swept parameter with the most values (numeric ones first). Sweep values are discrete: they
are drawn as markers, never joined by lines. Every combination of the other swept values is one marker
series, or, when there are more than ``MAX_SERIES`` of them, their median with the min–max range as an
error bar. Swept values where no job gave a number are marked × on the x axis.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import xarray as xr

from gyrolab.figures.evaluations import nfev_notes
from gyrolab.figures.labels import GAMMA, OMEGA, label, unit
from gyrolab.figures.options import DEFAULT_DPI, DEFAULT_FORMATS
from gyrolab.figures.run import INVARIANTS
from gyrolab.figures.save import save_all
from gyrolab.figures.style import DOUBLE, SINGLE, Axes, Figure, legend_outside, panel_note, styled, subplots
from gyrolab.output.units import KINDS

MAX_SERIES = 8
MARKERS = "osD^v<>p"

#: (panel title: the quantity, y label: what is plotted and its unit, values, log scale)
Panel = tuple[str, str, xr.DataArray, bool]
#: a y label longer than this puts its unit on a second line (a 3-column panel is ~1.6 in tall)
LABEL_WIDTH = 22


def final_values(da: xr.DataArray) -> xr.DataArray:
    """The value at the last output time of each job (the last finite sample when jobs differ in length)."""
    if "time" in da.dims:
        return da.isel(time=-1)
    values = np.moveaxis(da.values, da.get_axis_num("sample"), -1)
    finite = np.isfinite(values)
    last = np.where(finite.any(axis=-1), finite.shape[-1] - 1 - np.argmax(finite[..., ::-1], axis=-1), 0)
    picked = np.take_along_axis(values, last[..., None], axis=-1)[..., 0]
    return xr.DataArray(picked, dims=[d for d in da.dims if d != "sample"],
                        coords={d: da[d] for d in da.dims if d != "sample" and d in da.coords}, attrs=da.attrs)


def _final_state(ds: xr.Dataset) -> list[Panel]:
    panels = []
    for name, symbols, kind in (("omega", OMEGA, "rate"), ("gamma", GAMMA, "1")):
        if name not in ds:
            continue
        final = final_values(ds[name])
        for i, symbol in enumerate(symbols):
            panels.append((f"{symbol} at the end", _ylabel(symbol, unit(ds, ds[name].attrs.get("units"), kind)),
                           final.isel(axis=i), False))
    return panels


def _drift(ds: xr.Dataset) -> list[Panel]:
    panels = []
    for name in ds.data_vars:
        if str(name).endswith("_max_abs_drift"):
            base = str(name).removesuffix("_max_abs_drift")
            symbol, kind = INVARIANTS.get(base, (base.replace("_", " "), "1"))
            panels.append((symbol, _ylabel("max |I(t) − I(0)|", unit(ds, ds[name].attrs.get("units"), kind)),
                           ds[name], True))
    return panels


def _cost(ds: xr.Dataset) -> list[Panel]:
    costs = (("integrator_nfev", "integrator evaluations", "evaluations"),
             ("integrator_wall_time", "integrator wall time", "wall time (s)"))
    return [(title, ylabel, ds[name], True) for name, title, ylabel in costs if name in ds]


def _ylabel(name: str, unit_text: str) -> str:
    """'name (unit)', the unit on its own line when the label would overrun its panel."""
    text = label(name, unit_text)
    return text if len(text) <= LABEL_WIDTH or not unit_text else f"{name}\n({unit_text})"


def _draw(ds: xr.Dataset, panels: list[Panel], title: str) -> Figure:
    # x: the swept dimension with the most values, numeric ones first
    xdim = max(ds.attrs["sweep_dims"].split(), key=lambda d: (ds[d].dtype.kind in "iuf", ds.sizes[d]))
    ncols = min(3, len(panels))
    nrows = -(-len(panels) // ncols)
    fig, axes = subplots(nrows, ncols, width=SINGLE if ncols == 1 else DOUBLE, height=0.9 + 1.9 * nrows)
    for ax, (quantity, ylabel, da, log) in zip(axes.flat, panels):
        _panel(ax, da, xdim, log, ds)
        ax.set_title(quantity, loc="left", fontsize=7.5)  # left: a panel_note (sweep_cost) goes under it
        ax.set_ylabel(ylabel)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    legend_outside(fig, list(axes.flat))
    fig.suptitle(f"{title}: {ds.attrs.get('n_finished', '?')} jobs finished, {ds.attrs.get('n_failed', '?')} failed")
    return fig


@styled
def draw_final_state(ds: xr.Dataset) -> Figure:
    """ω and γ at the last output time of every job against the swept values."""
    return _draw(ds, _final_state(ds), "Final state")


@styled
def draw_invariant_drift(ds: xr.Dataset) -> Figure:
    """Each monitored invariant's max |I(t) − I(0)| against the swept values (log scale)."""
    return _draw(ds, _drift(ds), "Drift of the invariants")


@styled
def draw_cost(ds: xr.Dataset) -> Figure:
    """Integrator evaluations and wall time against the swept values (log scale)."""
    fig = _draw(ds, _cost(ds), "Cost")
    notes = [f"{name}: {what}" for name, what in nfev_notes(ds).items()]   # what each integrator's count counts
    if notes and "integrator_nfev" in ds:
        panel_note(fig.axes[0], "evaluations are right-hand-side calls, except " + "; ".join(notes))
    return fig


def _panel(ax: Axes, da: xr.DataArray, xdim: str, log: bool, ds: xr.Dataset) -> None:
    x = da[xdim].values
    numeric = x.dtype.kind in "iuf"
    positions = x.astype(float) if numeric else np.arange(len(x), dtype=float)
    others = [d for d in da.dims if d != xdim]
    da = da.transpose(*others, xdim)
    combos = list(itertools.product(*(range(da.sizes[d]) for d in others)))
    values = da.values.reshape(len(combos), len(x)).astype(float)
    if log:
        values = np.where(values > 0, values, np.nan)
    if len(combos) <= MAX_SERIES:
        for k, (combo, row) in enumerate(zip(combos, values)):
            name = ", ".join(f"{d} = {da[d].values[i]}" for d, i in zip(others, combo)) or "_"
            ax.plot(positions, row, MARKERS[k % len(MARKERS)], color=f"C{k % 8}", mfc="none" if k % 2 else None,
                    label=name)
    else:
        with np.errstate(all="ignore"):
            finite = np.isfinite(values).any(axis=0)
            mid = np.full(len(x), np.nan)
            low, high = mid.copy(), mid.copy()
            mid[finite] = np.nanmedian(values[:, finite], axis=0)
            low[finite] = np.nanmin(values[:, finite], axis=0)
            high[finite] = np.nanmax(values[:, finite], axis=0)
        ax.errorbar(positions, mid, yerr=[mid - low, high - mid], fmt="o", capsize=2, lw=0.8,
                    label=f"median over {', '.join(others)} (bar: min–max)")
    if log and np.isfinite(values).any():
        ax.set_yscale("log")
    empty = ~np.isfinite(values).any(axis=0)
    if empty.any():  # swept values where no job gave a number (failed jobs): marked on the x axis
        ax.plot(positions[empty], np.zeros(int(empty.sum())), "x", color="C1", ms=6, clip_on=False,
                transform=ax.get_xaxis_transform(), label="no result (failed job)")
    if not numeric:
        ax.set_xticks(positions, [str(v) for v in x])
        ax.set_xlim(positions[0] - 0.5, positions[-1] + 0.5)
    elif len(positions) > 1 and positions.min() > 0 and positions.max() / positions.min() > 50:
        ax.set_xscale("log")
    ax.set_xlabel(_xlabel(ds, da[xdim], xdim))


def _xlabel(ds: xr.Dataset, coord: xr.DataArray, xdim: str) -> str:
    """The swept key with its unit: SI as stored, a nondimensional rate or time in units of c (or Ω), none for
    a pure number (gyrolab.output.units knows which kind a key is)."""
    key = str(coord.attrs.get("override_key", xdim))
    units = coord.attrs.get("units")
    kind = KINDS.get(key.lstrip("+~").replace(".", "_"), "1")
    return label(key, unit(ds, units, kind) if units is not None else "")


FIGURES = {"sweep_final_state": (draw_final_state, _final_state), "sweep_invariant_drift": (draw_invariant_drift, _drift),
           "sweep_cost": (draw_cost, _cost)}


def save_figures(ds: xr.Dataset, directory: str | Path, formats: Iterable[str] = DEFAULT_FORMATS,
                 dpi: int = DEFAULT_DPI) -> list[Path]:
    """Every sweep figure that has something to show, into ``directory``."""
    figures = {name: draw(ds) for name, (draw, panels) in FIGURES.items() if panels(ds)}
    return save_all(figures, directory, ds, formats, dpi)
