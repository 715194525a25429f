"""One registry of plugins: gyrolab's built-ins plus ``gyrolab.*`` entry points.

Names are listed without importing anything; a plugin's module is imported the first time a scene asks for it.
A third-party plugin that cannot be used never breaks a command that does not use it (docs/plugins.md, "What the
engine checks", "Installing"): ``load`` raises one ``ConfigError`` naming it, which the config composition turns
into one ``PluginLoadWarning``.
"""

from __future__ import annotations

import importlib
import inspect
import warnings
from functools import cache
from importlib.metadata import entry_points
from typing import Any

from gyrolab.contracts import Force, Integrator, Regime, System
from gyrolab.errors import ConfigError, GyrolabWarning, choices, shorten

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
        "auto": "gyrolab.accuracy.auto:Auto",
        "lie_poisson": "gyrolab.plugins.integrators.compiled_solvers:LiePoisson",
    },
    "regime": {
        "small_parameter": "gyrolab.plugins.regimes.small_parameter:SmallParameter",
        "large_parameter": "gyrolab.plugins.regimes.large_parameter:LargeParameter",
        "resonant_omega3": "gyrolab.plugins.regimes.resonant_omega3:ResonantOmega3",
    },
}


def _normalise(target: str) -> str:
    """'pkg.mod:Cls' and 'pkg.mod.Cls' name the same class."""
    return target.replace(":", ".")


class PluginLoadWarning(GyrolabWarning):
    """A third-party plugin cannot be used; every command that does not use it goes on."""


#: the entry points behind ``external(group)``, refreshed with it (``origin`` names their distributions)
_ENTRY_POINTS: dict[str, dict[str, Any]] = {}


@cache
def external(group: str) -> dict[str, str]:
    """Entry-point plugins of a group: name -> 'module:Class' (nothing imported)."""
    ep_group, _ = GROUPS[group]
    found: dict[str, Any] = {}
    for ep in entry_points(group=ep_group):
        if ep.name in BUILTINS[group] or ep.name in found:
            warnings.warn(f"ignoring {ep_group} entry point {ep.name!r} ({ep.value}): the name is already registered",
                          stacklevel=2)
            continue
        found[ep.name] = ep
    _ENTRY_POINTS[group] = found
    return {name: ep.value for name, ep in found.items()}


def plugin_entry_points() -> list[Any]:
    """The entry point of every registered third-party plugin, of every group (read once, by ``external``)."""
    for group in GROUPS:
        external(group)
    return [ep for group in GROUPS for ep in _ENTRY_POINTS[group].values()]


def origin(group: str, name: str) -> str:
    """Where a registered plugin comes from, for error sentences: "distribution 'x' (entry point a = m:C)"."""
    external(group)  # (re)reads the entry points when the cache was cleared
    ep = _ENTRY_POINTS.get(group, {}).get(name)
    if ep is None:
        return f"gyrolab's built-in {BUILTINS[group].get(name, '?')}"
    dist_name = getattr(getattr(ep, "dist", None), "name", None)
    where = f"distribution {dist_name!r}" if dist_name else "an unknown distribution"
    return f"{where} (entry point {ep.name} = {ep.value})"


def targets(group: str) -> dict[str, str]:
    """All registered plugins of a group: name -> 'module:Class'."""
    if group not in GROUPS:
        raise ConfigError(f"unknown plugin group {group!r}; valid choices: {choices(GROUPS)}")
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
    """The plugin class registered under ``name``; one ConfigError sentence otherwise (the valid names for an unknown
    one; the plugin, its distribution, its entry point and the error for one that cannot be used)."""
    registered = targets(group)
    if name not in registered:
        raise ConfigError(f"unknown {group} {name!r}; valid choices: {choices(registered)}")
    try:
        cls = _import(registered[name])
    except Exception as exc:  # noqa: BLE001 - a third-party module may raise anything on import
        if name in BUILTINS[group]:
            raise  # gyrolab's own: a bug, with its traceback
        raise ConfigError(f"{group} plugin {name!r} from {origin(group, name)} cannot be imported "
                          f"({type(exc).__name__}: {shorten(str(exc), 160)}); fix or uninstall that "
                          "distribution") from None
    _, contract = GROUPS[group]
    if not (inspect.isclass(cls) and issubclass(cls, contract)):
        raise ConfigError(f"{group} plugin {name!r} from {origin(group, name)} is not a {contract.__name__} "
                          "subclass; fix the plugin package's entry point")
    return cls


def resolve_target(group: str, target: Any, where: str) -> tuple[str, type]:
    """(name, class) for a config's ``_target_``, which must be a registered plugin of the group."""
    by_target = {_normalise(t): n for n, t in targets(group).items()}
    name = by_target.get(_normalise(str(target)))
    if name is None:
        raise ConfigError(f"{where}._target_={target!r} is not a registered {group} plugin; "
                          f"choose one by name ({group}=NAME), valid names: {choices(targets(group))}")
    return name, load(group, name)


def default_params(cls: type) -> dict[str, Any]:
    """A plugin's config parameters and defaults, read from its ``__init__`` keywords; ``**params`` would accept any
    key (a typo included) and advertise none, and is refused (as xarray's backends refuse ``**kwargs``)."""
    params: dict[str, Any] = {}
    signature = inspect.signature(cls.__init__)
    variadic = [p.name for p in signature.parameters.values() if p.kind is p.VAR_KEYWORD]
    if variadic:
        raise ConfigError(f"plugin {getattr(cls, 'name', cls.__name__)!r} ({cls.__module__}.{cls.__qualname__}) takes "
                          f"**{variadic[0]} in __init__, so its parameters are unknown; declare each parameter as a "
                          "keyword with a default (def __init__(self, body, *, coefficient=0.1))")
    for p in signature.parameters.values():
        if p.kind is p.KEYWORD_ONLY or (p.kind is p.POSITIONAL_OR_KEYWORD and p.default is not p.empty):
            params[p.name] = None if p.default is p.empty else p.default
    return params
