"""Summary figures of a sweep: quantities of interest against the swept parameters.

``sweep_final_state.png`` (ω and γ at the last output time), ``sweep_invariant_drift.png`` (each
monitored invariant's max |I(t) − I(0)|, log scale) and ``sweep_cost.png`` (right-hand-side
evaluations, integrator wall time). The x axis is the swept parameter with the most values
(numeric ones first); every combination of the other swept values is one line, or, when there
are more than ``MAX_LINES`` of them, their median with the min–max range shaded.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

MAX_LINES = 8


def save_sweep_figures(ds: xr.Dataset, directory: Path) -> list[Path]:
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    dims = ds.attrs["sweep_dims"].split()
    xdim = choose_x(ds, dims)
    panels = {
        "sweep_final_state": [(f"{name}_{axis} at t_end", final_values(ds[name]).sel(axis=axis), False)
                              for name in ("omega", "gamma") if name in ds for axis in ds.axis.values],
        "sweep_invariant_drift": [(f"max |Δ{name[:-len('_max_abs_drift')]}|", ds[name], True)
                                  for name in ds.data_vars if name.endswith("_max_abs_drift")],
        "sweep_cost": [(label, ds[name], True) for name, label in
                       (("integrator_nfev", "rhs evaluations"), ("integrator_wall_time", "integrator wall time [s]"))
                       if name in ds],
    }
    written = []
    for stem, items in panels.items():
        if not items:
            continue
        fig = _figure(items, xdim, ds)
        path = directory / f"{stem}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def choose_x(ds: xr.Dataset, dims: list[str]) -> str:
    """The swept dimension with the most values, numeric ones first."""
    return max(dims, key=lambda d: (ds[d].dtype.kind in "iuf", ds.sizes[d]))


def final_values(da: xr.DataArray) -> xr.DataArray:
    """The value at the last output time of each job (the last finite sample when jobs differ in length)."""
    if "time" in da.dims:
        return da.isel(time=-1)
    values = np.moveaxis(da.values, da.get_axis_num("sample"), -1)
    finite = np.isfinite(values)
    last = np.where(finite.any(axis=-1), finite.shape[-1] - 1 - np.argmax(finite[..., ::-1], axis=-1), 0)
    picked = np.take_along_axis(values, last[..., None], axis=-1)[..., 0]
    return xr.DataArray(picked, dims=[d for d in da.dims if d != "sample"],
                        coords={d: da[d] for d in da.dims if d != "sample" and d in da.coords})


def _figure(items: list[tuple[str, xr.DataArray, bool]], xdim: str, ds: xr.Dataset) -> plt.Figure:
    ncols = 3 if len(items) > 4 else len(items)
    nrows = -(-len(items) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(4.2 * ncols, 3.2 * nrows), squeeze=False,
                             constrained_layout=True)
    for ax, (label, da, log) in zip(axes.flat, items):
        _panel(ax, da, xdim, log)
        ax.set_title(label, fontsize=9)
    for ax in list(axes.flat)[len(items):]:
        ax.set_visible(False)
    fig.suptitle(f"{ds.attrs.get('title', 'sweep')}: {ds.attrs['n_finished']} finished, "
                 f"{ds.attrs['n_failed']} failed", fontsize=9)
    return fig


def _panel(ax: plt.Axes, da: xr.DataArray, xdim: str, log: bool) -> None:
    x = da[xdim].values
    numeric = x.dtype.kind in "iuf"
    positions = x.astype(float) if numeric else np.arange(len(x))
    others = [d for d in da.dims if d != xdim]
    da = da.transpose(*others, xdim)
    combos = list(itertools.product(*(range(da.sizes[d]) for d in others)))
    values = da.values.reshape(len(combos), len(x)).astype(float)
    if log:
        values = np.where(values > 0, values, np.nan)
    if len(combos) <= MAX_LINES:
        for combo, row in zip(combos, values):
            label = ", ".join(f"{d}={da[d].values[i]}" for d, i in zip(others, combo)) or None
            ax.plot(positions, row, "o-", ms=3, lw=1, label=label)
        if others:
            ax.legend(fontsize=6)
    else:
        with np.errstate(all="ignore"):
            finite = np.isfinite(values).any(axis=0)
            mid = np.full(len(x), np.nan)
            low, high = mid.copy(), mid.copy()
            mid[finite] = np.nanmedian(values[:, finite], axis=0)
            low[finite] = np.nanmin(values[:, finite], axis=0)
            high[finite] = np.nanmax(values[:, finite], axis=0)
        ax.plot(positions, mid, "o-", ms=3, lw=1, label=f"median over {', '.join(others)}")
        ax.fill_between(positions, low, high, alpha=0.25, label="min–max")
        ax.legend(fontsize=6)
    if log and np.isfinite(values).any():
        ax.set_yscale("log")
    empty = ~np.isfinite(values).any(axis=0)
    if empty.any():  # swept values where no job gave a number (failed jobs): marked on the x axis
        ax.plot(positions[empty], np.zeros(int(empty.sum())), "x", color="tab:red", ms=7, clip_on=False,
                transform=ax.get_xaxis_transform(), label="no result (failed)")
        ax.legend(fontsize=6)
    if not numeric:
        ax.set_xticks(positions, [str(v) for v in x], fontsize=7)
    ax.set_xlabel(f"{xdim} ({da[xdim].attrs.get('override_key', xdim)})", fontsize=8)
    ax.grid(alpha=0.3)
