"""Every regular-precession case of Yehia & El-kenani (2021), sections 4.1.1, 4.1.2, 4.2, checked on the full model:
the residual along the prescribed motion (vector and Euler-angle equations), an integration from its initial state,
and Floquet multipliers for a motion that holds only (those along a non-solution describe no motion). Verdicts and
tolerances: docs/gyrostat.md, "Regular precession". Writes precession_cases.csv, precession_cases.nc and one figure
per geometric class.
"""

from __future__ import annotations

import csv
import logging
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf, open_dict

from gyrolab.output.atomic import atomic_open
from gyrolab.output.cf import conform, experiment_dataset
from gyrolab.output.dataset import FRAME_AXES
from gyrolab.errors import ConfigError, as_number
from gyrolab.analysis.precession.cases import CASES, Case
from gyrolab.analysis.precession.classify import classify
from gyrolab.analysis.precession.closed_forms import check_closed_forms
from gyrolab.analysis.precession.motion import body_config, euler_residual, magnetic_config, vector_residual, window
from gyrolab.analysis.precession.stability import Floquet, floquet
from gyrolab.figures.redraw import write_and_draw
from gyrolab.engine.scene import Scene
from gyrolab.engine import schemas
from gyrolab.engine.schemas import Task

log = logging.getLogger(__name__)
#: what ``stable`` asserts, said in the data (the multipliers decide spectral stability only)
STABILITY_COMMENT = ("stable means spectrally stable: every Floquet multiplier |rho| <= 1 + floquet_tolerance. It is "
                     "necessary, not sufficient: a multiplier 1 in a Jordan block (a marginal equilibrium, e.g. the "
                     "double zero pitch eigenvalue of an A = B satellite in a gravity gradient) is spectrally stable "
                     "and still drifts secularly")
COLUMNS = ("case", "formula", "residual_vector", "residual_euler_angles", "max_theta_deviation", "stable", "verdict",
           "condition", "stability_note")


def _scene(cfg: DictConfig, case: Case, orbits: float) -> Scene:
    scene_cfg = OmegaConf.create(OmegaConf.to_container(cfg, resolve=True))
    with open_dict(scene_cfg):
        scene_cfg.body = body_config(case.params)
        scene_cfg.force = {"newtonian": {"_target_": "gyrolab.plugins.forces.newtonian.Newtonian", "k": None, "R": None},
                           "magnetic": {"_target_": "gyrolab.plugins.forces.magnetic.Magnetic", **magnetic_config(case.params)}}
        scene_cfg.initial = case.motion.initial_config()
        scene_cfg.time = {"start": 0.0, "end": orbits * 2 * np.pi / case.params.Omega, "n_output": 2001}
        scene_cfg.output.figures = False
    return Scene.from_config(scene_cfg)


def evaluate(cfg: DictConfig, case: Case, orbits: float, tol: float) -> tuple[dict[str, Any], xr.Dataset]:
    scene = _scene(cfg, case, orbits)
    system = scene.system
    t = window(system, orbits, 1001)
    res_v = vector_residual(system, case.motion, t)
    res_e = euler_residual(system.parameters(), case.motion, t[:401])
    ds = scene.run()
    deviation = np.abs(ds.theta.values - case.motion.theta0)
    first = ds.time.values <= 2 * np.pi / system.Omega * (1 + 1e-12)
    kind = classify(case.motion, system.Omega)
    if res_v < tol and deviation[first].max() < 1e-6:
        verdict = "holds"
    elif res_v > 1e-6:
        verdict = "fails"
    else:
        verdict = "unclear"
    stability, note = stability_of(system, case, verdict, res_v)
    row = {"case": case.case, "label": case.label, "formula": case.formula, "residual_vector": res_v,
           "residual_euler_angles": res_e, "max_theta_deviation": float(deviation.max()),
           "max_theta_deviation_orbit1": float(deviation[first].max()), "stable": stability.stable,
           "max_floquet_modulus": stability.max_modulus, "floquet_tolerance": stability.tolerance,
           "floquet_uncertainty": stability.uncertainty, "floquet_kind": stability.kind, "verdict": verdict,
           "stability_note": note,
           "condition": case.condition, "orbital_frame": kind.orbital, "inertial_frame": kind.inertial,
           "geometric": kind.geometric,
           "jacobi_drift": float(ds.jacobi_integral.attrs["max_abs_drift"]) if "jacobi_integral" in ds else np.nan}
    log.info("%-6s %-9s res %.1e/%.1e  dθ %.1e  |ρ|max %.3g  %s  (%s)", case.label, case.formula, res_v, res_e,
             row["max_theta_deviation"], stability.max_modulus, verdict, kind)
    return row, ds


def stability_of(system, case: Case, verdict: str, residual: float) -> tuple[Floquet, str]:
    """Floquet analysis of a motion that holds; for anything else no multipliers and the reason."""
    if verdict == "holds":
        stability = floquet(system, case.motion)
        note = "" if stability.stable is not None else "quasi-periodic in the body frame: not analysed"
        return stability, note
    why = (f"not a solution (vector residual {residual:.1e}): stability of a non-solution is undefined"
           if verdict == "fails" else f"residual {residual:.1e} neither ~0 nor large: not analysed")
    return Floquet("not a solution" if verdict == "fails" else "unclear", float("nan"), np.array([])), why


TASK = Task("yehia2021_precessions", reads=("output.error_estimate",), section="yehia2021",
            settings=schemas.Yehia2021).sets_all(
    ("body", "force", "initial", "time"),
    "each precession case sets its own body, forces, initial state and span, the span from yehia2021.orbits")


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    spec = OmegaConf.to_container(cfg.get("yehia2021") or {}, resolve=True)
    orbits = as_number(spec.get("orbits", 5), "yehia2021.orbits", positive=True)
    tol = as_number(spec.get("residual_tolerance", 1e-10), "yehia2021.residual_tolerance", positive=True)
    if cfg.get("system", {}).get("_target_", "").split(".")[-1] != "OrbitingGyrostat":
        raise ConfigError("experiment yehia2021_precessions needs system=orbiting_gyrostat (select a gyrostat body)")
    rows, traces = [], {}
    for case in CASES:
        row, ds = evaluate(cfg, case, orbits, tol)
        rows.append(row)
        traces[case.label] = ds
    closed = check_closed_forms()
    for item in closed:
        log.info("closed form %-10s agrees with eq. (1): %s (max |Δα| %.1e, |Δβ| %.1e, right-handed error %.1e)",
                 item["solution"], item["agrees_with_eq1"], item["max_diff_alpha"], item["max_diff_beta"],
                 item["right_handed_error"])
    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path = out_dir / "precession_cases.csv"
    with atomic_open(csv_path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(COLUMNS)
        for row in rows:
            if row["formula"] == "new":
                continue
            writer.writerow([row["case"], row["formula"], f"{row['residual_vector']:.3e}",
                             f"{row['residual_euler_angles']:.3e}", f"{row['max_theta_deviation']:.3e}",
                             {True: "true", False: "false", None: ""}[row["stable"]], row["verdict"], row["condition"],
                             row["stability_note"]])
    traced = trace_variables(rows, traces)
    ds = _dataset(rows, closed, cfg).merge(traced, combine_attrs="override")
    ds.attrs.update(traced.attrs)
    ds = conform(ds, source="yehia2021_precessions experiment")
    return [csv_path, *write_and_draw("precession_cases.nc", ds, out_dir, cfg.get("output"))]


def trace_variables(rows: list[dict[str, Any]], traces: dict[str, xr.Dataset]) -> xr.Dataset:
    """The body z axis of every case's integration, in the orbital and inertial frames (what the figures draw)."""
    def padded(name: str) -> np.ndarray:
        """``name`` of every case's integration, stacked along case, NaN past each one's end."""
        arrays = [traces[row["label"]][name].values for row in rows]
        out = np.full((len(arrays), max(len(a) for a in arrays), *arrays[0].shape[1:]), np.nan)
        for i, values in enumerate(arrays):
            out[i, : len(values)] = values
        return out

    data = {}
    for name in ("body_axis_orbital", "body_axis_inertial"):
        data[name] = (("case", "sample", "frame_axis"), padded(name), {
            "units": "1", "long_name": traces[rows[0]["label"]][name].attrs.get("long_name", name)
            + ", over the integration of each case"})
    # the output times of each case's integration (they differ between cases: a variable along sample, NaN-padded)
    first_time = traces[rows[0]["label"]]["time"]
    data["trace_time"] = (("case", "sample"), padded("time"), {
        "units": first_time.attrs.get("units", "1"),
        "long_name": f"{first_time.attrs.get('long_name', 'time')} of each case's integration (NaN past its end)"})
    coords = {"case": ("case", np.array([r["label"] for r in rows]), {"long_name": "case label"}),
              "frame_axis": ("frame_axis", np.array(FRAME_AXES), {
                  "units": "1", "long_name": "frame axis: orbital (radial, along-track, orbit normal) or inertial "
                                             "(X, Y, Z: the orbital axes at t = 0)"})}
    return xr.Dataset(data, coords=coords, attrs={
        "sample_description": "dimension sample: the output times of each case's integration, in order "
                              "(trace_time holds them)"})


def _dataset(rows: list[dict[str, Any]], closed: list[dict], cfg: DictConfig) -> xr.Dataset:
    data: dict[str, Any] = {}
    numeric = {"residual_vector": "max |R| of the vector equations along the precession",
               "residual_euler_angles": "max |E| of the Euler-angle equations along the precession",
               "max_theta_deviation": "max |θ − θ0| of the integrated full equations",
               "max_theta_deviation_orbit1": "max |θ − θ0| over the first orbit",
               "max_floquet_modulus": "largest modulus of the Floquet multipliers",
               "floquet_tolerance": "stable if max |rho| <= 1 + this (10 max(sqrt(rtol), delta))",
               "floquet_uncertainty": "delta: change of the sorted |rho| between rtol and 100 rtol",
               "jacobi_drift": "max |H − H0| of the integration"}
    for name, long_name in numeric.items():
        data[name] = ("case", np.array([r[name] for r in rows], dtype=float), {"units": "1", "long_name": long_name})
    text = {"formula": "which formula of the case: printed, corrected or new",
            "verdict": "does the precession satisfy the full equations: holds, fails or unclear",
            "condition": "the paper's condition for the case",
            "orbital_frame": "kind of precession in the orbital frame",
            "inertial_frame": "kind of precession in the inertial frame",
            "geometric": "surface the body z axis sweeps in inertial space (cylindrical, conical, ...)",
            "floquet_kind": "spectral stability class from the Floquet multipliers",
            "stability_note": "why the stability was not analysed, if it was not"}
    for name, long_name in text.items():
        data[name] = ("case", np.array([str(r[name]) for r in rows]), {"units": "1", "long_name": long_name})
    data["stable"] = ("case", np.array([-1 if r["stable"] is None else int(r["stable"]) for r in rows], dtype=np.int32),
                      {"units": "1", "long_name": "spectrally stable (1), spectrally unstable (0), not analysed or not a solution (-1)",
                       "comment": STABILITY_COMMENT})
    for key in closed[0]:
        if key != "solution":
            data[f"closed_form_{key}"] = ("closed_form", np.array([float(c[key]) for c in closed]),
                                          {"units": "1", "long_name": f"printed closed form vs eq. (1): {key}"})
    coords = {"case": ("case", np.array([r["label"] for r in rows]), {"long_name": "case label"}),
              "closed_form": ("closed_form", np.array([c["solution"] for c in closed]),
                              {"long_name": "printed solution"})}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs["title"] = "regular precessions of a satellite-gyrostat (Yehia & El-kenani 2021)"
    return experiment_dataset(ds, cfg, "yehia2021_precessions experiment")
