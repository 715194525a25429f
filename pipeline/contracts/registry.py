"""One registry of plugins: gyrolab's built-ins plus ``gyrolab.*`` entry points.

Names are listed without importing anything; a plugin's module is imported
the first time a scene asks for it. A config's ``_target_`` may only name a
registered class of the group's contract, so a YAML file cannot make gyrolab
call arbitrary code.
"""

from __future__ import annotations

import importlib
import inspect
import warnings
from functools import cache
from importlib.metadata import entry_points
from typing import Any

from gyrolab.contracts import Force, Integrator, Regime, System
from gyrolab.errors import ConfigError, choices

#: config group -> (entry-point group, contract class)
GROUPS: dict[str, tuple[str, type]] = {
    "system": ("gyrolab.systems", System),
    "force": ("gyrolab.forces", Force),
    "integrator": ("gyrolab.integrators", Integrator),
    "regime": ("gyrolab.regimes", Regime),
}

BUILTINS: dict[str, dict[str, str]] = {
    "system": {
        "fixed_point": "gyrolab.plugins.systems.fixed_point:FixedPoint",
        "orbiting_gyrostat": "gyrolab.plugins.systems.orbiting_gyrostat:OrbitingGyrostat",
    },
    "force": {
        "uniform_gravity": "gyrolab.plugins.forces.uniform_gravity:UniformGravity",
        "newtonian": "gyrolab.plugins.forces.newtonian:Newtonian",
        "magnetic": "gyrolab.plugins.forces.magnetic:Magnetic",
    },
    "integrator": {
        "rk4": "gyrolab.plugins.integrators.rk4:RK4",
        "rk45": "gyrolab.plugins.integrators.scipy_solvers:RK45",
        "dop853": "gyrolab.plugins.integrators.scipy_solvers:DOP853",
        "lsoda": "gyrolab.plugins.integrators.scipy_solvers:LSODA",
        "radau": "gyrolab.plugins.integrators.scipy_solvers:Radau",
        "bdf": "gyrolab.plugins.integrators.scipy_solvers:BDF",
        "dop853_numba": "gyrolab.plugins.integrators.compiled_solvers:DOP853Numba",
        "rk4_numba": "gyrolab.plugins.integrators.compiled_solvers:RK4Numba",
        "taylor": "gyrolab.plugins.integrators.compiled_solvers:Taylor",
        "auto": "gyrolab.plugins.integrators.auto:Auto",
        "lie_poisson": "gyrolab.plugins.integrators.compiled_solvers:LiePoisson",
    },
    "regime": {
        "small_parameter": "gyrolab.plugins.regimes.small_parameter:SmallParameter",
        "large_parameter": "gyrolab.plugins.regimes.large_parameter:LargeParameter",
        "resonant_omega3": "gyrolab.plugins.regimes.resonant_omega3:ResonantOmega3",
    },
}


#: import paths of gyrolab 0.1 (top-level ``plugins``), still found in configs stored in older datasets
_LEGACY_PREFIXES = {"plugins.": "gyrolab.plugins."}


def _normalise(target: str) -> str:
    """'pkg.mod:Cls' and 'pkg.mod.Cls' name the same class; a 0.1 path names its class of today."""
    target = target.replace(":", ".")
    for old, new in _LEGACY_PREFIXES.items():
        if target.startswith(old):
            return new + target[len(old):]
    return target


@cache
def external(group: str) -> dict[str, str]:
    """Entry-point plugins of a group: name -> 'module:Class' (nothing imported)."""
    ep_group, _ = GROUPS[group]
    found: dict[str, str] = {}
    for ep in entry_points(group=ep_group):
        if ep.name in BUILTINS[group] or ep.name in found:
            warnings.warn(
                f"ignoring {ep_group} entry point {ep.name!r} ({ep.value}): the name is already registered",
                stacklevel=2,
            )
            continue
        found[ep.name] = ep.value
    return found


def targets(group: str) -> dict[str, str]:
    """All registered plugins of a group: name -> 'module:Class'."""
    _check_group(group)
    return {**BUILTINS[group], **external(group)}


def names(group: str) -> list[str]:
    return sorted(targets(group))


@cache
def _import(target: str) -> type:
    module_name, _, attr = target.partition(":")
    if not attr:
        module_name, _, attr = target.rpartition(".")
    module = importlib.import_module(module_name)
    return getattr(module, attr)


def load(group: str, name: str) -> type:
    """The plugin class registered under ``name``; ConfigError listing the valid names otherwise."""
    registered = targets(group)
    if name not in registered:
        raise ConfigError(f"unknown {group} {name!r}; valid choices: {choices(registered)}")
    cls = _import(registered[name])
    _, contract = GROUPS[group]
    if not (inspect.isclass(cls) and issubclass(cls, contract)):
        raise ConfigError(
            f"{group} plugin {name!r} ({registered[name]}) is not a {contract.__name__} subclass; "
            "fix the plugin package's entry point"
        )
    return cls


def resolve_target(group: str, target: Any, where: str) -> tuple[str, type]:
    """(name, class) for a config's ``_target_``, which must be a registered plugin of the group."""
    by_target = {_normalise(t): n for n, t in targets(group).items()}
    name = by_target.get(_normalise(str(target)))
    if name is None:
        raise ConfigError(
            f"{where}._target_={target!r} is not a registered {group} plugin; "
            f"choose one by name ({group}=NAME), valid names: {choices(targets(group))}"
        )
    return name, load(group, name)


def default_params(cls: type) -> dict[str, Any]:
    """A plugin's config parameters and defaults, read from its ``__init__`` keywords."""
    params: dict[str, Any] = {}
    for p in inspect.signature(cls.__init__).parameters.values():
        if p.kind is p.KEYWORD_ONLY or (p.kind is p.POSITIONAL_OR_KEYWORD and p.default is not p.empty):
            params[p.name] = None if p.default is p.empty else p.default
    return params


def _check_group(group: str) -> None:
    if group not in GROUPS:
        raise ConfigError(f"unknown plugin group {group!r}; valid choices: {choices(GROUPS)}")
