"""``experiment=orbit_family``: the exact periodic orbit of the heavy body followed from fast to slow spin, each
family of ``orbit_family.families`` shot at its start spin (from the fast-spin series or the pendulum swing) and
continued in ln r0, with the series' errors along it (docs/regimes.md, "Orbit families from fast to slow spin").
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.analysis.continuation import (
    FamilyPoint,
    Section,
    bifurcations,
    continue_family,
    locate_events,
    shoot_section,
)
from gyrolab.analysis.periodic import FixedPointModel
from gyrolab.engine import schemas
from gyrolab.engine.schemas import Task
from gyrolab.errors import ConfigError, IntegrationError, as_number
from gyrolab.figures.redraw import write_and_draw
from gyrolab.output.cf import experiment_dataset
from gyrolab.physics import pendulum
from gyrolab.plugins.regimes import large_parameter as slow
from gyrolab.plugins.regimes.base import NondimensionalScene
from gyrolab.plugins.regimes.small_parameter import SmallParameter

log = logging.getLogger(__name__)
COMPONENTS = ("p", "q", "r", "gamma_x", "gamma_y", "gamma_z")
BANDS = (1e-6, 1e-3)


def _family_spec(name: str, spec: dict) -> dict[str, Any]:
    where = f"orbit_family.families.{name}"
    out = {key: as_number(spec.get(key), f"{where}.{key}", positive=key != "k")
           for key in ("a", "b", "k", "theta0", "r0_start", "r0_end")}
    com = spec.get("com_direction")
    if not isinstance(com, (list, tuple)) or len(com) != 3:
        raise ConfigError(f"{where}.com_direction must be a list of three numbers, got {com!r}")
    out["com"] = np.array([as_number(c, f"{where}.com_direction") for c in com], dtype=float)
    out["com"] /= np.linalg.norm(out["com"])
    out["section"] = str(spec.get("section", "gamma_prime"))
    out["max_points"] = int(as_number(spec.get("max_points", 120), f"{where}.max_points", positive=True))
    out["max_period"] = as_number(spec.get("max_period", 40.0), f"{where}.max_period", positive=True)
    out["label"] = str(spec.get("label", name))
    return out


def _scene(f: dict, r0: float) -> NondimensionalScene:
    return NondimensionalScene(f["a"], f["b"], *map(float, f["com"]), f["k"], 1.0, float(r0), f["theta0"], 0.0, False)


#: the orders of ``small_parameter``'s series whose error is recorded along the families
FAST_SPIN_ORDERS = (3, 6, 10)


def _fast_spin(f: dict, r0: float, order: int | None = None) -> tuple[np.ndarray, float]:
    """The fast-spin series' (``small_parameter``, the paper's closed forms or ``order``) t = 0 state and period."""
    regime, s = SmallParameter(order=order), _scene(f, r0)
    return regime._state(s, np.array([0.0]))[0], regime._period(s)


def slow_spin_error(f: dict, point: FamilyPoint) -> float:
    on_axis = abs(f["com"][0]) < 1e-12 and abs(f["com"][1]) < 1e-12 and f["com"][2] > 0
    if not (on_axis and 0 < point.r0 <= slow.MAX_SPIN and slow.MIN_TILT <= f["theta0"] <= slow.MAX_TILT):
        return float("nan")
    series = slow.series_for(f["a"], f["b"], f["k"], f["theta0"])
    return _error(series.initial_state(point.r0), series.period(point.r0), point)


def _error(y0: np.ndarray, period: float, point: FamilyPoint) -> float:
    state = float(np.max(np.abs(y0 - point.y0))) / max(1.0, float(np.max(np.abs(point.y0))))
    return max(state, abs(period - point.period) / point.period)


def start_point(f: dict, model: FixedPointModel, section: Section) -> FamilyPoint:
    r0 = f["r0_start"]
    if section.kind == "turning":  # from the pendulum swing (slow-spin series when in its domain)
        T0 = pendulum.period(f["b"], pendulum.kappa(f["a"], f["k"]), f["theta0"])
        return shoot_section(model, section, np.zeros(2), T0, r0)
    y, period = _fast_spin(f, r0)
    return shoot_section(model, section, y[:2], period, r0)


def amplitude(model: FixedPointModel, point: FamilyPoint, samples: int = 48) -> float:
    """Nutation amplitude max θ − min θ over one period (θ = arccos γ'')."""
    theta = np.arccos(np.clip(model.sample(point.y0, np.linspace(0, point.period, samples + 1))[:, 5], -1, 1))
    return float(np.max(theta) - np.min(theta))


def trace(name: str, f: dict) -> dict[str, Any]:
    model = FixedPointModel(np.array([f["a"], f["b"], 1.0]), f["com"], f["k"])
    section = Section(f["section"], float(np.cos(f["theta0"])))
    try:
        start = start_point(f, model, section)
    except IntegrationError as error:
        raise IntegrationError(f"family {name}: no periodic orbit at its start r0/c={f['r0_start']:g} ({error})")
    points = continue_family(model, section, start, f["r0_end"], max_points=f["max_points"],
                             max_period=f["max_period"])
    events = bifurcations(points)
    located = locate_events(model, section, points, events)
    reached = points[-1].r0
    ended = ("reached r0/c = {:.4g}".format(reached) if (np.log(f["r0_end"]) - np.log(reached))
             * np.sign(np.log(f["r0_end"]) - np.log(f["r0_start"])) <= 0 else
             f"stopped at r0/c = {reached:.4g} with period {points[-1].period:.4g}: {points.stop_reason}")
    errors = {f"order_{o}": [_error(*_fast_spin(f, p.r0, o), p) if p.r0 >= 1 else np.nan for p in points]
              for o in FAST_SPIN_ORDERS}
    errors["slow"] = [slow_spin_error(f, p) for p in points]
    log.info("family %s: %d points, %s; bifurcations: %s", name, len(points), ended,
             ", ".join(f"{e.kind} at r0/c = {e.r0:.5g}" for e in located) or "none")
    return {"name": name, "label": f["label"], "points": points, "events": events, "located": located,
            "ended": ended,
            "amplitude": [amplitude(model, p) for p in points], "errors": errors}


def bands(r0: np.ndarray, error: np.ndarray, tol: float) -> str:
    ok = np.isfinite(error) & (error <= tol)
    return f"r0/c {r0[ok].min():.3g}–{r0[ok].max():.3g}" if ok.any() else "nowhere"


TASK = Task("orbit_family", section="orbit_family", settings=schemas.OrbitFamily).sets_all(
    ("system", "body", "force", "initial", "time", "integrator", "accuracy"),
    "each family of orbit_family.families sets its own body, Newtonian k and tilt, and the continuation its spins "
    "and periods")


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    spec = OmegaConf.to_container(cfg.get("orbit_family") or {}, resolve=True)
    families = spec.get("families") or {}
    if not isinstance(families, dict) or not families:
        raise ConfigError("orbit_family.families must name at least one family (body, theta0, section, r0_start, r0_end)")
    traces = [trace(name, _family_spec(name, f)) for name, f in families.items()]
    return write_and_draw("orbit_family.nc", dataset(traces, cfg), out_dir, cfg.get("output"))


def dataset(traces: list[dict], cfg: DictConfig) -> xr.Dataset:
    """The families' points, the series' errors along them and the located bifurcations, in one dataset."""
    points = [p for tr in traces for p in tr["points"]]
    data = {**_point_variables(traces, points), **_error_variables(traces), **_event_variables(traces)}
    coords = {"point": ("point", np.arange(len(points)), {"units": "1", "long_name": "point along the families"}),
              "component": ("component", np.array(COMPONENTS), {"units": "1", "long_name": "state component"}),
              "multiplier": ("multiplier", np.arange(6), {"units": "1", "long_name": "Floquet multiplier index"}),
              "event": ("event", np.arange(len(data["event_kind"][1])), {"units": "1",
                                                                         "long_name": "located bifurcation index"})}
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({"title": "exact periodic-orbit families of the heavy body, fast to slow spin",
                     "summary": _summary(traces)})
    return experiment_dataset(ds, cfg, "orbit_family experiment")


def _bifurcation_labels(traces: list[dict]) -> list[str]:
    """Per point along the families: the bifurcations detected between the previous point and it."""
    labels: list[str] = []
    for tr in traces:
        here = [""] * len(tr["points"])
        for i, label in tr["events"]:
            here[i] = f"{here[i]}, {label}" if here[i] else label
        labels += here
    return labels


def _point_variables(traces: list[dict], points: list) -> dict[str, Any]:
    """The variables along dimension ``point``: each family point, its stability and its bifurcation label."""
    family = np.array([tr["name"] for tr in traces for _ in tr["points"]])
    multipliers = np.array([p.multipliers for p in points])
    return {
        "r0_over_c": ("point", np.array([p.r0 for p in points]), {"units": "1", "long_name": "spin r0 in units of c = √(Mgℓ/C)"}),
        "period": ("point", np.array([p.period for p in points]), {"units": "1", "long_name": "period of the body-frame motion (units of 1/c)"}),
        "initial_state": (("point", "component"), np.array([p.y0 for p in points]),
                          {"units": "1", "long_name": "state (p, q, r, γ, γ', γ'') at t = 0 (rates in units of c)"}),
        "floquet_multiplier_real": (("point", "multiplier"), multipliers.real, {"units": "1", "long_name": "Floquet multiplier, real part"}),
        "floquet_multiplier_imag": (("point", "multiplier"), multipliers.imag, {"units": "1", "long_name": "Floquet multiplier, imaginary part"}),
        "stability_index": ("point", np.array([p.stability_index for p in points]),
                            {"units": "1", "long_name": "s = tr(monodromy) − 4 = ρ + 1/ρ of the non-trivial pair"}),
        "stable": ("point", np.array([int(p.stable) for p in points]), {"units": "1", "long_name": "spectrally stable (|s| ≤ 2, the multipliers on the unit circle): 1, else 0",
                            "comment": "spectral (linear) stability: necessary, not sufficient for stability"}),
        "amplitude": ("point", np.concatenate([tr["amplitude"] for tr in traces]), {"units": "rad", "long_name": "nutation amplitude max θ − min θ"}),
        "return_residual": ("point", np.array([p.residual for p in points]), {"units": "1", "long_name": "relative return residual of the shooting"}),
        "family": ("point", family, {"units": "1", "long_name": "family name (orbit_family.families)"}),
        "family_label": ("point", np.array([tr["label"] for tr in traces for _ in tr["points"]]),
                         {"units": "1", "long_name": "family description (body, tilt, where it starts)"}),
        "bifurcation": ("point", np.array(_bifurcation_labels(traces)),
                        {"units": "1", "long_name": "bifurcation detected between the previous point and this one"}),
    }


def _error_variables(traces: list[dict]) -> dict[str, Any]:
    """The relative error of each series along the families."""
    data = {}
    for key in traces[0]["errors"]:
        name = "fast_spin" if key.startswith("order") else "slow_spin"
        what = (f"fast-spin series (small_parameter, {key.replace('_', ' ')})" if name == "fast_spin"
                else "slow-spin series (large_parameter)")
        data[f"error_{name}_{key}" if name == "fast_spin" else "error_slow_spin_series"] = (
            "point", np.concatenate([tr["errors"][key] for tr in traces]),
            {"units": "1", "long_name": f"relative error of the {what} against the exact orbit (NaN: outside its domain)"})
    return data


def _event_variables(traces: list[dict]) -> dict[str, Any]:
    """The variables along dimension ``event``: each located bifurcation."""
    starts = np.cumsum([0] + [len(tr["points"]) for tr in traces])
    located = [(tr["name"], e) for tr in traces for e in tr["located"]]
    after = [int(start + e.index) for start, tr in zip(starts, traces) for e in tr["located"]]
    return {
        "event_point": ("event", np.array(after, dtype=np.int64), {
            "units": "1", "long_name": "index along point of the family point right after the bifurcation"}),
        "event_family": ("event", np.array([n for n, _ in located], dtype=str), {
            "units": "1", "long_name": "family of the located bifurcation"}),
        "event_kind": ("event", np.array([e.kind for _, e in located], dtype=str), {
            "units": "1", "long_name": "bifurcation: fold (r0 turns), branch point (s = +2), period doubling (s = -2)"}),
        "event_r0_over_c": ("event", np.array([e.r0 for _, e in located], dtype=float), {
            "units": "1", "long_name": "spin r0/c where the bifurcation happens (located, not the next family point)"}),
        "event_stability_index": ("event", np.array([e.stability_index for _, e in located], dtype=float), {
            "units": "1", "long_name": "s = rho + 1/rho at the located bifurcation (+2 or -2 for a crossing)"}),
        "event_period": ("event", np.array([e.period for _, e in located], dtype=float), {
            "units": "1", "long_name": "period of the orbit at the located bifurcation (units of 1/c)"}),
        "event_initial_state": (("event", "component"), np.array([e.y0 for _, e in located]).reshape(-1, 6), {
            "units": "1", "long_name": "state (p, q, r, γ, γ', γ'') at t = 0 of the orbit at the located bifurcation "
                                       "(NaN for a fold, located by interpolation)"}),
        "event_method": ("event", np.array([e.located for _, e in located], dtype=str), {
            "units": "1", "long_name": "how the bifurcation was located"}),
    }


def _summary(traces: list[dict]) -> str:
    """One line per family: how it ended, its first bifurcations, where each series is within each band."""
    summary = []
    for tr in traces:
        r0 = np.array([p.r0 for p in tr["points"]])
        parts = [f"{tr['name']}: {tr['ended']}"]
        parts += [f"{e.kind} at r0/c = {e.r0:.5g}" for e in tr["located"][:6]]
        for key, errs in tr["errors"].items():
            parts.append(f"{key} series within " + ", ".join(f"{tol:g}: {bands(r0, np.array(errs), tol)}" for tol in BANDS))
        summary.append("; ".join(parts))
    return " | ".join(summary)
