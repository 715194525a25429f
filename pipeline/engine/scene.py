"""A scene: one run's validated config turned into a system, its forces and an integrator."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.engine import registry
from gyrolab.engine.config import compose_config
from gyrolab.contracts import CompiledModel, Integrator, System
from gyrolab.output.dataset import build_dataset
from gyrolab.errors import ConfigError, as_number, require_finite
from gyrolab.engine.progress import Progress

log = logging.getLogger(__name__)


@dataclass
class Scene:
    """Everything one run needs, built and validated once; ``run()`` integrates and writes nothing."""

    config: DictConfig
    system: System
    integrator: Integrator
    times: np.ndarray

    @classmethod
    def from_config(cls, cfg: DictConfig) -> Scene:
        plain = OmegaConf.to_container(cfg, resolve=True)
        require_finite(plain, "")
        system_cls = _plugin_class("system", cfg.system, "system")
        body = system_cls.body_type.from_config(plain["body"])
        forces = [
            build_force(_plugin_class("force", node, f"force.{name}"), node, f"force.{name}", body)
            for name, node in (cfg.get("force") or {}).items()
        ]
        system = _build(system_cls, cfg.system, "system", body, forces, plain["initial"], plain.get("output") or {})
        timed = [f.name for f in forces if f.time_dependent]
        if timed and system.name != "fixed_point":
            raise ConfigError(f"force {timed[0]!r} is time-dependent, which system {system.name!r} does not support; "
                              "valid systems: fixed_point")
        integrator = _build(_plugin_class("integrator", cfg.integrator, "integrator"), cfg.integrator, "integrator")
        times = _output_times(plain["time"])
        integrator.prepare(system)
        scene = cls(config=cfg, system=system, integrator=integrator, times=times)
        if integrator.needs_compiled_model and scene.compiled is None:
            reason = getattr(system, "compile_error", None) or f"system {system.name!r} has no compiled form"
            raise ConfigError(
                f"integrator {integrator.name!r} runs compiled models only, and {reason}; "
                f"choose dop853 (or rk45, rk4, lsoda, radau, bdf) or integrator=auto"
            )
        if scene.compiled is not None and integrator.name in ("taylor", "lie_poisson"):
            from gyrolab.plugins.compiled import models

            if scene.compiled.model not in models.TAYLOR_MODELS:
                traced = ", ".join(f.name for f in system.forces if f.compiled_terms() is None)
                raise ConfigError(
                    f"integrator {integrator.name!r} evaluates the built-in torque forms only, and force {traced} "
                    f"is a compiled plugin torque; choose dop853_numba, rk4_numba or integrator=auto"
                )
        elif scene.compiled is None and integrator.prefers_compiled_model:
            reason = getattr(system, "compile_error", None)
            if reason:
                log.info("%s; %s runs scipy's integrators", reason, integrator.name)
        return scene

    @cached_property
    def config_yaml(self) -> str:
        """The resolved config as YAML (stored in every dataset; computed once per scene)."""
        return OmegaConf.to_yaml(self.config, resolve=True)

    @cached_property
    def compiled(self) -> CompiledModel | None:
        """The system's compiled model, when the integrator uses one (packed once per scene)."""
        integrator = self.integrator
        wants = integrator.needs_compiled_model or integrator.prefers_compiled_model
        return self.system.compiled_model() if wants else None

    def run(self) -> xr.Dataset:
        """Integrate the full equations of motion and return the self-describing dataset."""
        if log.isEnabledFor(logging.INFO):  # the title is worth building only when someone reads it
            log.info("integrating %s with %s over t=[%g, %g] (%d output times)", self.system.title(),
                     self.integrator.name, self.times[0], self.times[-1], len(self.times))
        compiled = self.compiled  # a plugin's torque compiles here (once), before progress is timed
        progress = Progress(self.integrator.name, self.times[0], self.times[-1])
        solution = self.integrator.integrate(self.system.rhs, self.times, self.system.initial_state(), progress,
                                             compiled)
        stats = solution.stats
        log.info("%s: %d steps (%s rejected), %d evaluations, %.3f s", self.integrator.name, stats.n_steps,
                 "?" if stats.n_rejected is None else stats.n_rejected, stats.nfev, stats.wall_time)
        return build_dataset(self, solution)


def compose_scene(overrides: Sequence[str] = ()) -> Scene:
    """Compose gyrolab's config with Hydra overrides, validate it and build the scene (once)."""
    return Scene.from_config(compose_config(overrides))


def run(overrides: Sequence[str] = ()) -> xr.Dataset:
    """``compose_scene(overrides).run()``."""
    return compose_scene(overrides).run()


def _plugin_class(group: str, node: Any, where: str) -> type:
    if not isinstance(node, DictConfig) or "_target_" not in node:
        raise ConfigError(f"{where} must be a plugin config with a _target_; valid choices: "
                          f"{', '.join(registry.names(group))}")
    _, cls = registry.resolve_target(group, node._target_, where)
    return cls


def _build(cls: type, node: DictConfig, where: str, *args: Any) -> Any:
    """Instantiate a registered plugin class with its config parameters (no nested instantiation)."""
    params = {k: v for k, v in OmegaConf.to_container(node, resolve=True).items() if k != "_target_"}
    for key, value in params.items():
        if isinstance(value, dict) and "_target_" in value:
            raise ConfigError(f"{where}.{key} has a nested _target_, which gyrolab does not instantiate")
    accepted = registry.default_params(cls)
    unknown = sorted(set(params) - set(accepted))
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]} is not a parameter of {cls.__name__}; valid parameters: "
                          f"{', '.join(sorted(accepted)) or '(none)'}")
    return cls(*args, **params)


def build_force(cls: type, node: Any, where: str, body: Any) -> Any:
    """Instantiate a force plugin; its ValueError/TypeError becomes one ConfigError naming the parameter.

    ``node`` is the force's config (a DictConfig or a dict of parameters). The culprit is found by
    building the force with each given parameter alone; the force must declare its area-integral flag.
    """
    from gyrolab.contracts.force import check_declared

    if not isinstance(node, DictConfig):
        node = OmegaConf.create(dict(node))
    try:
        force = _build(cls, node, where, body)
    except (ValueError, TypeError) as exc:
        if isinstance(exc, ConfigError):
            raise
        params = {k: v for k, v in OmegaConf.to_container(node, resolve=True).items() if k != "_target_"}
        culprit = next((key for key in params if _fails(cls, body, {key: params[key]})), None)
        named = f"{where}.{culprit}={params[culprit]!r}" if culprit else \
            f"{where} ({', '.join(f'{k}={v!r}' for k, v in params.items()) or 'defaults'})"
        raise ConfigError(f"{named} is not valid for {cls.__name__}: {type(exc).__name__}: {exc}") from None
    check_declared(force, where)
    return force


def _fails(cls: type, body: Any, params: dict[str, Any]) -> bool:
    try:
        cls(body, **params)
    except (ValueError, TypeError):
        return True
    return False


def _output_times(time_cfg: dict[str, Any]) -> np.ndarray:
    start = as_number(time_cfg.get("start", 0.0), "time.start")
    end = as_number(time_cfg.get("end"), "time.end")
    if end <= start:
        raise ConfigError(f"time.end={end:g} must be after time.start={start:g}")
    n = time_cfg.get("n_output")
    if isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ConfigError(f"time.n_output={n!r} must be an integer ≥ 2 (number of stored samples, both ends included)")
    return np.linspace(start, end, n)
