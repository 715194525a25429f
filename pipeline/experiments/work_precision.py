"""Work against precision: every integrator × setting on one scene, errors against a reference of known accuracy.

Timed by the minimum CPU time of the process (``time.process_time``: numba's parallel kernels count all their
threads) over ``repeats`` runs: on a shared machine the wall time depends on who else runs, and the minimum drops
the preempted repeats. The dataset's ``timing`` and reference attributes say how it was measured.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf, open_dict

from gyrolab.contracts.integrator import NFEV_COUNTS_ATTRIBUTE
from gyrolab.engine import schemas
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene
from gyrolab.engine.schemas import Task
from gyrolab.errors import ConfigError
from gyrolab.figures.redraw import write_and_draw
from gyrolab.kernels import layout
from gyrolab.output.cf import experiment_dataset
from gyrolab.physics.reference import fixed_point_reference
from gyrolab.plugins.integrators.compiled_solvers import Taylor

log = logging.getLogger(__name__)
#: how cpu_time was measured (the dataset's ``timing`` attribute)
TIMING = ("cpu_time: time.process_time() around Scene.run() (CPU time of the whole process, every thread), "
          "minimum over {} repeats after one untimed run that compiles or loads the kernels; "
          "wall_time: time.perf_counter(), minimum over the same repeats")
SETTING_KEYS = {"rtol": ("rtol", "atol"), "tol": ("tol",), "step": ("step",), "accuracy": ("accuracy",)}


TASK = Task("work_precision", reads=("output.error_estimate",), section="work_precision",
            settings=schemas.WorkPrecision, sets={
                "integrator": "it runs every method of work_precision.methods",
                "accuracy": "auto's settings are listed in work_precision.methods",
                "time.n_output": "it compares final states, with time.n_output=2"})


def check(cfg: DictConfig, out_dir: Path) -> None:
    """The refusals before the run directory exists: a method's setting that its integrator does not read
    (``methods: {taylor: {accuracy: [1e-8]}}`` would run taylor at its own tolerance under the label accuracy=1e-08)."""
    methods = OmegaConf.to_container(cfg.work_precision, resolve=True).get("methods") or {}
    for method, settings in methods.items():
        for key, values in (settings or {}).items():
            if key == "accuracy" and values:
                try:
                    compose_config([f"integrator={method}", f"accuracy={values[0]!r}"])  # refuses a value not read
                except ConfigError as refused:
                    raise ConfigError(f"work_precision.methods.{method}.accuracy: {refused}") from None


def _scene_for(cfg: DictConfig, method: str, key: str, value: float) -> Scene:
    overrides = [f"integrator={method}"]
    overrides += [f"accuracy={value!r}"] if key == "accuracy" else [f"integrator.{k}={value!r}" for k in SETTING_KEYS[key]]
    base = OmegaConf.to_container(cfg, resolve=True)
    scene_cfg = compose_config(overrides)
    with open_dict(scene_cfg):
        for section in ("system", "body", "initial", "force", "time", "output"):
            scene_cfg[section] = base[section]
        scene_cfg.output.figures = False
        scene_cfg.time.n_output = 2
    return Scene.from_config(scene_cfg)


def reference_state(scene: Scene) -> tuple[np.ndarray, str]:
    """Final (ω, γ) of the scene from the most accurate reference available, and its name."""
    compiled = scene.compiled_model
    if compiled is None or compiled.built_in is None:  # the built-in torque forms only
        raise ConfigError("work_precision needs a scene whose forces have compiled forms (for its reference run)")
    p = compiled.built_in
    y0 = scene.system.initial_state()[:6]
    if not layout.torques_on_horizontal_axes(p):
        ref = fixed_point_reference(p[layout.INERTIA:layout.INERTIA + 3], p[layout.U_Z:layout.U_Z + 3],
                                    p[layout.N_Z], y0, scene.times[[0, -1]])
        return ref[-1].astype(float), "extended-precision Taylor (gyrolab.physics.reference)"
    sol = Taylor(order=24, tol=1e-18).integrate(scene.system.rhs, scene.times, scene.system.initial_state(), None,
                                                compiled)
    return sol.y[-1, :6], "compiled Taylor, order 24, tol 1e-18 (double precision)"


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    spec = OmegaConf.to_container(cfg.work_precision, resolve=True)
    repeats = int(spec.get("repeats", 3))
    rows: list[dict[str, Any]] = []
    reference, reference_name, scene_title = None, "", ""
    for method, settings in spec["methods"].items():
        (key, values), = settings.items()
        if key not in SETTING_KEYS:
            raise ConfigError(f"work_precision.methods.{method}.{key} is not a setting; valid: {', '.join(SETTING_KEYS)}")
        for value in values:
            scene = _scene_for(cfg, method, key, value)
            if reference is None:
                reference, reference_name = reference_state(scene)
                scene_title = f"{scene.system.title()}, t ∈ [{scene.times[0]:g}, {scene.times[-1]:g}]"
                log.info("reference: %s", reference_name)
            scene.run()  # compile or load kernels outside the timing
            best, best_wall, ds = np.inf, np.inf, None
            for _ in range(repeats):
                start, start_wall = time.process_time(), time.perf_counter()
                ds = scene.run()
                best = min(best, time.process_time() - start)
                best_wall = min(best_wall, time.perf_counter() - start_wall)
            final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
            error = float(np.max(np.abs(final - reference)))
            drift = float(ds.energy.attrs["max_abs_drift"]) if "energy" in ds else np.nan
            rows.append({"method": method, "setting": f"{key}={value:g}", "error": error, "cpu_time": best, "wall_time": best_wall,
                         "nfev": int(ds.attrs["integrator_nfev"]), "energy_drift": drift,
                         "nfev_counts": str(ds.attrs.get(NFEV_COUNTS_ATTRIBUTE, ""))})
            log.info("%-13s %-14s error %.2e  %.4f s CPU  nfev %d", method, f"{key}={value:g}", error, best,
                     rows[-1]["nfev"])
    result = _dataset(rows, cfg, reference_name, repeats)
    result.attrs["scene"] = scene_title
    return write_and_draw("work_precision.nc", result, out_dir, cfg.get("output"))


def _dataset(rows: list[dict[str, Any]], cfg: DictConfig, reference_name: str, repeats: int) -> xr.Dataset:
    units = {"error": ("1", "max-norm error of the final (ω, γ) against the reference"),
             "cpu_time": ("s", "smallest process CPU time of Scene.run() over the repeats (all threads)"),
             "wall_time": ("s", "smallest wall time of Scene.run() over the repeats"),
             "nfev": ("1", "right-hand-side evaluations (Taylor: series evaluations)"),
             "energy_drift": ("1", "max |E(t) − E(0)| over the run")}
    data = {name: ("run", np.array([r[name] for r in rows]), {"units": u, "long_name": ln})
            for name, (u, ln) in units.items()}
    data["method"] = ("run", np.array([r["method"] for r in rows]), {"units": "1", "long_name": "integrator"})
    data["nfev_counts"] = ("run", np.array([r["nfev_counts"] for r in rows]), {
        "units": "1", "long_name": "what nfev counts where not right-hand-side calls (empty: right-hand-side calls)"})
    data["setting"] = ("run", np.array([r["setting"] for r in rows]), {"units": "1", "long_name": "its setting"})
    ds = xr.Dataset(data, coords={"run": ("run", np.arange(len(rows), dtype=np.int32),
                                          {"units": "1", "long_name": "run index"})})
    ds.attrs.update({"title": "work against precision", "reference": reference_name, "timing": TIMING.format(repeats),
                     "repeats": repeats})
    return experiment_dataset(ds, cfg, "work_precision experiment")
