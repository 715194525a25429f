"""Figure of ``shaker_omega3.nc``: Euler angles θ, ψ and φ − (mean rate) t of the ω = 3 series against the
full model on the exact periodic orbit (the mean spin is removed from φ to show its O(μ²) part)."""

from __future__ import annotations

import xarray as xr

from gyrolab.figures.labels import time_label
from gyrolab.figures.style import SINGLE, Figure, legend_outside, styled, subplots


@styled
def draw_shaker(ds: xr.Dataset) -> Figure:
    fig, axes = subplots(3, 1, width=SINGLE, height=4.6, sharex="col")
    t = ds["time"].values
    for ax, (name, ylabel) in zip(axes[:, 0], (("theta", "θ (rad)"), ("psi", "ψ (rad)"),
                                               ("phi", "φ − (mean rate) t (rad)"))):
        full, series = ds[f"{name}_full"].values, ds[f"{name}_series"].values
        shift = (full[-1] - full[0]) / (t[-1] - t[0]) * t if name == "phi" else 0.0
        ax.plot(t, full - shift, "-", lw=2.0, color="0.7", label="full model (exact periodic orbit)")
        ax.plot(t, series - shift, "--", lw=1.0, color="C1", label="ω = 3 series")
        ax.set_ylabel(ylabel)
    axes[-1, 0].set_xlabel(time_label(ds))
    legend_outside(fig, ncols=1)
    fig.suptitle("ω = 3 resonance: Euler angles")
    return fig


FIGURES = {"shaker_omega3_euler": draw_shaker}
