"""Figure of a regime run (``regime.nc``): the analytic periodic solution against the full model, the
exact periodic orbit and (where the regime has one) the reduced system, for p, q, r and γ₃ = cos θ."""

from __future__ import annotations

import xarray as xr

from gyrolab.figures.labels import label, time_label, unit
from gyrolab.figures.style import DOUBLE, Figure, legend_outside, panel_note, styled, subplots

#: source suffix -> (legend, line style); drawn in this order
SOURCES = {"orbit": ("exact periodic orbit (Newton shooting)", dict(ls="-", lw=2.2, color="0.75")),
           "full": ("full model from the analytic t = 0 state", dict(ls="-", lw=0.9, color="C0")),
           "analytic": ("analytic solution", dict(ls="--", lw=1.2, color="C1")),
           "reduced": ("reduced system, integrated", dict(ls=":", lw=1.4, color="C2"))}


#: a rescaling of the series' γ(0) smaller than this is rounding, not worth a word
RESCALE_SHOWN = 1e-9
#: further than this from 1 (gyrolab.experiments.regime_run.NORM_WARNING), the panel of γ₃ says the scene is outside
#: the series' domain
OUTSIDE_NOTE = 1e-3


@styled
def draw_regime_comparison(ds: xr.Dataset) -> Figure:
    rate = unit(ds, ds["omega_analytic"].attrs.get("units"), "rate")
    panels = [("omega", 0, label("p", rate)), ("omega", 1, label("q", rate)), ("omega", 2, label("r", rate)),
              ("gamma", 2, "γ₃ = cos θ")]
    fig, axes = subplots(2, 2, width=DOUBLE, height=4.6, sharex=True)
    t = ds["time"].values
    names = {source: name for source, (name, _) in SOURCES.items()}
    norm = ds.attrs.get("analytic_gamma0_norm")
    if norm is not None and abs(float(norm) - 1.0) > RESCALE_SHOWN:   # the full model's start was rescaled: say so
        names["full"] += f", γ(0) normalised (series |γ| − 1 = {float(norm) - 1:.2g})"
    for ax, (var, i, ylabel) in zip(axes.flat, panels):
        for source, (_, style) in SOURCES.items():
            if f"{var}_{source}" in ds:
                ax.plot(t, ds[f"{var}_{source}"].values[:, i], label=names[source], **style)
        ax.set_ylabel(ylabel)
    for ax in axes[1]:
        ax.set_xlabel(time_label(ds))
    regime = ds.attrs.get("regime", ds.attrs.get("title", "regime").split(":")[0])
    value = ds.attrs.get("regime_parameter_value")
    if value is not None:
        panel_note(axes[0, 0], f"{ds.attrs.get('regime_parameter', 'parameter')} = {float(value):.4g}")
    if "series_order" in ds.attrs:  # a regime with a series of configurable order
        panel_note(axes[0, 1], f"order-{ds.attrs['series_order']} series: error slope "
                               f"{float(ds.attrs['series_error_slope']):.2f}, radius of convergence c/r₀ = "
                               f"{float(ds.attrs['series_radius_of_convergence']):.3g}")
    if norm is not None and abs(float(norm) - 1.0) > OUTSIDE_NOTE:
        panel_note(axes[1, 1], f"series |γ(0)| = {float(norm):.5g}: outside its domain")
    legend_outside(fig, ncols=2)
    fig.suptitle(f"Regime {regime}: analytic solution against the full model")
    return fig


FIGURES = {"regime_comparison": draw_regime_comparison}
