"""Shaker et al.'s Euler angles θ, ψ, φ against t: the ω = 3 series against the full model (report §9 body).

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
from gyrolab.output.dataset import time_attributes
from gyrolab.experiments.regime_run import compute, prepare
from gyrolab.figures.redraw import write_and_draw
from gyrolab.output.provenance import provenance
from gyrolab.engine.schemas import Task

log = logging.getLogger(__name__)


TASK = Task("shaker_omega3", reads=("regime",))


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
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
    return write_and_draw("shaker_omega3.nc", ds, out_dir, cfg.get("output"))
