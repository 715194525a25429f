"""Figure of ``orbit_family.nc``: the exact periodic-orbit families from fast spin to slow spin.

Period and nutation amplitude against r0/c (filled markers: linearly stable, open: unstable;
bifurcations drawn where they were located: open squares folds, open diamonds branch points, triangles period
doublings, explained in the legend; where a family turns back near its homoclinic end and its events crowd
together, an inset of the amplitude panel shows that stretch at linear r0), and the error of each series
against the exact orbit with the 1e-6 and 1e-3 levels that bound the bands in ``docs/regimes.md``.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from gyrolab.figures.style import DOUBLE, Figure, legend_outside, styled, subplots

#: located bifurcations are markers explained in the legend (text labels of nearby events overprinted each other):
#: open shapes of decreasing size, so that events located at the same orbit (a fold that is also a period
#: doubling, say) stay visible one inside the other
EVENT_STYLES = {"fold": dict(marker="s", ms=7.0, mfc="none", mew=1.0),
                "branch point": dict(marker="D", ms=5.0, mfc="none", mew=0.9),
                "period doubling": dict(marker="v", ms=3.2)}
#: where the families turn back near their homoclinic end their events crowd into a few hundredths of r0/c:
#: they are drawn in an inset of the amplitude panel at linear r0 (this much margin around the turning arcs)
ZOOM_MARGIN = 0.03
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


def _on_family(r0: np.ndarray, values: np.ndarray, point: int, where: float, at: np.ndarray, log_y: bool) -> float:
    """The value at located r0 ``where`` on the segment between the two family points that bracket the event."""
    i = int(np.clip(np.searchsorted(at, point), 1, len(at) - 1))
    w = np.clip((np.log(where) - np.log(r0[i - 1])) / (np.log(r0[i]) - np.log(r0[i - 1])), 0, 1) \
        if r0[i] != r0[i - 1] else 0.0
    if log_y:
        return float(np.exp((1 - w) * np.log(values[i - 1]) + w * np.log(values[i])))
    return float((1 - w) * values[i - 1] + w * values[i])


def zoom_window(ds: xr.Dataset, families: list[str]) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """(r0/c range, amplitude range) of the families' arcs past their first fold (where they turn back and their
    events crowd), with a margin; None when no family turns."""
    turned, located = [], []
    for family in families:
        at = np.flatnonzero(ds["family"].values == family)
        events = _located_events(ds, family)
        folds = [point for kind, _, point in events if kind == "fold"]
        if folds:
            turned += list(at[at >= min(folds) - 1])
            # a fold is located at the extreme r0 of the turn, just beyond the points that bracket it
            located += [where for _, where, point in events if point >= min(folds)]
    if not turned:
        return None
    ranges = []
    for values in (np.concatenate([ds["r0_over_c"].values[turned], located]), ds["amplitude"].values[turned]):
        low, high = float(values.min()), float(values.max())
        pad = ZOOM_MARGIN * (high - low or abs(high) or 1.0)
        ranges.append((low - pad, high + pad))
    return ranges[0], ranges[1]


@styled
def draw_orbit_family(ds: xr.Dataset) -> Figure:
    fig, axes = subplots(3, 1, width=DOUBLE, height=7.4, sharex="col")
    period_ax, amplitude_ax, error_ax = axes[:, 0]
    families = list(dict.fromkeys(str(f) for f in ds["family"].values))
    labels = ds["family_label"].values if "family_label" in ds else ds["family"].values
    series = [name for name in ds.data_vars if str(name).startswith("error_")]
    styles = ["-", "--", ":", "-."]
    window, heights = zoom_window(ds, families) or (None, None)
    zoom = amplitude_ax.inset_axes([0.6, 0.2, 0.38, 0.76]) if window else None
    for n, family in enumerate(families):
        at = np.flatnonzero(ds["family"].values == family)
        colour = f"C{n}"
        r0 = ds["r0_over_c"].values[at]
        stable = ds["stable"].values[at].astype(bool)
        events = _located_events(ds, family)
        panels = [(period_ax, ds["period"].values[at], True), (amplitude_ax, ds["amplitude"].values[at], False)]
        if zoom is not None:
            panels.append((zoom, ds["amplitude"].values[at], False))
        for ax, values, log_y in panels:
            ax.plot(r0, values, "-", color=colour, lw=0.8, label=str(labels[at[0]]))
            ax.plot(r0[stable], values[stable], "o", ms=3, color=colour, ls="none")
            ax.plot(r0[~stable], values[~stable], "o", ms=3, mfc="none", mec=colour, ls="none")
            for kind, where, point in events:
                inside = window is not None and window[0] <= where <= window[1]
                if inside != (ax is zoom):   # crowded events in the inset only, the others in the main panels
                    continue
                ax.plot([where], [_on_family(r0, values, point, where, at, log_y)], color=colour, ls="none",
                        **EVENT_STYLES[kind])
        for k, name in enumerate(series):
            errors = ds[name].values[at]
            if np.isfinite(errors).any():
                error_ax.plot(r0, np.where(errors > 0, errors, np.nan), styles[k % len(styles)], color=colour, lw=0.8,
                              label=f"_{family}_{name}")
    if zoom is not None:
        zoom.set(xlim=window, ylim=heights)
        zoom.tick_params(labelsize=6)
        zoom.set_title(f"turning arcs, r0 (units of c) from {window[0]:.3g} to {window[1]:.3g}", fontsize=6.5)
        amplitude_ax.indicate_inset_zoom(zoom, edgecolor="0.4")
    for level in LEVELS:
        error_ax.axhline(level, color="0.5", lw=0.6, ls=(0, (2, 2)))
    for k, name in enumerate(series):  # line style = series, colour = family
        error_ax.plot([], [], styles[k % len(styles)], color="0.3", lw=0.8, label=_series_label(str(name)))
    period_ax.plot([], [], "o", ms=3, color="0.3", ls="none", label="stable (filled) / unstable (open)")
    for kind, style in EVENT_STYLES.items():
        period_ax.plot([], [], color="0.3", ls="none", label=f"{kind} (located)", **style)
    period_ax.set(yscale="log", ylabel="period (units of 1/c)")
    amplitude_ax.set_ylabel("nutation amplitude (rad)")
    error_ax.set(yscale="log", ylabel="series error vs exact orbit", xscale="log", xlabel="spin r0 (units of c)")
    legend_outside(fig, [period_ax, amplitude_ax, error_ax], ncols=2)
    fig.suptitle("Periodic-orbit families from fast spin (right) to slow spin (left)")
    return fig


FIGURES = {"orbit_family": draw_orbit_family}
