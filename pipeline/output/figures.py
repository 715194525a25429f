"""Figures of one run, for people: state, invariant drift, Euler angles, body axis on the sphere.

Margins are fixed by hand: matplotlib's layout engines cost more than the drawing itself
and would double the time of a default run.
"""

from __future__ import annotations

import multiprocessing
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

COMPONENTS = ("x", "y", "z")


STATS = {"nfev", "n_steps", "n_rejected", "wall_time", "njev", "nlu"}


def _subtitle(ds: xr.Dataset) -> str:
    """The scene's title and the integrator with its settings (not its statistics)."""
    name = ds.attrs.get("integrator", "?")
    settings = [f"{key.removeprefix('integrator_')}={value:g}" for key, value in ds.attrs.items()
                if key.startswith("integrator_") and key.removeprefix("integrator_") not in STATS]
    if "accuracy" in ds.attrs:
        settings.append(f"accuracy={ds.attrs['accuracy']:g} → {ds.attrs.get('auto_method', '?')}")
    return f"{ds.attrs.get('title', '')}\nfull equations of motion, {name} ({', '.join(settings)})"


def _label(variable: xr.DataArray) -> str:
    """Axis label: long name and units (the long name may already carry the unit in brackets)."""
    long_name = variable.attrs.get("long_name", variable.name)
    return long_name if "[" in long_name else f"{long_name} [{variable.attrs.get('units', '?')}]"


def _time_label(ds: xr.Dataset) -> str:
    return ds.time.attrs.get("long_name", "time")


def plot_state(ds: xr.Dataset) -> plt.Figure:
    fig, (ax_w, ax_g) = plt.subplots(2, 1, sharex=True, figsize=(9, 6))
    fig.subplots_adjust(left=0.12, right=0.97, top=0.86, bottom=0.09, hspace=0.12)
    labels = {"omega": ("p", "q", "r"), "gamma": ("γ", "γ′", "γ″")}
    for ax, name in ((ax_w, "omega"), (ax_g, "gamma")):
        for i, label in enumerate(labels[name]):
            ax.plot(ds.time, ds[name].isel(axis=i), lw=0.8, label=label)
        ax.set_ylabel(_label(ds[name]).replace(" in body axes", "\nin body axes"), fontsize=8)
        ax.legend(loc="lower right", bbox_to_anchor=(1.0, 1.0), fontsize=8, ncol=3, frameon=False)
        ax.grid(alpha=0.3)
    ax_g.set_xlabel(_time_label(ds))
    fig.suptitle(_subtitle(ds), fontsize=9)
    return fig


def plot_invariants(ds: xr.Dataset) -> plt.Figure:
    fig, ax = plt.subplots(figsize=(9, 4.5))
    fig.subplots_adjust(left=0.1, right=0.97, top=0.82, bottom=0.12)
    for name in ds.attrs.get("monitored_invariants", "").split():
        values = ds[name].values
        drift = np.abs(values - values[0])
        drift[drift == 0] = np.nan  # log scale: exact conservation shows as a gap, not a spike
        ax.semilogy(ds.time, drift, lw=0.8, label=f"{name} [{ds[name].attrs['units']}]")
    ax.set_xlabel(_time_label(ds))
    ax.set_ylabel("|I(t) − I(0)|  (absolute drift)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    ax.set_title("drift of the monitored first integrals\n" + _subtitle(ds), fontsize=9)
    return fig


def plot_euler_angles(ds: xr.Dataset) -> plt.Figure:
    names = [n for n in ("psi", "theta", "phi") if n in ds]
    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(9, 2.2 * len(names) + 1))
    fig.subplots_adjust(left=0.12, right=0.97, top=0.86, bottom=0.08, hspace=0.12)
    for ax, name in zip(np.atleast_1d(axes), names):
        ax.plot(ds.time, ds[name], lw=0.8)
        ax.set_ylabel(_label(ds[name]).replace(" (", "\n("), fontsize=8)
        ax.grid(alpha=0.3)
    np.atleast_1d(axes)[-1].set_xlabel(_time_label(ds))
    fig.suptitle("Euler angles (z-x-z)\n" + _subtitle(ds), fontsize=9)
    return fig


def plot_body_axis(ds: xr.Dataset) -> plt.Figure:
    """Trace of the body z axis on the unit sphere of the fixed frame (apex of the body)."""
    fig = plt.figure(figsize=(6.5, 6.5))
    fig.subplots_adjust(left=0.02, right=0.98, top=0.88, bottom=0.02)
    ax = fig.add_subplot(projection="3d")
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi, 19))
    ax.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", lw=0.4)
    gamma = ds["gamma"].values
    if "body_axis_inertial" in ds:  # a system that reports the body axis in its own frames (orbiting gyrostat)
        for name, style in (("body_axis_orbital", "-"), ("body_axis_inertial", "--")):
            trace = ds[name].values
            ax.plot(*trace.T, style, lw=0.8, label=ds[name].attrs.get("long_name", name))
            ax.scatter(*trace[0], color="green", s=25)
        frame = ("axis 1", "axis 2", "axis 3 (orbit normal)")
        trace, label = None, None
    elif "alpha" in ds:
        alpha = ds["alpha"].values
        beta = np.cross(gamma, alpha)
        trace = np.stack([alpha[:, 2], beta[:, 2], gamma[:, 2]], axis=1)  # body z in fixed X, Y, Z
        frame, label = ("X", "Y", "Z (vertical)"), "body z axis in the fixed frame"
    else:  # without the full attitude: the vertical seen from the body
        trace = gamma
        frame, label = ("body x", "body y", "body z"), "fixed vertical in body axes (γ)"
    if trace is not None:
        ax.plot(*trace.T, lw=0.8, label=label)
        ax.scatter(*trace[0], color="green", s=25, label="start")
        ax.scatter(*trace[-1], color="red", s=25, label="end")
    ax.set_xlabel(frame[0])
    ax.set_ylabel(frame[1])
    ax.set_zlabel(frame[2])
    ax.set_box_aspect((1, 1, 1))
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title("trace on the unit sphere (direction cosines, dimensionless)\n" + _subtitle(ds), fontsize=8)
    return fig


PLOTS = {
    "state": plot_state,
    "invariant_drift": plot_invariants,
    "euler_angles": plot_euler_angles,
    "body_axis_sphere": plot_body_axis,
}


def _draw(name: str, ds: xr.Dataset, directory: Path) -> Path:
    fig = PLOTS[name](ds)
    path = directory / f"{name}.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def save_figures(ds: xr.Dataset, directory: Path, workers: int | None = None) -> list[Path]:
    """Draw every figure into ``directory``; on Linux the figures are drawn by forked workers in parallel."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    workers = min(len(PLOTS), os.cpu_count() or 1) if workers is None else workers
    if workers > 1 and "fork" in multiprocessing.get_all_start_methods() and not _daemonic():
        # Forked after matplotlib is imported: a worker costs milliseconds, not an import.
        with multiprocessing.get_context("fork").Pool(workers) as pool:
            return pool.starmap(_draw, [(name, ds, directory) for name in PLOTS])
    return [_draw(name, ds, directory) for name in PLOTS]


def _daemonic() -> bool:
    """Daemonic processes (some launcher workers) may not start children."""
    return multiprocessing.current_process().daemon
