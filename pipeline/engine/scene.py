"""A scene: one run's validated config turned into a system, its forces and an integrator."""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab import accuracy
from gyrolab.contracts import CompiledModel, Integrator, System, registry
from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.claims import check_claims, claim_states
from gyrolab.contracts.force import check_declared
from gyrolab.contracts.integrator import (
    COMPILED_MODEL,
    NFEV_COUNTS_ATTRIBUTE,
    PREFERS_COMPILED_MODEL,
    TIME_DEPENDENT,
)
from gyrolab.engine.config import compose_config
from gyrolab.engine.force_guard import GuardedRhs, plugin_forces
from gyrolab.engine.progress import Progress
from gyrolab.engine.unread import ACCURACY_IGNORED_ATTRIBUTE, ignored_accuracy
from gyrolab.errors import ConfigError, GyrolabError, as_number, require_finite, shorten
from gyrolab.kernels.model import python_rhs
from gyrolab.output.dataset import build_dataset, scene_attributes

log = logging.getLogger(__name__)

#: ``time.n_output: auto``: AUTO_SAMPLES_PER_PERIOD samples per period of the fastest motion
#: (``fastest_rate``), at least AUTO_MIN_SAMPLES and at most AUTO_MAX_SAMPLES (then it warns)
AUTO = "auto"
AUTO_SAMPLES_PER_PERIOD = 8
AUTO_MIN_SAMPLES = 2001
AUTO_MAX_SAMPLES = 200_001
#: fewer samples per fastest period than this (auto's cap or an explicit time.n_output) is warned about
MIN_SAMPLES_PER_PERIOD = 2


@dataclass
class Scene:
    """Everything one run needs, built and validated once; ``run()`` integrates and writes nothing.

    Build one with `compose_scene` (from Hydra overrides) or ``Scene.from_config`` (from a composed
    config). A scene is reusable: ``run()`` may be called again.
    """

    #: the resolved config the scene was built from (stored in every dataset it writes)
    config: DictConfig
    #: the equations of motion with the body, forces and initial state
    system: System
    integrator: Integrator
    #: the output times (model time units)
    times: np.ndarray
    #: ``time.n_output`` as the config gave it: ``"auto"`` or a number of samples
    n_output_requested: int | str = AUTO
    #: why the config's ``accuracy`` is not read by this scene's integrator, when a config file set it
    #: (``gyrolab.engine.unread``; a given one is refused): recorded in every run dataset as ``accuracy_ignored``
    accuracy_ignored: str | None = None
    #: the layouts of its runs' datasets (``output.dataset``: their coordinates built once, shared by later runs)
    dataset_layouts: list = field(default_factory=list, init=False, repr=False, compare=False)

    @classmethod
    def from_config(cls, cfg: DictConfig, check: Callable[[System], None] | None = None) -> Scene:
        """The scene of a composed config; ``check`` (the preflight's budget) is given the system as soon as it is
        built, before the output times are allocated or the integrator built."""
        plain = OmegaConf.to_container(cfg, resolve=True)
        require_finite(plain, "")
        system_cls, body, forces = body_and_forces(cfg, plain)
        system = _build(system_cls, cfg.system, "system", body, forces, plain["initial"], plain.get("output") or {})
        if check is not None:
            check(system)
        check_force_claims(system, float(plain["time"].get("start", 0.0) or 0.0))
        timed = [f.name for f in forces if f.time_dependent]
        _check_time_dependent(timed, system)
        integrator = _build(_plugin_class("integrator", cfg.integrator, "integrator"), cfg.integrator, "integrator")
        _check_time_dependent(timed, system, integrator)
        times = _output_times(plain["time"], fastest_rate(system))
        _guarded(type(integrator), "integrator", integrator.prepare, system)
        scene = cls(config=cfg, system=system, integrator=integrator, times=times,
                    n_output_requested=plain["time"].get("n_output", AUTO))
        scene._check_compiled_model()
        scene.log_notes()
        return scene

    def _check_compiled_model(self) -> None:
        """ConfigError when the integrator runs compiled models only and the system has none, or refuses the
        system's compiled model; each sentence names the integrators that would run it."""
        integrator, system, compiled = self.integrator, self.system, self.compiled
        if integrator.supports(COMPILED_MODEL) and compiled is None:
            reason = system.compile_error or f"system {system.name!r} has no compiled form"
            raise ConfigError(f"integrator {integrator.name!r} runs compiled models only, and {reason}; "
                              f"choose {or_list(integrators_with(accept=lambda c: not c.supports(COMPILED_MODEL)))}")
        refusal = integrator.refusal(compiled, system) if compiled is not None else None
        if refusal:
            valid = or_list(integrators_with(accept=lambda c: (c.supports(COMPILED_MODEL)
                                                               or c.supports(PREFERS_COMPILED_MODEL))
                                             and c is not type(integrator) and c.refusal(compiled, system) is None))
            raise ConfigError(f"integrator {integrator.name!r} {refusal}; choose {valid}")

    def log_notes(self) -> None:
        """Log what the scene's user should know: output times that undersample its motion (a warning), scipy's
        integrators running where a compiled model could not be built (info)."""
        if self.compiled is None and self.integrator.supports(PREFERS_COMPILED_MODEL) and self.system.compile_error:
            log.info("%s; %s runs scipy's integrators", self.system.compile_error, self.integrator.name)
        warning = self.sampling_warning()
        if warning:
            log.warning("%s", warning)

    @cached_property
    def config_yaml(self) -> str:
        """The resolved config as YAML (stored in every dataset; computed once per scene)."""
        return OmegaConf.to_yaml(self.config, resolve=True)

    @cached_property
    def estimated(self) -> bool:
        """Whether its runs' errors are measured (``accuracy.estimate.wanted``; the config read once per scene)."""
        return accuracy.estimate.wanted(self)

    @cached_property
    def dataset_attributes(self) -> tuple[dict[str, Any], dict[str, Any]]:
        """The run dataset's attributes that depend on the scene alone (``output.dataset.scene_attributes``, plus
        ``accuracy_ignored`` and the integrator's ``evaluation_label``), computed once per scene."""
        before, after = scene_attributes(self)
        if self.accuracy_ignored:
            before = {**before, ACCURACY_IGNORED_ATTRIBUTE: self.accuracy_ignored}
        label = self.integrator.evaluation_label
        return before, ({**after, NFEV_COUNTS_ATTRIBUTE: label} if label else after)

    @cached_property
    def compiled_model(self) -> CompiledModel | None:
        """The system's compiled model, traced once per scene (~1 ms), whether or not the integrator uses it (the error
        estimate's Taylor companion may)."""
        return self.system.compiled_model()

    @cached_property
    def compiled(self) -> CompiledModel | None:
        """The system's compiled model, when the integrator uses one."""
        integrator = self.integrator
        wants = integrator.supports(COMPILED_MODEL) or integrator.supports(PREFERS_COMPILED_MODEL)
        return self.compiled_model if wants else None

    def __getstate__(self) -> dict[str, Any]:
        # the generated right-hand side is a function made in this process: generated again after unpickling
        return {key: value for key, value in self.__dict__.items() if key != "rhs"}

    @cached_property
    def rhs(self) -> Callable[[float, np.ndarray], np.ndarray]:
        """The Python right-hand side the integrator calls: the system's own generated as Python on floats
        (``kernels.model.python_rhs``: the same numbers, ~5× faster), or, when a third-party force takes part, the
        system's own guarded (``gyrolab.engine.force_guard``: its torque's faults become one sentence naming it)."""
        plugins = plugin_forces(self.system.forces)
        if plugins:
            return GuardedRhs(self.system, plugins)
        # an integrator of the compiled model calls its kernels, not this: no trace (~0.2 ms) for it
        return self.system.rhs if self.compiled is not None else python_rhs(self.system)

    @cached_property
    def fastest_rate(self) -> float | None:
        """Upper estimate of the scene's fastest angular frequency (``fastest_rate``; None: not known)."""
        return fastest_rate(self.system)

    def sampling_warning(self) -> str:
        """One sentence when the output times undersample the fastest motion (fewer than
        ``MIN_SAMPLES_PER_PERIOD`` samples per period 2π/ν), else ''. Two samples ask for the end states
        only (as work_precision does), not for a series: no warning."""
        if self.fastest_rate is None or len(self.times) <= 2:
            return ""
        per_period = samples_per_period(self.times, self.fastest_rate)
        if per_period >= MIN_SAMPLES_PER_PERIOD:
            return ""
        needed = _needed_samples(float(self.times[-1] - self.times[0]), self.fastest_rate, MIN_SAMPLES_PER_PERIOD)
        given = ("the cap of time.n_output=auto" if self.n_output_requested == AUTO
                 else f"time.n_output={self.n_output_requested}")
        return (f"{given} stores {per_period:.3g} samples per period of the fastest motion "
                f"(2π/ν = {2 * np.pi / self.fastest_rate:.3g} time units, ν = {self.fastest_rate:.4g}), fewer than "
                f"{MIN_SAMPLES_PER_PERIOD}: the stored series and figures may alias; time.n_output ≥ {needed} "
                f"(or auto) resolves it")

    def sampling_attributes(self) -> dict[str, Any]:
        """Dataset attributes saying how the output times were chosen and whether they resolve the motion."""
        attrs: dict[str, Any] = {"sampling_n_output_requested": str(self.n_output_requested)}
        if self.fastest_rate is not None:
            attrs["sampling_fastest_rate"] = float(self.fastest_rate)
            attrs["sampling_samples_per_period"] = float(samples_per_period(self.times, self.fastest_rate))
        warning = self.sampling_warning()
        if warning:
            attrs["sampling_warning"] = warning
        return attrs

    def run(self) -> xr.Dataset:
        """Integrate the full equations of motion and return the self-describing dataset.

        Returns
        -------
        xarray.Dataset
            What ``run.nc`` holds: the trajectory, the Euler angles, the monitored first integrals,
            the resolved config and provenance (nothing is written to disk).

        Raises
        ------
        gyrolab.errors.GyrolabError
            A subclass naming what went wrong (an integration that fails, a torque that is not finite).
        """
        if log.isEnabledFor(logging.INFO):  # the title is worth building only when someone reads it
            log.info("integrating %s with %s over t=[%g, %g] (%d output times)", self.system.title(),
                     self.integrator.name, self.times[0], self.times[-1], len(self.times))
        compiled = self.compiled  # a plugin's torque compiles here (once), before progress is timed
        progress = Progress(self.integrator.name, self.times[0], self.times[-1])
        y0 = self.system.initial_state()
        if compiled is not None and isinstance(self.rhs, GuardedRhs):
            # the compiled path runs a plugin's traced torque, unguarded: one Python evaluation first names the
            # force whose torque is already at fault at the start (the usual case: NaN or inf in its formula)
            self.rhs.inspect(float(self.times[0]), y0)
        # the run, its error measured and its promise kept (gyrolab.accuracy)
        solution, ran, add = accuracy.measured_run(self, y0, progress, compiled)
        return build_dataset(self, solution, add, ran)


def compose_scene(overrides: Sequence[str] = ()) -> Scene:
    """Compose gyrolab's config with Hydra overrides, validate it and build the scene (once).

    Parameters
    ----------
    overrides : sequence of str
        Hydra overrides, exactly as on the command line (``"integrator=rk4"``, ``"initial.r0=5"``).

    Returns
    -------
    Scene
        The validated scene; ``scene.run()`` integrates it.

    Raises
    ------
    gyrolab.errors.ConfigError
        A bad value, key or choice, in one sentence naming it and the valid choices.

    Examples
    --------
    >>> from gyrolab import compose_scene
    >>> scene = compose_scene(["body=lagrange_top", "time.end=5", "time.n_output=51"])
    >>> ds = scene.run()
    >>> ds.sizes["time"]
    51
    """
    cfg = compose_config(overrides)
    scene = Scene.from_config(cfg)
    # the gyrolab command says this once per job itself, knowing a sweep's overrides (app._run_one)
    scene.accuracy_ignored = ignored_accuracy(cfg, overrides)
    if scene.accuracy_ignored:
        log.warning("%s", scene.accuracy_ignored)
    return scene


def run(overrides: Sequence[str] = ()) -> xr.Dataset:
    """Compose, build and integrate a scene: ``compose_scene(overrides).run()``, the run's dataset (what ``run.nc``
    holds; nothing is written to disk)."""
    return compose_scene(overrides).run()


def body_and_forces(cfg: DictConfig, plain: dict[str, Any]) -> tuple[type, Any, list[Any]]:
    """(the system's class, its body, its forces) of a composed config (``plain``: resolved), in this order."""
    system_cls = _plugin_class("system", cfg.system, "system")
    body = system_cls.body_type.from_config(plain["body"])
    return system_cls, body, [build_force(_plugin_class("force", node, f"force.{name}"), node, f"force.{name}", body)
                              for name, node in (cfg.get("force") or {}).items()]


def _check_time_dependent(timed: Sequence[str], system: System, integrator: Integrator | None = None) -> None:
    """ConfigError when time-dependent forces (``timed``) act in a system, or (given) an integrator, that does not
    support them."""
    if timed and system.name != "fixed_point":
        raise ConfigError(f"force {timed[0]!r} is time-dependent, which system {system.name!r} does not support; "
                          "valid systems: fixed_point")
    if timed and integrator is not None and not integrator.supports(TIME_DEPENDENT):
        raise ConfigError(f"integrator {integrator.name!r} does not integrate time-dependent forces (capability "
                          f"{TIME_DEPENDENT}) and force {timed[0]!r} is one; valid choices: "
                          f"{or_list(integrators_with(TIME_DEPENDENT))}")


def _plugin_class(group: str, node: Any, where: str) -> type:
    if not isinstance(node, DictConfig) or "_target_" not in node:
        raise ConfigError(f"{where} must be a plugin config with a _target_; valid choices: "
                          f"{', '.join(registry.names(group))}")
    _, cls = registry.resolve_target(group, node._target_, where)
    return cls


def plugin_params(cls: type, node: DictConfig, where: str) -> dict[str, Any]:
    """A plugin's config parameters, each one a keyword of its ``__init__`` (no nested instantiation)."""
    params = {k: v for k, v in OmegaConf.to_container(node, resolve=True).items() if k != "_target_"}
    for key, value in params.items():
        if isinstance(value, dict) and "_target_" in value:
            raise ConfigError(f"{where}.{key} has a nested _target_, which gyrolab does not instantiate")
    accepted = registry.default_params(cls)
    unknown = sorted(set(params) - set(accepted))
    if unknown:
        raise ConfigError(f"{where}.{unknown[0]} is not a parameter of {cls.__name__}; valid parameters: "
                          f"{', '.join(sorted(accepted)) or '(none)'}")
    return params


def _build(cls: type, node: DictConfig, where: str, *args: Any) -> Any:
    """Instantiate a registered plugin class with its config parameters."""
    return _guarded(cls, where, cls, *args, **plugin_params(cls, node, where))


def _guarded(cls: type, where: str, call: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``call(*args, **kwargs)`` of plugin ``cls`` (its ``__init__``, an integrator's ``prepare``); whatever it
    raises (RuntimeError, ImportError, SyntaxError, ...) becomes one ConfigError naming the plugin."""
    try:
        return call(*args, **kwargs)
    except GyrolabError:
        raise
    except Exception as exc:  # noqa: BLE001 - a plugin may raise anything; the user gets one sentence
        raise init_failure(cls, where, exc) from exc


def init_failure(cls: type, where: str, exc: BaseException) -> ConfigError:
    """One sentence for a plugin ``__init__`` that raised something other than gyrolab's ConfigError."""
    name = getattr(cls, "name", cls.__name__)
    return ConfigError(f"{where}: plugin {name!r} ({cls.__module__}.{cls.__qualname__}) failed to build: "
                       f"{type(exc).__name__}: {shorten(str(exc), 160) or '(no message)'}; its __init__ should "
                       "raise gyrolab.errors.ConfigError naming the bad value")


def build_force(cls: type, node: Any, where: str, body: Any) -> Any:
    """Instantiate a force plugin from its config (a DictConfig or a dict of parameters); its ValueError/TypeError
    becomes one ConfigError naming the parameter (the culprit: the one that fails alone), any other exception one
    naming the plugin."""
    if not isinstance(node, DictConfig):
        node = OmegaConf.create(dict(node))
    params = plugin_params(cls, node, where)
    try:
        force = cls(body, **params)
    except GyrolabError:
        raise
    except AttributeError as exc:  # a force reading what this system's body lacks (a third-party system's body)
        raise ConfigError(f"{where} ({cls.__name__}) cannot act on a {type(body).__name__} body ({exc}); choose "
                          "the forces the system supports (force=[] for none)") from None
    except (ValueError, TypeError) as exc:
        culprit = next((key for key in params if _fails(cls, body, {key: params[key]})), None)
        named = f"{where}.{culprit}={params[culprit]!r}" if culprit else \
            f"{where} ({', '.join(f'{k}={v!r}' for k, v in params.items()) or 'defaults'})"
        raise ConfigError(f"{named} is not valid for {cls.__name__}: {type(exc).__name__}: {exc}") from None
    except Exception as exc:  # noqa: BLE001 - RuntimeError, ImportError, SyntaxError, ... from a plugin
        raise init_failure(cls, where, exc) from exc
    check_declared(force, where)
    return force


def _fails(cls: type, body: Any, params: dict[str, Any]) -> bool:
    try:
        cls(body, **params)
    except Exception:  # noqa: BLE001 - only which parameter fails matters here
        return True
    return False


def check_force_claims(system: System, t0: float = 0.0) -> None:
    """ConfigError when a third-party force's potential does not belong to its torque, or its
    ``preserves_area_integral = True`` is false (``gyrolab.contracts.claims``), at the initial state and
    seeded random states. gyrolab's own forces are tested against closed forms and skipped."""
    plugins = plugin_forces(system.forces)
    if not plugins:
        return
    y0 = np.asarray(system.initial_state(), dtype=float)
    frame0 = system.reference_frame(y0)
    omegas, frames = claim_states(y0[:3], frame0)
    for force in plugins:
        if force.preserves_area_integral or force.conservative:
            check_claims(force, omegas, frames, t0, f"force.{force.name}", initial=frame0 is not None)


def fastest_rate(system: System, omega0: np.ndarray | None = None) -> float | None:
    """An upper estimate ν of the fastest angular frequency in the stored series (model units), from the initial ω
    (``omega0``: another one, e.g. a batch's most energetic).

    A body turning at |ω| moves every body-frame vector (γ, α) at up to |ω|, and its
    nutation and the body-frame motion of ω run at up to (I_max/I_min) |ω| (a symmetric top
    spinning at r nutates at C r/A; a free asymmetric one turns ω in the body at
    r √((C−A)(C−B)/(AB))). |ω| itself is bounded by energy: ½ I_min |ω|² ≤ ½ ω0·Iω0 + ΔV, with
    ΔV the range of the potentials (2|M g r_c| for the weight, ½N(I_max − I_min) for an attracting
    centre or a circular orbit's gradient N = 3Ω², 2|m||B| for a dipole). The orbiting gyrostat
    adds the orbit rate Ω (the frame turns) and the rotor |k|/I_min. ν is at least the slowest
    torque's pendulum frequency √(ΔV/I_min), so a body at rest still has a time scale. None for a
    third-party system whose body has no principal ``inertia`` (then auto stores AUTO_MIN_SAMPLES).
    """
    body = system.body
    if getattr(body, "inertia", None) is None or system.state_size < 3:
        return None
    inertia = np.asarray(body.inertia, dtype=float)
    i_min, i_max = float(inertia.min()), float(inertia.max())
    omega0 = np.asarray(system.initial_state()[:3] if omega0 is None else omega0, dtype=float)
    orbit = float(getattr(body, "orbit_rate", 0.0) or 0.0)
    spread = 0.5 * (i_max - i_min)
    dv = 2.0 * float(np.linalg.norm(getattr(body, "weight_moment", np.zeros(3))))
    for force in system.forces:
        dv += spread * float(getattr(force, "N", 0.0) or 0.0)
        moment, field = getattr(force, "moment", None), getattr(force, "field", None)
        if moment is not None and field is not None:
            dv += 2.0 * float(np.linalg.norm(moment)) * abs(float(field))
    rotor = float(np.linalg.norm(getattr(body, "gyrostatic_momentum", np.zeros(3)))) / i_min
    omega_max = np.sqrt(float(omega0 @ (inertia * omega0)) / i_min + 2.0 * dv / i_min)
    rate = (i_max / i_min) * (omega_max + rotor) + orbit
    return max(rate, np.sqrt(dv / i_min), orbit, 1e-300)


def samples_per_period(times: np.ndarray, rate: float) -> float:
    """Stored samples per period 2π/rate of evenly spaced ``times``."""
    step = float(times[1] - times[0])
    return 2.0 * np.pi / (rate * step)


def _needed_samples(span: float, rate: float, per_period: float) -> int:
    return int(np.ceil(per_period * span * rate / (2.0 * np.pi))) + 1


def _output_times(time_cfg: dict[str, Any], rate: float | None) -> np.ndarray:
    start = as_number(time_cfg.get("start", 0.0), "time.start")
    end = as_number(time_cfg.get("end"), "time.end")
    if end <= start:
        raise ConfigError(f"time.end={end:g} must be after time.start={start:g}")
    n = time_cfg.get("n_output", AUTO)
    if n == AUTO:
        needed = AUTO_MIN_SAMPLES if rate is None else _needed_samples(end - start, rate, AUTO_SAMPLES_PER_PERIOD)
        n = min(max(needed, AUTO_MIN_SAMPLES), AUTO_MAX_SAMPLES)
    elif isinstance(n, bool) or not isinstance(n, int) or n < 2:
        raise ConfigError(f"time.n_output={n!r} must be an integer ≥ 2 (number of stored samples, both ends "
                          "included) or auto")
    return np.linspace(start, end, n)
