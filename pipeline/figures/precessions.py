"""Figures of ``precession_cases.nc``: for each geometric class of the regular precessions that hold, the
trace of the body z axis on the unit sphere, in the orbital and the inertial frame (one panel each).

Every case is accounted for: a case whose axis stays fixed (a cylindrical precession about the orbit normal
is a point on the sphere) is drawn as a marker, cases fixed at the same point share one marker whose legend
names them all, and cases whose axes run along the same curve share one line, named together.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

import numpy as np
import xarray as xr

from gyrolab.figures.options import DEFAULT_DPI, DEFAULT_FORMATS
from gyrolab.figures.save import save_all
from gyrolab.figures.style import DOUBLE, Figure, figure, legend_outside, styled, unit_sphere

FRAMES = {"orbital": ("body_axis_orbital", ("α (radial)", "β (along-track)", "γ (normal)")),
          "inertial": ("body_axis_inertial", ("X", "Y", "Z (normal)"))}
LINESTYLES = ("-", "--", ":", "-.")
#: a trace that moves less than this on the unit sphere is drawn as a fixed point
FIXED = 1e-3


def classes(ds: xr.Dataset) -> list[str]:
    """Geometric classes with at least one case that holds (one figure each)."""
    holds = [str(v) == "holds" for v in ds["verdict"].values]
    return sorted({str(g) for g, h in zip(ds["geometric"].values, holds) if h})


def _same_path(a: np.ndarray, b: np.ndarray, tol: float = 0.02) -> bool:
    """Whether two traces run along the same curve on the sphere (each point of one near the other)."""
    a, b = a[:: max(1, len(a) // 200)], b[:: max(1, len(b) // 200)]
    d = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=-1)
    return bool(d.min(axis=1).max() < tol and d.min(axis=0).max() < tol)


def _panel(ax, ds: xr.Dataset, cases: list[int], frame: str, variable: str, names: tuple[str, str, str]) -> None:
    unit_sphere(ax)
    fixed: dict[tuple[float, ...], list[str]] = {}
    paths: list[tuple[np.ndarray, list[str]]] = []
    for i in cases:
        trace = ds[variable].values[i]
        trace = trace[np.all(np.isfinite(trace), axis=1)]
        label = str(ds["case"].values[i])
        if np.ptp(trace, axis=0).max() < FIXED:
            fixed.setdefault(tuple(np.round(trace[0], 2) + 0.0), []).append(label)
            continue
        for path, labels in paths:  # cases along the same curve share one line, named together
            if _same_path(path, trace):
                labels.append(label)
                break
        else:
            paths.append((trace, [label]))
    for k, (path, labels) in enumerate(paths):
        ax.plot(*path.T, LINESTYLES[k % len(LINESTYLES)], lw=0.9, color=f"C{k % 8}",
                label=f"{frame} frame: {', '.join(labels)}" + (" (same path)" if len(labels) > 1 else ""))
        ax.scatter(*path[0], s=8, color=f"C{k % 8}", depthshade=False)
    for m, (point, labels) in enumerate(fixed.items()):
        where = ", ".join(f"{v:g}" for v in point)
        ax.scatter(*point, s=30, marker="os^D"[m % 4], facecolors="none", edgecolors="k", depthshade=False,
                   label=f"{frame} frame, fixed at ({where}): {', '.join(labels)}")
    for setter, name in zip((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel), names):
        setter(name, labelpad=-6)


@styled
def draw_class(ds: xr.Dataset, geometric: str) -> Figure:
    cases = [i for i, (g, v) in enumerate(zip(ds["geometric"].values, ds["verdict"].values))
             if str(g) == geometric and str(v) == "holds"]
    fig = figure(DOUBLE, 4.4, layout="none")  # 3-D axes: margins by hand
    fig.subplots_adjust(left=0.0, right=0.93, top=0.9, bottom=0.2, wspace=0.12)
    for j, (frame, (variable, names)) in enumerate(FRAMES.items()):
        ax = fig.add_subplot(1, 2, j + 1, projection="3d")
        _panel(ax, ds, cases, frame, variable, names)
        ax.set_title(f"{frame} frame", fontsize=8, pad=0)
    legend_outside(fig, fig.axes, ncols=2)
    fig.suptitle(f"Regular precessions, {geometric} class: body z axis on the unit sphere")
    return fig


def save_figures(ds: xr.Dataset, directory: str | Path, formats: Iterable[str] = DEFAULT_FORMATS,
                 dpi: int = DEFAULT_DPI) -> list[Path]:
    if "body_axis_orbital" not in ds:  # a dataset written before the traces were stored: nothing to draw from
        return []
    figures = {f"body_axis_{g.replace(' ', '_')}": draw_class(ds, g) for g in classes(ds)}
    return save_all(figures, directory, ds, formats, dpi)
