"""Figures of ``work_precision.nc``: error of the final state against what each method costs.

* ``error_vs_wall_time`` -- every method against the smallest CPU time of the repeats of a whole run
  (files written before CPU time was measured: their best wall time)
  (``Scene.run``), so ``auto`` includes its pilot runs and its choice.
* ``error_vs_nfev`` -- only the methods whose evaluations are right-hand-side calls. Taylor's are
  evaluations of an order-N series (each costs far more than one right-hand side), ``lie_poisson``'s
  are exact sub-flows and ``auto`` mixes its pilot runs with the method it chose: they are compared in
  wall time only, and the figure says so.

Every method keeps one marker in both figures; methods whose points coincide (dop853 and
dop853_numba take the same steps) are drawn with open and filled markers of different sizes and the
legend says which coincide, so no series hides another.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from gyrolab.figures.style import SINGLE, Figure, legend_outside, log_positive, panel_note, styled, subplots
from gyrolab.figures.evaluations import chooses_method, nfev_counts

MARKERS = "osD^v<>ph*"


def _methods(ds: xr.Dataset) -> list[str]:
    return list(dict.fromkeys(str(m) for m in ds["method"].values))


def _points(ds: xr.Dataset, method: str, x: str) -> tuple[np.ndarray, np.ndarray]:
    """A method's (cost, error) in the order of its settings (so the line follows the tolerance, not the cost)."""
    pick = np.array([str(m) == method for m in ds["method"].values])
    return ds[x].values[pick].astype(float), ds["error"].values[pick].astype(float)


def _coincide(xs: np.ndarray, errs: np.ndarray, other: tuple[np.ndarray, np.ndarray]) -> bool:
    """Whether any point of a method lies on a point of another (same cost and error to 1e-9)."""
    ox, oe = other
    return bool(np.any(np.isclose(xs[:, None], ox[None, :], rtol=1e-9) & np.isclose(errs[:, None], oe[None, :], rtol=1e-9)))


def _draw(ds: xr.Dataset, x: str, methods: list[str], xlabel: str) -> Figure:
    fig, axes = subplots(1, 1, width=SINGLE, height=3.6)
    ax = axes[0, 0]
    everyone = _methods(ds)
    drawn: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    zeros = []
    for method in methods:
        k = everyone.index(method)
        xs, errs = _points(ds, method, x)
        same = [other for other, points in drawn.items() if _coincide(xs, errs, points)]
        label = method + (f" (points coincide with {', '.join(same)})" if same else "")
        ax.plot(xs, log_positive(errs), marker=MARKERS[k % len(MARKERS)], ms=2.5 if same else 5.5, lw=0.8,
                color=f"C{k % 8}", mfc=f"C{k % 8}" if same else "none", zorder=3 if same else 2, label=label)
        drawn[method] = (xs, errs)
        if np.any(errs <= 0):
            zeros.append(method)
    ax.set(xscale="log", yscale="log", xlabel=xlabel, ylabel="max-norm error of the final (ω, γ)")
    ax.grid(True, which="both", alpha=0.2)
    if zeros:
        panel_note(ax, f"error exactly 0 (not drawn): {', '.join(zeros)}")
    legend_outside(fig, [ax], ncols=2)
    return fig


@styled
def draw_error_vs_wall_time(ds: xr.Dataset) -> Figure:
    """Error against the smallest CPU time of a whole run, every method (auto: pilot runs included).

    The figure keeps its name; a file written before CPU time was measured is drawn against its wall time.
    """
    if "cpu_time" in ds:
        fig = _draw(ds, "cpu_time", _methods(ds), "CPU time of one run (s), minimum of the repeats")
    else:
        fig = _draw(ds, "wall_time", _methods(ds), "wall time of one run (s), best of the repeats")
    choosers = [m for m in _methods(ds) if chooses_method(m)]
    if choosers:
        panel_note(fig.axes[0], f"{', '.join(choosers)}: {'its' if len(choosers) == 1 else 'their'} pilot runs included")
    fig.suptitle("Work against precision: CPU time" if "cpu_time" in ds else "Work against precision: wall time")
    return fig


@styled
def draw_error_vs_nfev(ds: xr.Dataset) -> Figure:
    """Error against right-hand-side calls, for the methods whose evaluations are right-hand-side calls."""
    methods = _methods(ds)
    counts = _nfev_counts(ds)
    counted = [m for m in methods if not counts[m]]
    fig = _draw(ds, "nfev", counted, "right-hand-side evaluations")
    left_out = [m for m in methods if counts[m]]
    if left_out:
        panel_note(fig.axes[0], f"not shown: {', '.join(left_out)} (their evaluations are not\n"
                                "right-hand-side calls; compare them in wall time)")
    fig.suptitle("Work against precision: right-hand-side calls")
    return fig


def _nfev_counts(ds: xr.Dataset) -> dict[str, str]:
    """Method -> what its ``nfev`` counts where not right-hand-side calls ('' for calls): the experiment's record
    (variable ``nfev_counts``), else the integrator class of that name (datasets written before the record)."""
    if "nfev_counts" in ds:
        recorded: dict[str, str] = {}
        for method, label in zip(ds["method"].values, ds["nfev_counts"].values):
            recorded[str(method)] = recorded.get(str(method)) or str(label)
        return recorded
    return {m: nfev_counts(m) for m in _methods(ds)}


FIGURES = {"error_vs_wall_time": draw_error_vs_wall_time, "error_vs_nfev": draw_error_vs_nfev}
