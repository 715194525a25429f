"""Figure of ``ismail2021_tables.nc``: the γ₂ column of Ismail (2021) Tables 1 and 2, published and
regenerated, and their absolute differences on a log axis. Differences that are exactly zero cannot be
drawn on it: they are marked ▼ on the bottom edge of the panel and the legend says so (no fake floor)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from gyrolab.figures.style import DOUBLE, Axes, Figure, legend_outside, log_positive, styled, subplots

COLUMN = "gamma2"


def _zeros(ax: Axes, t: np.ndarray, values: np.ndarray, color: str) -> None:
    zero = values == 0
    if zero.any():
        ax.plot(t[zero], np.zeros(int(zero.sum())), "v", color=color, ms=4, clip_on=False,
                transform=ax.get_xaxis_transform(), label="difference exactly 0 (on the axis edge)")


@styled
def draw_tables(ds: xr.Dataset) -> Figure:
    fig, axes = subplots(1, 2, width=DOUBLE, height=3.0)
    left, right = axes[0]
    t = ds["t"].values
    j = [str(c) for c in ds["column"].values].index(COLUMN)
    for n, marker, color in ((1, "o", "C0"), (2, "s", "C1")):
        published, regenerated = ds[f"published{n}"].values[:, j], ds[f"table{n}"].values[:, j]
        left.plot(t, published, marker, mfc="none", ms=4, color=color, label=f"published Table {n}")
        left.plot(t, regenerated, "-" if n == 1 else "--", lw=0.9, color=color, label=f"regenerated Table {n}")
        diff = np.abs(regenerated - published)
        right.plot(t, log_positive(diff), marker + "-", ms=3, lw=0.7, color=color,
                   label=f"|regenerated − published|, Table {n}")
        _zeros(right, t, diff, color)
    rk4 = np.abs(ds["published1"].values[:, j] - ds["published2"].values[:, j])
    right.plot(t, log_positive(rk4), "^-", ms=3, lw=0.7, color="C2", label="|Table 1 − Table 2| (RK4 truncation)")
    _zeros(right, t, rk4, "C2")
    for ax in (left, right):
        ax.set_xlabel("t, the tables' time (τ = 2πt/100)")
    left.set_ylabel("γ₂")
    right.set(yscale="log", ylabel="absolute difference of γ₂")
    legend_outside(fig, ncols=3)
    fig.suptitle("Ismail (2021), Tables 1 and 2 regenerated")
    return fig


FIGURES = {"ismail2021_tables": draw_tables}
