"""A regime run (``gyrolab regime=NAME ...``): the analytic periodic solution against the full model integrated from
its t = 0 state ("full"), the exact periodic orbit through the same r0, θ0, γ'(0) = 0 ("orbit", Newton shooting),
and the regime's reduced system where it has one ("reduced"; docs/regimes.md, "Reduced systems"). Writes
``regime.nc`` and ``figures/regime_comparison.png``.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from hydra.core.hydra_config import HydraConfig
from omegaconf import DictConfig

from gyrolab.analysis.periodic import FixedPointModel, PeriodicOrbit, shoot
from gyrolab.contracts import registry
from gyrolab.contracts.integrator import CHOOSES_METHOD, COMPILED_MODEL
from gyrolab.contracts.regime import Regime
from gyrolab.engine.scene import Scene, plugin_params
from gyrolab.engine.schemas import Task
from gyrolab.engine.unread import ACCURACY_IGNORED_ATTRIBUTE, ignored_accuracy
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.figures.redraw import write_and_draw
from gyrolab.output.cf import conform, unit_attributes
from gyrolab.output.dataset import time_attributes
from gyrolab.output.provenance import provenance
from gyrolab.physics.attitude import angles_from_states
from gyrolab.plugins.integrators.compiled_solvers import Taylor
from gyrolab.plugins.integrators.scipy_solvers import DOP853
from gyrolab.plugins.regimes.base import with_alpha

log = logging.getLogger(__name__)
SOURCE_NAMES = {"analytic": "analytic solution", "full": "full model from the analytic t = 0 state",
                "orbit": "exact periodic orbit (Newton shooting)",
                "reduced": "reduced quasilinear system integrated numerically"}


def build_regime(cfg: DictConfig) -> Regime:
    """The regime plugin selected by ``cfg.regime`` (a registered class only)."""
    node = cfg.get("regime")
    if not isinstance(node, DictConfig) or "_target_" not in node:
        raise ConfigError(f"regime must be selected by name (regime=NAME); valid choices: "
                          f"{', '.join(registry.names('regime'))}")
    _, cls = registry.resolve_target("regime", node._target_, "regime")
    return cls(**plugin_params(cls, node, "regime"))


#: |γ(0)| of the series further than this from 1 is reported as a warning (the figure states any rescaling)
NORM_WARNING = 1e-3


def prepare(cfg: DictConfig, *, report: bool = True) -> tuple[Scene, Regime, list[str]]:
    """Scene, regime and the domain warnings; ConfigError (before any integration) outside the domain.

    ``report`` logs each warning; the command line's check before Hydra starts passes False (the run that
    follows reports them: once, not twice), and so does an experiment that collects expected warnings.
    """
    scene = Scene.from_config(cfg)
    regime = build_regime(cfg)
    if scene.system.name not in regime.systems:
        raise ConfigError(f"regime {regime.name} is derived for system {', '.join(regime.systems)}, "
                          f"not {scene.system.name}")
    warnings = regime.check_domain(scene.system)
    for warning in warnings if report else ():
        log.warning("%s: %s", regime.name, warning)
    return scene, regime, warnings


def exact_orbit(scene: Scene, regime: Regime) -> PeriodicOrbit:
    """The full model's periodic orbit, by Newton shooting from the analytic one."""
    system = scene.system
    y0 = regime.initial_state(system)
    y0[3] = np.sqrt(max(0.0, 1.0 - y0[5] ** 2))
    y0[4] = 0.0
    return shoot(FixedPointModel.from_system(system), y0, regime.period(system))


def integrate(scene: Scene, y0: np.ndarray, t: np.ndarray, *, taylor: bool = False) -> np.ndarray:
    """The full model from y0 (the system's layout) at times t: the scene's integrator or compiled Taylor."""
    system = scene.system
    if taylor:
        return Taylor(order=24, tol=1e-16).integrate(system.rhs, t, y0, None, system.compiled_model()).y
    return scene.integrator.integrate(system.rhs, t, y0, None, scene.compiled).y


def compute(scene: Scene, regime: Regime, t: np.ndarray, *, full: bool = True,
            allow_no_orbit: bool = False) -> dict[str, Any]:
    """States (n, 6) and Euler angles of the three sources, the exact orbit and its analytic period.

    With ``allow_no_orbit`` a failed orbit search is recorded (``orbit`` None, ``orbit_failure``) instead of raised.
    """
    system = scene.system
    out: dict[str, Any] = {"period_analytic": regime.period(system)}
    try:
        out["orbit"] = exact_orbit(scene, regime)
    except IntegrationError as err:  # e.g. Shaker et al.'s printed branches (ii), (iv): no orbit exists near them
        if not allow_no_orbit:
            raise
        out["orbit"], out["orbit_failure"] = None, str(err)
        log.warning("%s: no exact periodic orbit near the analytic one: %s", regime.name, err)
    states = {"analytic": regime.solution(system, t)}
    angles = {"analytic": regime.euler_angles(system, t)}
    runs = {"orbit": out["orbit"].y0} if out["orbit"] is not None else {}
    if full:
        runs["full"] = regime.full_initial_state(system)[:6]
        # the series satisfies |γ| = 1 only to its order: the full model starts from γ(0) scaled to unit norm,
        # recorded (and stated by the figure) because far outside the series' domain the scaling is visible
        out["analytic_gamma0_norm"] = float(np.linalg.norm(regime.initial_state(system)[3:6]))
    for source, y0 in runs.items():
        y = integrate(scene, with_alpha(regime, system, y0), t, taylor=source == "orbit")
        states[source] = y[:, :6]
        variables = system.variables(t, y)
        angles[source] = {k: variables[k].values for k in ("psi", "theta", "phi") if k in variables}
    out["states"], out["angles"] = states, angles
    return out


def reduced_solution(scene: Scene, regime: Regime, t: np.ndarray) -> tuple[np.ndarray, str] | None:
    """The regime's reduced system integrated over t by the scene's integrator plugin: ((n, 6) model-unit states,
    a description of the method); None if the regime has none. Integrated in t, not τ = c r0 t, so that the plugin's
    settings mean what they mean for the full model (docs/regimes.md, "Reduced systems").
    """
    if not hasattr(regime, "reduced_rhs"):
        return None
    rhs, Z0, to_model = regime.reduced_rhs(scene.system)
    s = regime.scene(scene.system)
    kappa = s.r0 * s.c

    def rhs_t(time, Z):
        return kappa * rhs(kappa * time, Z)

    integrator = scene.integrator
    label = integrator.name
    # a compiled-only integrator has no model of the reduced system; one that chooses its method chose for the full one
    if integrator.supports(COMPILED_MODEL) or integrator.supports(CHOOSES_METHOD):
        settings = {k: getattr(integrator, k, 1e-12) for k in ("rtol", "atol")}
        integrator = DOP853(**settings)
        label = (f"{DOP853.name} rtol={settings['rtol']:g} atol={settings['atol']:g} (standing in for the scene's "
                 f"{label}, which integrates compiled models of the full equations only)")
    solution = integrator.integrate(rhs_t, np.asarray(t, dtype=float), np.asarray(Z0, dtype=float))
    return to_model(solution.y.T), label


def _reduced_or_why_not(scene: Scene, regime: Regime, t: np.ndarray) -> tuple[tuple[np.ndarray, str] | None, str]:
    """``reduced_solution``, or None and one sentence saying why it is left out (it diverged or failed)."""
    try:
        reduced = reduced_solution(scene, regime, t)
    except IntegrationError as error:
        return None, (f"{regime.name}: the reduced system could not be integrated over the window ({error}); the "
                      "comparison with it is left out, the analytic series and the full model are not affected")
    if reduced is not None and not np.all(np.isfinite(reduced[0])):
        bad = int(np.argmax(~np.all(np.isfinite(reduced[0]), axis=1)))
        return None, (f"{regime.name}: the reduced system diverges (non-finite from t = {t[bad]:.4g} of the "
                      f"{t[-1]:.4g} window at {regime.parameter} = {regime.parameter_value(scene.system):.4g}); the "
                      "comparison with it is left out, the analytic series and the full model are not affected")
    return reduced, ""


def errors(result: dict[str, Any], against: str = "orbit") -> dict[str, float]:
    """Max errors of the analytic solution over the window, per group of variables (model units)."""
    a, b = result["states"]["analytic"], result["states"][against]
    d = np.abs(a - b)
    out = {"pq": float(d[:, :2].max()), "r": float(d[:, 2].max()), "gamma": float(d[:, 3:5].max()),
           "gamma3": float(d[:, 5].max())}
    if against == "orbit":
        out["period"] = abs(result["period_analytic"] - result["orbit"].period)
    return out


TASK = Task("regime", reads=("regime",))


def run(cfg: DictConfig, out_dir: Path) -> list[Path]:
    scene, regime, warnings = prepare(cfg)
    system = scene.system
    T = regime.period(system)
    t = np.linspace(0.0, regime.periods * T, regime.periods * regime.samples_per_period + 1)
    result = compute(scene, regime, t, allow_no_orbit=True)
    reduced, reduced_failure = _reduced_or_why_not(scene, regime, t)
    if reduced is not None:
        result["states"]["reduced"], result["reduced_method"] = reduced
        psi0 = float(result["angles"]["analytic"]["psi"][0])
        result["angles"]["reduced"] = angles_from_states(t, result["states"]["reduced"], psi0)
    elif reduced_failure:
        # the reduced system is a comparison, not the result: its failure is recorded and the run goes on
        warnings = [*warnings, reduced_failure]
        log.warning("%s", reduced_failure)
        result["reduced_method"] = f"none: {reduced_failure}"
    norm = result.get("analytic_gamma0_norm")
    if norm is not None and abs(norm - 1.0) > NORM_WARNING:
        rescaled = (f"the full model starts from the analytic t = 0 state with γ rescaled to unit norm (the series "
                    f"gives |γ(0)| = {norm:.5g}, off by {abs(norm - 1):.2g}: the scene is outside the series' domain)")
        warnings = [*warnings, rescaled]
        log.warning("%s: %s", regime.name, rescaled)
    orbit = result["orbit"]
    if orbit is not None:
        log.info("%s (%s): %s = %.4g, analytic period %.10g, exact %.10g, Newton residuals %s", regime.name,
                 regime.formula, regime.parameter, regime.parameter_value(system), T, orbit.period,
                 ", ".join(f"{r:.1e}" for r in orbit.residuals))
    ds = dataset(scene, regime, t, result, warnings)
    diagnostics = getattr(regime, "diagnostics", None)  # e.g. small_parameter's order-N series evidence
    data, coords, attrs = diagnostics(system) if diagnostics is not None else ({}, {}, {})
    if data or attrs:
        ds = ds.assign_coords(coords).assign(data)
        ds.attrs.update(attrs)
        log.info("%s: %s", regime.name, ", ".join(f"{k} = {v}" for k, v in attrs.items() if not isinstance(v, list)))
    # the app logged it; regime.nc records it (the command line's overrides of the running Hydra job, none outside one)
    ignored = ignored_accuracy(cfg, list(HydraConfig.get().overrides.task) if HydraConfig.initialized() else [])
    if ignored:
        ds.attrs[ACCURACY_IGNORED_ATTRIBUTE] = ignored
    return write_and_draw("regime.nc", ds, out_dir, cfg.get("output"))


def dataset(scene: Scene, regime: Regime, t: np.ndarray, result: dict[str, Any], warnings: list[str]) -> xr.Dataset:
    system, body = scene.system, scene.system.body
    orbit = result["orbit"]
    data: dict[str, Any] = {}
    for source, y in result["states"].items():
        label = SOURCE_NAMES[source]
        data[f"omega_{source}"] = (("time", "axis"), y[:, :3],
                                   {"units": body.rate_unit, "long_name": f"angular velocity (p, q, r), {label}"})
        data[f"gamma_{source}"] = (("time", "axis"), y[:, 3:6],
                                   {"units": "1", "long_name": f"direction cosines of the vertical (γ, γ', γ''), {label}"})
        for name, values in result["angles"].get(source, {}).items():
            data[f"{name}_{source}"] = ("time", values, {"units": "rad", "long_name": f"Euler angle {name}, {label}"})
    states = result["states"]
    for name, a, b, what in (("max_error_vs_full", "analytic", "full", "analytic"),
                             ("max_error_vs_orbit", "analytic", "orbit", "analytic"),
                             ("max_error_reduced_vs_orbit", "reduced", "orbit", SOURCE_NAMES["reduced"])):
        if a in states and b in states:  # the orbit's states exist only when it was found
            data[name] = ("component", np.max(np.abs(states[a] - states[b]), axis=0), {
                "units": "1", "long_name": f"max |{what} − {SOURCE_NAMES[b]}| over the window, per component "
                                           "(model units of ω, γ)"})
    if orbit is not None:
        data.update(orbit_variables(orbit, body))
    data["period_analytic"] = ((), result["period_analytic"], {"units": body.time_unit,
                                                                "long_name": "period of the analytic orbit"})
    coords = {
        "time": ("time", t, time_attributes(body)),
        "axis": ("axis", np.array(["x", "y", "z"]), {"units": "1", "long_name": "principal body axis"}),
        "component": ("component", np.array(["p", "q", "r", "gamma_x", "gamma_y", "gamma_z"]),
                      {"units": "1", "long_name": "state component"}),
    }
    if orbit is not None:
        coords["iteration"] = ("iteration", np.arange(len(orbit.residuals), dtype=np.int32),
                               {"units": "1", "long_name": "Newton iteration"})
        coords["multiplier"] = ("multiplier", np.arange(6, dtype=np.int32),
                                {"units": "1", "long_name": "Floquet multiplier index"})
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update({
        "title": f"regime {regime.name} ({regime.formula}): {system.title()}",
        "config": scene.config_yaml,
        "regime_parameter_value": float(regime.parameter_value(system)),
        "regime_warnings": " | ".join(warnings) if warnings else "none",
        **({"analytic_gamma0_norm": result["analytic_gamma0_norm"],
            "full_model_start": "the analytic t = 0 state with γ scaled to unit norm (|γ| of the series at t = 0 is "
                                "analytic_gamma0_norm)"} if "analytic_gamma0_norm" in result else {}),
        "reduced_system_integrator": result.get("reduced_method", "none (the regime has no reduced system)"),
        "exact_orbit": "found" if orbit is not None else f"not found: {result['orbit_failure']}",
        "scene": system.title(),
        "rate_label": body.rate_label,
        **regime.attributes(), **provenance(), **system.attributes(), **unit_attributes(body),
    })
    return conform(ds, source=f"regime run ({regime.name}, {regime.formula})")


def orbit_variables(orbit: PeriodicOrbit, body) -> dict[str, Any]:
    """The exact orbit's Newton history, Floquet multipliers, initial state and period as dataset variables."""
    return {
        "newton_residual": ("iteration", np.array(orbit.residuals), {
            "units": "1", "long_name": "max-norm of the shooting return residual y(T) − y(0), relative to max(1, |y0|)"}),
        "floquet_multiplier_real": ("multiplier", orbit.multipliers.real, {
            "units": "1", "long_name": "Floquet multipliers (eigenvalues of the monodromy matrix), real part"}),
        "floquet_multiplier_imag": ("multiplier", orbit.multipliers.imag, {
            "units": "1", "long_name": "Floquet multipliers, imaginary part"}),
        "orbit_initial_state": ("component", orbit.y0, {
            "units": "1", "long_name": "exact orbit initial state (p, q, r, γ, γ', γ'') in model units"}),
        "period_orbit": ((), orbit.period, {"units": body.time_unit, "long_name": "period of the exact orbit"}),
    }
