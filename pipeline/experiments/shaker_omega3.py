"""Shaker et al.'s Euler angles θ, ψ, φ against t: the ω = 3 series against the full model on the exact periodic orbit,
for the research's body (``conf/experiment/shaker_omega3.yaml``; docs/derivations/seed001_resonant_omega3.md §9).
Writes ``shaker_omega3.nc`` and ``figures/shaker_omega3_euler.png``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig

from gyrolab.output.cf import experiment_dataset, unit_attributes
from gyrolab.output.dataset import time_attributes
from gyrolab.experiments.regime_run import compute, prepare
from gyrolab.figures.redraw import write_and_draw
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
                     **{f"max_error_{k}": v for k, v in errors.items()}})
    experiment_dataset(ds, cfg, "shaker_omega3 experiment (ω = 3 Euler angles against the exact orbit)")
    return write_and_draw("shaker_omega3.nc", ds, out_dir, cfg.get("output"))
