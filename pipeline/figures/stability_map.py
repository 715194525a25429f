"""Figure of ``stability_map.nc``: a chaos indicator over the (θ0, r0) plane, with the regimes and example scenes.

Left: the indicator (MEGNO ⟨Y⟩ by default) as a colour map, clipped at ``CLIP`` (⟨Y⟩ ≥ 8 is chaotic beyond doubt
over any useful span; the colour bar's upper end is open), the contour ⟨Y⟩ = ``REGULAR_EDGE`` separating regular
(⟨Y⟩ → 2) from chaotic motion, the regimes' domains of ``docs/regimes.md`` (small parameter: r0/c ≥ 5, large
parameter: r0/c ≤ 0.2, resonance ω = 3: a body property, noted) and the seeds' example scenes. Right: the max
deviation of the nutation angle. Below, when the dataset has them (``gyrolab.analysis.chaos.section_dataset``):
the Poincaré sections of a few points, marked on the map by number.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import xarray as xr
import matplotlib
from matplotlib.colors import Normalize

from gyrolab.errors import ConfigError, OutputError
from gyrolab.figures.options import DEFAULT_DPI, DEFAULT_FORMATS
from gyrolab.figures.save import save_all
from gyrolab.figures.style import DOUBLE, Axes, Figure, figure, panel_note, styled
from gyrolab.output.user_yaml import stored_yaml

#: colour scale of MEGNO: 0 (stable periodic) … 2 (quasi-periodic) … CLIP and beyond (chaotic)
CLIP = 8.0
#: ⟨Y⟩ above this at the end of the span counts as chaotic on the map (its contour is drawn)
REGULAR_EDGE = 4.0
#: the regimes' domains in r0/c (docs/regimes.md): small parameter ε = c/r0 ≤ 0.2, large parameter r0/c ≤ 0.2
SMALL_PARAMETER_MIN = 5.0
LARGE_PARAMETER_MAX = 0.2
#: the seeds' example scenes, (label, θ0 in rad, r0 in units of c): conf/initial and conf/experiment
EXAMPLES = (
    ("fast_spin (reference scene)", 1.0, 5.0),
    ("slow_spin (Ismail 2021's setting)", 1.5, 0.1),
    ("shaker_omega3 (Shaker et al., own body)", 0.6435011087932844, 8.94427190999916),
)


def _values(ds: xr.Dataset, name: str) -> np.ndarray:
    """``ds[name]`` as a (theta0, r0) array."""
    return ds[name].transpose("theta0", "r0").values.astype(float)


def _edges(centres: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around grid centres (geometric means on a log axis)."""
    c = np.log(centres) if log else np.asarray(centres, dtype=float)
    if c.size == 1:
        e = np.array([c[0] - 0.5, c[0] + 0.5])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        e = np.concatenate([[2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]])
    return np.exp(e) if log else e


def _r0_scale(ds: xr.Dataset) -> float | None:
    """c in the units of the r0 coordinate (1 for a nondimensional body), or None when unknown."""
    units = str(ds["r0"].attrs.get("units", "1"))
    if units in ("1", ""):
        return 1.0
    c2 = ds.attrs.get("body_nondim_c2")
    return math.sqrt(float(c2)) if c2 is not None and float(c2) > 0 else None


def _body_omega(ds: xr.Dataset) -> float | None:
    """The body's natural frequency ω, ω² = (a − 1)(b − 1)/(ab) (docs/regimes.md), when the dataset names a, b."""
    a, b = ds.attrs.get("body_nondim_a", ds.attrs.get("body_a")), ds.attrs.get("body_nondim_b", ds.attrs.get("body_b"))
    if a is None or b is None:
        return None
    w2 = (float(a) - 1.0) * (float(b) - 1.0) / (float(a) * float(b))
    return math.sqrt(w2) if w2 > 0 else None


def _stored_system(ds: xr.Dataset) -> tuple[str, dict]:
    """(the system's class name, the body section) of the map's stored config (checked as untrusted input); ("", {})
    when the dataset holds none: the fixed point's annotations are then drawn as before."""
    try:
        config = stored_yaml(ds.attrs.get("config", ""), "the map's stored config") if "config" in ds.attrs else {}
    except ConfigError:
        return "", {}
    config = config if isinstance(config, dict) else {}
    target = str((config.get("system") or {}).get("_target_", ""))
    return target.rpartition(".")[2], dict(config.get("body") or {})


def _rate_unit(ds: xr.Dataset) -> str:
    """The r0 axis's unit: the coordinate's CF units, or the nondimensional rate unit of the map's system."""
    units = str(ds["r0"].attrs.get("units", "1"))
    if units not in ("1", ""):
        return units
    system, body = _stored_system(ds)
    if system == "OrbitingGyrostat":
        return "units of Ω" if float(body.get("orbit_rate", 1.0) or 1.0) == 1.0 else "model rate"
    return "units of c"


def _com_on_z(ds: xr.Dataset) -> bool:
    """Whether the map's body has its centre of mass on the body +z axis (the large-parameter regime's domain)."""
    com = ds.attrs.get("body_nondim_com_direction")
    if com is None:
        return False
    x, y, z = (float(v) for v in np.atleast_1d(com)[:3])
    return abs(x) <= 1e-9 and abs(y) <= 1e-9 and z > 0


def _indicator_label(ds: xr.Dataset) -> str:
    attrs = ds["indicator"].attrs
    name = str(attrs.get("indicator_name", "indicator"))
    if name == "MEGNO":
        return "MEGNO ⟨Y⟩ (2 regular, 0 periodic, ≫ 2 chaotic)"
    return f"{name} ({attrs.get('units', '1')})"


def _mark_regimes(ax: Axes, ds: xr.Dataset, r_lo: float, r_hi: float) -> None:
    c = _r0_scale(ds)
    if c is None:
        panel_note(ax, "regime domains not drawn: c unknown for this r0 unit")
        return
    spans = [(SMALL_PARAMETER_MIN * c, r_hi, "small parameter (r0/c ≥ 5)", "//")]
    if _com_on_z(ds):
        spans.append((r_lo, LARGE_PARAMETER_MAX * c, "large parameter (r0/c ≤ 0.2)", "\\\\"))
    else:  # the slow-spin regime is derived for a centre of mass on the body +z axis only (docs/regimes.md)
        panel_note(ax, "large parameter (slow spin): not for this body, its centre of mass is off the z axis")
    for lo, hi, label, hatch in spans:
        lo, hi = max(lo, r_lo), min(hi, r_hi)
        if lo < hi:
            ax.axvspan(lo, hi, facecolor="none", edgecolor="0.6", hatch=hatch, lw=0.0, label=label)
            ax.axvline(lo if hi == r_hi else hi, color="0.6", lw=0.8, ls="--")
    omega = _body_omega(ds)
    if omega is None or abs(omega - 3.0) > 1e-6:
        text = f"ω = {omega:.3g}" if omega is not None else "ω unknown"
        panel_note(ax, f"resonance ω = 3 is not on this map ({text}: a property of the body, not of θ0, r0)")


def _mark_examples(ax: Axes, ds: xr.Dataset, t_lo: float, t_hi: float, r_lo: float, r_hi: float) -> None:
    c = _r0_scale(ds)
    if c is None:
        return
    for (label, theta0, r0), marker in zip(EXAMPLES, ("*", "P", "X")):
        if t_lo <= theta0 <= t_hi and r_lo <= r0 * c <= r_hi:
            ax.plot(r0 * c, theta0, marker, ms=8, mfc="white", mec="black", mew=0.7, ls="none", label=label)


@styled
def draw_stability_map(ds: xr.Dataset) -> Figure:
    if "indicator" not in ds or not {"theta0", "r0"} <= set(ds["indicator"].dims):
        raise OutputError("a stability map needs a variable 'indicator' over the dimensions (theta0, r0)")
    n_sections = int(ds.sizes.get("section_point", 0)) if "section_phi" in ds else 0
    fig = figure(DOUBLE, 3.6 + (2.2 if n_sections else 0.0))
    grid = fig.add_gridspec(2 if n_sections else 1, max(2, n_sections), height_ratios=[1.7, 1] if n_sections else [1])
    top = grid[0, :].subgridspec(1, 2, width_ratios=[1.25, 1])
    map_ax, dev_ax = fig.add_subplot(top[0]), fig.add_subplot(top[1])
    theta0, r0 = ds["theta0"].values.astype(float), ds["r0"].values.astype(float)
    log_r = bool(np.all(r0 > 0) and r0.size > 1 and r0.max() / r0.min() > 20)
    r_edges, t_edges = _edges(r0, log_r), _edges(theta0, False)
    indicator = _values(ds, "indicator")
    is_megno = str(ds["indicator"].attrs.get("indicator_name", "MEGNO")) == "MEGNO"
    norm = Normalize(0.0, CLIP) if is_megno else Normalize(*np.nanpercentile(indicator, [1, 99]))
    cmap = matplotlib.colormaps["magma"].with_extremes(bad="0.75")
    mesh = map_ax.pcolormesh(r_edges, t_edges, np.ma.masked_invalid(indicator), cmap=cmap, norm=norm,
                             shading="flat", rasterized=True)
    bar = fig.colorbar(mesh, ax=map_ax, extend="max" if is_megno else "neither", pad=0.02)
    bar.set_label(_indicator_label(ds), fontsize=7)
    if is_megno and indicator.size > 3 and np.isfinite(indicator).any() and r0.size > 1 and theta0.size > 1:
        map_ax.contour(r0, theta0, np.where(np.isfinite(indicator), indicator, CLIP), levels=[REGULAR_EDGE],
                       colors="cyan", linewidths=0.6)
        map_ax.plot([], [], color="cyan", lw=0.6, label=f"⟨Y⟩ = {REGULAR_EDGE:g}")
    if np.isnan(indicator).any():
        panel_note(map_ax, f"grey: {int(np.isnan(indicator).sum())} failed points")
    r_lo, r_hi, t_lo, t_hi = r_edges[0], r_edges[-1], t_edges[0], t_edges[-1]
    system = _stored_system(ds)[0]
    if system in ("", "FixedPoint"):  # the papers' regimes and example scenes are the heavy body's
        _mark_regimes(map_ax, ds, r_lo, r_hi)
        _mark_examples(map_ax, ds, t_lo, t_hi, r_lo, r_hi)
    if "max_nutation_deviation" in ds:
        dev = dev_ax.pcolormesh(r_edges, t_edges, np.ma.masked_invalid(_values(ds, "max_nutation_deviation")),
                                cmap="viridis", shading="flat", rasterized=True)
        fig.colorbar(dev, ax=dev_ax, pad=0.02).set_label("max |θ − θ0| (rad)", fontsize=7)
    else:
        dev_ax.set_axis_off()
    r_unit = _rate_unit(ds)
    for ax in (map_ax, dev_ax):
        ax.set(xscale="log" if log_r else "linear", xlim=(r_lo, r_hi), ylim=(t_lo, t_hi),
               xlabel=f"initial spin r0 ({r_unit})", ylabel="initial nutation θ0 (rad)")
        ax.grid(False)
    if n_sections:
        _draw_sections(fig, grid, ds, map_ax, n_sections)
    handles, labels = map_ax.get_legend_handles_labels()
    if labels:
        fig.legend(handles, labels, loc="outside lower center", ncols=min(3, len(labels)), fontsize=6.5)
    fig.suptitle("Stability map: chaos indicator over initial nutation and spin")
    return fig


def _draw_sections(fig: Figure, grid, ds: xr.Dataset, map_ax: Axes, count: int) -> None:
    for k in range(count):
        ax = fig.add_subplot(grid[1, k])
        phi = ds["section_phi"].values[k]
        r = ds["section_r"].values[k]
        ax.plot(np.mod(phi, 2 * np.pi), r, ",", color=f"C{k}", ms=1, rasterized=True)
        ax.plot(np.mod(phi, 2 * np.pi), r, ".", color=f"C{k}", ms=0.8, rasterized=True)
        t0, rr = float(ds["section_theta0"].values[k]), float(ds["section_r0"].values[k])
        ax.set_title(f"{k + 1}: θ0 = {t0:.2f}, r0 = {rr:.3g}", fontsize=7)
        ax.set_xlim(0, 2 * np.pi)
        ax.set_xlabel("φ at γ3 = cos θ0 (rad)", fontsize=7)
        if k == 0:
            ax.set_ylabel("spin ω3", fontsize=7)
        map_ax.annotate(str(k + 1), (rr, t0), color="white", fontsize=7, fontweight="bold", ha="center", va="center",
                        bbox={"boxstyle": "circle,pad=0.15", "fc": f"C{k}", "ec": "white", "lw": 0.5})


FIGURES = {"stability_map": draw_stability_map}


def draw(ds: xr.Dataset, directory: str | Path, formats: Iterable[str] = DEFAULT_FORMATS,
         dpi: int = DEFAULT_DPI) -> list[Path]:
    """Write ``stability_map.<format>`` drawn from ``ds`` into ``directory``; returns the paths."""
    return save_all({"stability_map": draw_stability_map(ds)}, directory, ds, tuple(formats), dpi)
