"""Seed 001's Euler angles θ, ψ, φ against t: the ω = 3 series against the full model (report §9 body).

The body is the research's suggestion (docs/derivations/seed001_resonant_omega3.md §9): a = 0.4,
b = 1/7 (A:B:C = 14:5:35, non-physical, ω = 3), r_c = (0.48, 0.36, 0.8), k = N/c² = 1, θ0 = arctan 0.75,
μ = 0.1 (r0 = 8.944 c), t ∈ [0, 20]/c. The full model starts from the exact periodic orbit (shooting),
as the research did. Writes ``shaker_omega3.nc`` and ``figures/shaker_omega3_euler.png``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.output.cf import conform, unit_attributes
from gyrolab.output.dataset import time_attributes, write_dataset
from gyrolab.experiments.regime_run import compute, prepare
from gyrolab.output.provenance import provenance

log = logging.getLogger(__name__)


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    out_dir = Path(out_dir)
    scene, regime, warnings = prepare(cfg)
    t = scene.times
    result = compute(scene, regime, t, full=False)
    data, errors = {}, {}
    for name, long in (("theta", "nutation θ"), ("psi", "precession ψ"), ("phi", "proper rotation φ")):
        series, full = result["angles"]["analytic"][name], result["angles"]["orbit"][name]
        data[f"{name}_series"] = ("time", series, {"units": "rad", "long_name": f"{long}, ω = 3 series ({regime.formula})"})
        data[f"{name}_full"] = ("time", full, {"units": "rad", "long_name": f"{long}, full model on the exact orbit"})
        errors[name] = float(np.abs(series - full).max())
        log.info("max |series − full| of %s over t ∈ [%g, %g]: %.2e rad", name, t[0], t[-1], errors[name])
    body = scene.system.body
    ds = xr.Dataset(data, coords={"time": ("time", t, time_attributes(body))})
    ds.attrs.update({"title": f"ω = 3 Euler angles: {scene.system.title()}", **unit_attributes(body),
                     "regime_warnings": " | ".join(warnings) or "none",
                     "period_series": result["period_analytic"], "period_exact": result["orbit"].period,
                     **{f"max_error_{k}": v for k, v in errors.items()},
                     "config": OmegaConf.to_yaml(cfg, resolve=True), **provenance()})
    conform(ds, source="shaker_omega3 experiment (ω = 3 Euler angles against the exact orbit)")
    written = [write_dataset(ds, out_dir / "shaker_omega3.nc")]
    written.append(_plot(ds, out_dir / "figures" / "shaker_omega3_euler.png", body.time_label))
    return written


def _plot(ds: xr.Dataset, path: Path, time_label: str) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    t = ds.time.values
    for ax, (name, label) in zip(axes, (("theta", "θ [rad]"), ("psi", "ψ [rad]"), ("phi", "φ − r0 t [rad]"))):
        shift = t * float(ds.attrs.get("spin", 0.0)) if name == "phi" else 0.0
        full, series = ds[f"{name}_full"].values, ds[f"{name}_series"].values
        if name == "phi":
            shift = (full[-1] - full[0]) / (t[-1] - t[0]) * t  # remove the mean spin to show the O(μ²) part
        ax.plot(t, full - shift, "-", lw=1.2, label="full model (exact periodic orbit)")
        ax.plot(t, series - shift, "--", lw=1.2, label="ω = 3 series (corrected)")
        ax.set_ylabel(label if name != "phi" else "φ − (mean rate) t [rad]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel(f"time t [{time_label}]")
    fig.suptitle(ds.attrs["title"], fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
