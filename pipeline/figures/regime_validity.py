"""Figure of ``regime_validity.nc``: error of each regime's analytic solution over its parameter, and of
``small_parameter`` across the resonances it excludes; one panel each, in a grid.

Errors are relative (divided by each variable's scale) and dimensionless. Exact zeros cannot be drawn
on a log axis: they are left out and a panel that has any says so.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from gyrolab.figures.style import DOUBLE, Axes, Figure, log_positive, styled, subplots
from gyrolab.output.user_yaml import stored_yaml

#: error key -> (legend, marker); one color per key in every panel
KEYS = {"pq": ("p, q", "o"), "r": ("r", "s"), "gamma": ("γ₁, γ₂", "D"), "gamma3": ("γ₃", "^"), "period": ("period", "v")}
PARAMETERS = {"mu": "μ", "c/r0": "c/r₀", "c/r0 (as printed)": "μ = c/r₀ (paper's reading)"}


def _spec(ds: xr.Dataset) -> dict[str, Any]:
    try:
        return stored_yaml(ds.attrs.get("config", ""), "the dataset's config attribute").get("regime_validity") or {}
    except Exception:  # noqa: BLE001 -- a dataset without its config still draws, with generic labels
        return {}


def _regime_panel(ax: Axes, ds: xr.Dataset, name: str, spec: dict[str, Any]) -> None:
    dim = f"{name}_parameter"
    x = ds[dim].values.astype(float)
    zeros: list[str] = []
    for k, (legend, marker) in KEYS.items():
        var = f"{name}_error_{k}_vs_orbit"
        if var not in ds:
            continue
        e = ds[var].values.astype(float)
        if not np.isfinite(e).any():
            continue
        order = ds.get(f"{name}_order_{k}")
        slope = float(order) if order is not None and np.isfinite(float(order)) else None
        ax.plot(x, log_positive(e), marker=marker, lw=0.8, ms=3.5, color=f"C{list(KEYS).index(k)}",
                label=legend + (f", slope {slope:.2f}" if slope is not None else ""))
        if np.any(e == 0):
            zeros.append(legend)
    parameter = str((spec.get(name) or {}).get("parameter", "expansion parameter"))
    ax.set(xscale="log", yscale="log", xlabel=PARAMETERS.get(parameter, parameter))
    notes = _regime_notes(ds, name, x, zeros)
    ax.set_title(name.replace("_", " ") + ("\n" + "; ".join(notes) if notes else ""), fontsize=7)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=2, fontsize=6)


def _regime_notes(ds: xr.Dataset, name: str, x: np.ndarray, zeros: list[str]) -> list[str]:
    """The panel's notes: where the regime was refused or failed, what it is compared with, zeros not drawn."""
    status = [str(s) for s in ds[f"{name}_status"].values] if f"{name}_status" in ds else []
    refused = [v for v, s in zip(x, status) if s.startswith(("refused", "failed"))]
    notes = [f"refused or failed at {', '.join(f'{v:g}' for v in refused)}"] if refused else []
    if name == "large_parameter":
        notes.append("printed formulas against the full model")
    if zeros:
        notes.append(f"exact zeros not drawn: {', '.join(zeros)}")
    return notes

def _resonance_panel(ax: Axes, ds: xr.Dataset, spec: dict[str, Any]) -> None:
    d = ds["resonance_distance"].values.astype(float)
    errors = ds["resonance_error_max_vs_orbit"].values
    status = ds["resonance_status"].values
    for i, n in enumerate(ds["resonance"].values):
        _draw_resonance(ax, i, n, float(ds["resonance_exponent_max"].values[i]), ds["side"].values, d, errors[i],
                        status[i])
    tolerance = (spec.get("resonance_sweep") or {}).get("tolerance")
    if tolerance is not None:
        ax.axhline(float(tolerance), color="k", lw=0.7, ls=":", label=f"tolerance {float(tolerance):g}")
    ax.set(xscale="log", yscale="log", xlabel="|ω − n| (grey: refused)", ylabel="max error vs exact orbit")
    r0 = (spec.get("resonance_sweep") or {}).get("r0")
    ax.set_title("small parameter across ω = n" + (f", c/r₀ = {1 / float(r0):g}" if r0 else ""), fontsize=7)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=2, fontsize=6)


def _draw_resonance(ax: Axes, i: int, n: float, s: float, sides: np.ndarray, d: np.ndarray, errors: np.ndarray,
                    status: np.ndarray) -> None:
    """The error towards resonance ω = n from both sides, and the distances where it was refused (grey)."""
    for j, side in enumerate(sides):
        label = f"ω → {n:g}{'+' if side > 0 else '−'}" + (f", s = {s:.2f}" if j == 0 and np.isfinite(s) else "")
        ax.plot(d, log_positive(errors[j]), marker="o" if side > 0 else "s", ls="-" if side > 0 else "--",
                lw=0.8, ms=3.5, color=f"C{i}", mfc="none" if side < 0 else None, label=label)
    refused = [dd for dd, row in zip(d, status.T) if any(str(x).startswith("refused") for x in row)]
    if refused:
        ax.axvspan(min(d) * 0.8, max(refused) * 1.1, color="0.5", alpha=0.12, lw=0)

@styled
def draw_regime_validity(ds: xr.Dataset) -> Figure:
    spec = _spec(ds)
    regimes = [str(d).removesuffix("_parameter") for d in ds.dims if str(d).endswith("_parameter")]
    n = len(regimes) + ("resonance_error_max_vs_orbit" in ds)
    ncols = min(3, n)
    nrows = -(-n // ncols)
    fig, axes = subplots(nrows, ncols, width=DOUBLE, height=0.6 + 3.0 * nrows)
    flat = list(axes.flat)
    for ax, name in zip(flat, regimes):
        _regime_panel(ax, ds, name, spec)
    if "resonance_error_max_vs_orbit" in ds:
        _resonance_panel(flat[len(regimes)], ds, spec)
    for ax in flat[n:]:
        ax.set_visible(False)
    for row in axes:
        row[0].set_ylabel("max relative error")
    fig.suptitle("Validity of the expansion regimes: error against the exact orbit")
    return fig


FIGURES = {"regime_validity": draw_regime_validity}
