"""Figure of ``orbit_family.nc``: the exact periodic-orbit families from fast spin to slow spin.

Period and nutation amplitude against r0/c (filled markers: linearly stable, open: unstable;
bifurcations drawn where they were located: squares folds, diamonds branch points, triangles period doublings,
explained in the legend), and the error of each series
against the exact orbit with the 1e-6 and 1e-3 levels that bound the bands in ``docs/regimes.md``.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from gyrolab.figures.style import DOUBLE, legend_outside, styled, subplots

MARKS = {"fold": "F", "branch point": "BP", "period doubling": "PD"}
#: the located bifurcations are drawn as markers explained in the legend (text labels of nearby events overprint)
EVENT_MARKERS = {"fold": "s", "branch point": "D", "period doubling": "v"}
LEVELS = (1e-6, 1e-3)


def _series_label(name: str) -> str:
    """``error_fast_spin_order_6`` -> "fast-spin series, order 6"; ``error_slow_spin_series`` -> "slow-spin series"."""
    if name == "error_slow_spin_series":
        return "slow-spin series"
    order = name.rsplit("order_", 1)[-1]
    return f"fast-spin series, order {order}" if order.isdigit() else "fast-spin series, the paper's order"


def _located_events(ds: xr.Dataset, family: str) -> list[tuple[str, float, int]]:
    """(kind, located r0/c, index of the point after it) of a family's bifurcations; from the point labels (at the
    point after the event) for datasets written before events were located."""
    if "event_r0_over_c" in ds:
        mine = np.flatnonzero(ds["event_family"].values == family)
        return [(str(ds["event_kind"].values[k]), float(ds["event_r0_over_c"].values[k]),
                 int(ds["event_point"].values[k])) for k in mine]
    at = np.flatnonzero(ds["family"].values == family)
    return [(part.strip(), float(ds["r0_over_c"].values[i]), int(i)) for i in at[1:]
            for part in str(ds["bifurcation"].values[i]).split(",") if part.strip()]


@styled
def draw_orbit_family(ds: xr.Dataset) -> plt.Figure:
    fig, axes = subplots(3, 1, width=DOUBLE, height=7.0, sharex="col")
    period_ax, amplitude_ax, error_ax = axes[:, 0]
    families = list(dict.fromkeys(str(f) for f in ds["family"].values))
    labels = ds["family_label"].values if "family_label" in ds else ds["family"].values
    series = [name for name in ds.data_vars if str(name).startswith("error_")]
    styles = ["-", "--", ":", "-."]
    for n, family in enumerate(families):
        at = np.flatnonzero(ds["family"].values == family)
        colour = f"C{n}"
        r0 = ds["r0_over_c"].values[at]
        stable = ds["stable"].values[at].astype(bool)
        events = _located_events(ds, family)
        for ax, values in ((period_ax, ds["period"].values[at]), (amplitude_ax, ds["amplitude"].values[at])):
            ax.plot(r0, values, "-", color=colour, lw=0.8, label=str(labels[at[0]]))
            ax.plot(r0[stable], values[stable], "o", ms=3, color=colour, ls="none")
            ax.plot(r0[~stable], values[~stable], "o", ms=3, mfc="none", mec=colour, ls="none")
            for kind, where, point in events[:4]:  # the first few: near a homoclinic end they pile up
                # on the segment between the two family points that bracket it, at the located r0
                i = int(np.searchsorted(at, point))
                w = np.clip((np.log(where) - np.log(r0[i - 1])) / (np.log(r0[i]) - np.log(r0[i - 1])), 0, 1) \
                    if r0[i] != r0[i - 1] else 0.0
                y = np.exp((1 - w) * np.log(values[i - 1]) + w * np.log(values[i])) if ax is period_ax \
                    else (1 - w) * values[i - 1] + w * values[i]
                ax.plot([where], [y], marker=EVENT_MARKERS[kind], ms=5, color=colour, ls="none")
        for k, name in enumerate(series):
            errors = ds[name].values[at]
            if np.isfinite(errors).any():
                error_ax.plot(r0, np.where(errors > 0, errors, np.nan), styles[k % len(styles)], color=colour, lw=0.8,
                              label=f"_{family}_{name}")
    for level in LEVELS:
        error_ax.axhline(level, color="0.5", lw=0.6, ls=(0, (2, 2)))
    for k, name in enumerate(series):  # line style = series, colour = family
        error_ax.plot([], [], styles[k % len(styles)], color="0.3", lw=0.8, label=_series_label(str(name)))
    period_ax.plot([], [], "o", ms=3, color="0.3", ls="none", label="stable (filled) / unstable (open)")
    for kind, marker in EVENT_MARKERS.items():
        period_ax.plot([], [], marker=marker, ms=5, color="0.3", ls="none", label=f"{kind} (located)")
    period_ax.set_yscale("log")
    period_ax.set_ylabel("period (units of 1/c)")
    amplitude_ax.set_ylabel("nutation amplitude (rad)")
    error_ax.set_yscale("log")
    error_ax.set_ylabel("series error vs exact orbit")
    error_ax.set_xscale("log")
    error_ax.set_xlabel("spin r0 (units of c)")
    legend_outside(fig, ncols=2)
    fig.suptitle("Periodic-orbit families from fast spin (right) to slow spin (left)")
    return fig


FIGURES = {"orbit_family": draw_orbit_family}
