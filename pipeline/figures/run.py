"""Figures of one run (``run.nc``): state, invariant drift, Euler angles, body axis on the unit sphere.

A series that oscillates too fast for its panel (the spin of a fast top over a long run) is drawn as its
min–max envelope, and a second column shows the leading window with the oscillations resolved; the
panels say which is which.
"""

from __future__ import annotations

import gc
import multiprocessing
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import xarray as xr

from gyrolab.figures.labels import GAMMA, label, time_label, unit
from gyrolab.figures.options import DEFAULT_DPI, DEFAULT_FORMATS
from gyrolab.figures.save import metadata_of, save
from gyrolab.figures.style import (DOUBLE, SINGLE, Figure, fast_window, figure, fit, legend_outside, log_positive,
                                   panel_note, styled, subplots, trace, unit_sphere)

#: invariant variable -> (symbol in a legend, kind of unit)
INVARIANTS = {"energy": ("energy E", "energy"), "jacobi_integral": ("Jacobi integral H", "energy"),
              "area_integral": ("area integral Iω·γ", "momentum"), "gamma_norm": ("norm |γ|", "1"),
              "frame_error": ("frame orthonormality error", "1")}


def _rows(ds: xr.Dataset) -> list[tuple[str, list[int], list[str], str]]:
    """(variable, components, legend labels, y label) of the state panels: p, q | r | γ."""
    rate = unit(ds, ds["omega"].attrs.get("units"), "rate")
    kind = "absolute " if "absolute" in ds["omega"].attrs.get("long_name", "") else ""  # the gyrostat's ω
    vector = "orbit normal" if ds.attrs.get("system") == "orbiting_gyrostat" else "vertical Z"
    return [("omega", [0, 1], ["p", "q"], label(f"{kind}p, q", rate)), ("omega", [2], ["r"], label(f"{kind}r", rate)),
            ("gamma", [0, 1, 2], list(GAMMA), f"γ ({vector}\nin body axes)")]


@styled
def draw_state(ds: xr.Dataset) -> Figure:
    """ω = (p, q, r) and γ = (γ₁, γ₂, γ₃) against time: p, q and r on separate axes; the full span (as an
    envelope where the line would be a solid band) and, when it differs, the leading window."""
    t = ds["time"].values
    rows = _rows(ds)
    window = fast_window(t, [ds[v].values[:, i] for v, comps, _, _ in rows for i in comps])
    ncols = 1 if window == slice(None) else 2
    fig, axes = subplots(3, ncols, width=SINGLE if ncols == 1 else DOUBLE, height=5.2, layout="none", sharex="col")
    enveloped = []
    for row, (name, comps, labels, ylabel) in enumerate(rows):
        for j, (i, lab) in enumerate(zip(comps, labels)):
            color = f"C{j if row != 1 else 2}"
            if trace(axes[row, 0], t, ds[name].values[:, i], label=lab, color=color):
                enveloped.append(lab)
            if ncols == 2:
                axes[row, 1].plot(t[window], ds[name].values[window, i], color=color)
        axes[row, 0].set_ylabel(ylabel)
        axes[row, -1].legend(*axes[row, 0].get_legend_handles_labels(), loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    for ax in axes[-1]:
        ax.set_xlabel(time_label(ds))
    if ncols == 2:
        panel_note(axes[0, 0], "whole run" + (f" ({', '.join(enveloped)}: min–max envelope, too dense for lines)"
                                              if enveloped else ""))
        panel_note(axes[0, 1], f"leading window, t ≤ {t[window][-1]:.3g}")
    fig.suptitle("Angular velocity and direction cosines in body axes")
    fit(fig, axes)
    return fig


@styled
def draw_invariants(ds: xr.Dataset) -> Figure:
    """Absolute drift |I(t) − I(0)| of every monitored first integral (log scale; exact zeros are gaps)."""
    fig, axes = subplots(1, 1, width=SINGLE, height=2.9, layout="none")
    ax = axes[0, 0]
    exact, violated = [], []
    for name in ds.attrs.get("monitored_invariants", "").split():
        if name not in ds:
            continue
        symbol, kind = INVARIANTS.get(name, (ds[name].attrs.get("long_name", name), "1"))
        if ds[name].attrs.get("invariant_check") == "violated":  # run.nc says the run does not conserve it
            violated.append(symbol)
            continue
        values = ds[name].values
        drift = log_positive(np.abs(values - values[0]))
        if not np.isfinite(drift).any():
            exact.append(symbol)
            continue
        ax.plot(ds["time"].values, drift, lw=0.8, label=label(symbol, unit(ds, ds[name].attrs.get("units"), kind)))
    ax.set(yscale="log", xlabel=time_label(ds), ylabel="absolute drift |I(t) − I(0)|")
    ax.grid(True, which="both", alpha=0.25)
    if exact:
        panel_note(ax, f"conserved exactly (not drawn): {', '.join(exact)}")
    if violated:
        panel_note(ax, f"NOT conserved by this run (flagged violated in run.nc, not drawn): {', '.join(violated)}")
    legend_outside(fig, [ax], ncols=1)
    fit(fig, axes)
    return fig


@styled
def draw_euler_angles(ds: xr.Dataset) -> Figure:
    """Euler angles ψ, θ, φ (z-x-z, unwrapped) against time."""
    names = [(n, s) for n, s in (("psi", "precession ψ"), ("theta", "nutation θ"), ("phi", "proper rotation φ"))
             if n in ds]
    fig, axes = subplots(len(names), 1, width=SINGLE, height=1.0 + 1.3 * len(names), layout="none",
                         sharex="col")
    notes = []
    for ax, (name, symbol) in zip(axes[:, 0], names):
        if trace(ax, ds["time"].values, ds[name].values, color="C0"):
            notes.append(symbol.split()[-1])
        ax.set_ylabel(label(symbol.split()[-1], unit(ds, ds[name].attrs.get("units"), "angle")))
    axes[-1, 0].set_xlabel(time_label(ds))
    if notes:
        panel_note(axes[0, 0], f"{', '.join(notes)}: min–max envelope (too dense to draw as lines)")
    fig.suptitle("Euler angles (z-x-z)")
    fit(fig, axes)
    return fig


@styled
def draw_body_axis(ds: xr.Dataset) -> Figure:
    """Trace of the body z axis on the unit sphere of the fixed (or orbital/inertial) frame.

    gyrolab's fixed Z points along the weight (down): the Z axis of the plot is drawn pointing down, so
    that up on the page is up in the world.
    """
    fig = figure(SINGLE, SINGLE + 0.4, layout="none")  # 3-D axes: margins by hand
    fig.subplots_adjust(left=0.0, right=0.9, top=0.93, bottom=0.14)
    ax = fig.add_subplot(projection="3d")
    unit_sphere(ax)
    traces = []
    if "body_axis_inertial" in ds:  # the orbiting gyrostat reports the body axis in its own frames
        for name, style in (("body_axis_orbital", "-"), ("body_axis_inertial", "--")):
            traces.append((ds[name].values, style, "body z axis, " + name.removeprefix("body_axis_") + " frame"))
        names, down = ("axis 1", "axis 2", "axis 3 (orbit normal)"), False
    elif "alpha" in ds:
        gamma, alpha = ds["gamma"].values, ds["alpha"].values
        beta = np.cross(gamma, alpha)
        traces.append((np.stack([alpha[:, 2], beta[:, 2], gamma[:, 2]], axis=1), "-", "body z axis in the fixed frame"))
        names, down = ("X", "Y", "Z (along the weight)"), True
    else:  # without the full attitude: the vertical seen from the body
        traces.append((ds["gamma"].values, "-", "vertical Z in body axes (γ)"))
        names, down = ("body x", "body y", "body z"), False
    for values, style, lab in traces:
        ax.plot(*values.T, style, lw=0.7, label=lab)
    start, end = traces[0][0][0], traces[0][0][-1]
    ax.scatter(*start, color="C2", s=14, depthshade=False, label="start")
    ax.scatter(*end, color="C1", s=14, marker="s", depthshade=False, label="end")
    for setter, name in zip((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel), names):
        setter(name, labelpad=-6)
    if down:
        ax.invert_zaxis()  # Z along the weight: drawn pointing down
    legend_outside(fig, [ax], ncols=2, where="lower center")
    fig.suptitle("Body axis on the unit sphere")
    return fig


FIGURES: dict[str, Callable[[xr.Dataset], Figure]] = {"state": draw_state, "invariant_drift": draw_invariants,
                                                       "euler_angles": draw_euler_angles,
                                                       "body_axis_sphere": draw_body_axis}


def _draw(name: str, ds: xr.Dataset, directory: Path, formats: tuple[str, ...], dpi: int) -> list[Path]:
    fig = FIGURES[name](ds, dpi=dpi if "png" in formats else None)
    return save(fig, directory / name, formats, dpi, metadata_of(ds, fig._suptitle.get_text() if fig._suptitle else name))


def save_figures(ds: xr.Dataset, directory: str | Path, formats: Iterable[str] = DEFAULT_FORMATS,
                 dpi: int = DEFAULT_DPI) -> list[Path]:
    """Draw every run figure into ``directory``. On Linux a forked worker draws the state figure (about half the
    work) while this process draws the others: one fork, not a pool of two (docs/performance.md, "The default
    run")."""
    directory, formats = Path(directory), tuple(formats)
    jobs = [(name, ds, directory, formats, dpi) for name in FIGURES]
    pool = None
    if "fork" in multiprocessing.get_all_start_methods() and not multiprocessing.current_process().daemon:
        # forked after matplotlib is imported: the worker costs milliseconds, not an import; the parent's objects
        # are frozen out of its collections and, short-lived, it collects nothing
        gc.freeze()
        pool = multiprocessing.get_context("fork").Pool(1, initializer=gc.disable)
        forked = pool.apply_async(_draw, jobs.pop(0))
    try:
        results = [_draw(*job) for job in jobs]
        if pool is not None:
            results.insert(0, forked.get())
    finally:
        if pool is not None:
            # close and join, not the context manager's terminate(): terminate kills the worker, and one killed while
            # it held the task queue's lock left the run waiting for that lock (a hung run)
            pool.close()
            pool.join()
            gc.unfreeze()
    return [path for paths in results for path in paths]
