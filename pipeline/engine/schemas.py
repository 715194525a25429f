"""The config's schemas: one dataclass per config section and group option, in Hydra's ``ConfigStore``.

The YAML files extend them, as in Hydra's ``examples/tutorials/structured_configs/`` (docs/configs.md, "Your own
configs"), so that Hydra checks keys and types while composing (the primary config's sections are any mapping
then, so that ``~output.dpi`` deletes as in any Hydra app); :func:`validate` applies every schema to a composed
config after composing, a group's chosen by its ``_target_``; :func:`sentence` turns OmegaConf's error into one
sentence naming the key, the value and what is expected.

Field metadata says what a type cannot: ``TOLERANCE`` (in (0, 1), read by the budget's check), ``OWN_SETTING`` (an
integrator's own accuracy setting, named when the top-level ``accuracy`` is not read), ``example`` (a required
section's key shown in the sentences), ``type``/``alt`` (a value of an ``Any`` field: ``time.n_output`` is an
integer or ``auto``).

:class:`Task` is what a task (an experiment, a plain run, ``gyrolab batch``, a sweep's jobs) declares it reads and
sets; ``gyrolab.experiments`` derives its tables from the declarations.
"""

from __future__ import annotations

import ast
import dataclasses
import difflib
import re
import types
import typing
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from typing import Any, Dict, List, Optional

from hydra.core.config_store import ConfigStore
from omegaconf import MISSING, DictConfig, ListConfig, OmegaConf
from omegaconf.errors import ConfigKeyError, MissingMandatoryValue, OmegaConfBaseException, ValidationError

from gyrolab.contracts import registry
from gyrolab.errors import ConfigError, shorten

TOLERANCE = {"tolerance": True, "own": True}
OWN_SETTING = {"own": True}
#: keys only the runs that declare them read (Task.reads): a value given to any other run is refused
ONLY_DECLARED = {"only_declared": True}
#: groups whose options are chosen by name on the command line
SELECTABLE_GROUPS = ("system", "body", "initial", "force", "integrator", "regime", "experiment")
#: the sections a group option fills, whose schema is the option's (any mapping in the primary config's)
GROUP_SECTIONS = ("system", "body", "initial", "force", "integrator", "regime")


def _required(example: str) -> Any:
    return field(default=MISSING, metadata={"example": example})


# ---- top-level sections ------------------------------------------------------------------------------------

@dataclass
class Time:
    start: float = 0.0
    end: float = 100.0
    n_output: Any = field(default="auto", metadata={"type": int, "alt": "auto"})


@dataclass
class Output:
    euler_angles: bool = True
    figures: bool = True
    job_figures: bool = field(default=False, metadata=ONLY_DECLARED)
    figure_formats: List[str] = field(default_factory=lambda: ["png"])
    dpi: int = 200
    error_estimate: Optional[bool] = field(default=None, metadata=ONLY_DECLARED)


@dataclass
class Batch:
    output: str = "reductions"
    decimate: int = 10
    chunk: Any = field(default="auto", metadata={"type": int, "alt": "auto"})
    memory: float = 64.0
    scheduler: Optional[str] = None
    points: Optional[int] = None
    points_file: Optional[str] = None
    zip: bool = False


# ---- experiments' settings (each experiment's Task names its section and schema) -------------------------

@dataclass
class WorkPrecision:
    repeats: int = 3
    methods: Dict[str, Dict[str, List[float]]] = field(default_factory=dict)


@dataclass
class StabilityMap:
    theta0: List[float] = field(default_factory=lambda: [0.05, 3.09])
    r0: List[float] = field(default_factory=lambda: [0.05, 10.0])
    r0_spacing: str = "log"
    n_theta0: int = 100
    n_r0: int = 100
    file: str = "stability_map.nc"
    sections: List[Any] = field(default_factory=list)
    section_time: float = 2000.0


@dataclass
class OrbitFamily:
    #: per family: label, a, b, com_direction, k, theta0, section, r0_start, r0_end, max_points, max_period
    #: (checked one by one by the experiment, whose defaults depend on the family's name)
    families: Dict[str, Dict[str, Any]] = field(default_factory=dict)


@dataclass
class Yehia2021:
    orbits: float = 5.0
    residual_tolerance: float = 1e-10


@dataclass
class Gyrolab:
    """The primary config: the scene's sections, the settings of a run, each experiment's section."""

    task: Any = field(default="scene", metadata={"type": str})
    accuracy: Optional[float] = field(default=None, metadata=TOLERANCE)
    allow_large: bool = False
    time: Time = _required("end")
    output: Output = _required("figures")
    batch: Batch = field(default_factory=Batch, metadata=ONLY_DECLARED)
    system: Any = _required("_target_")
    body: Any = _required("a")
    initial: Any = _required("r0")
    force: Optional[Dict[str, Any]] = field(default_factory=dict)
    integrator: Any = _required("rtol")
    regime: Any = field(default=None, metadata=ONLY_DECLARED)
    work_precision: Optional[WorkPrecision] = None
    stability_map: Optional[StabilityMap] = None
    orbit_family: Optional[OrbitFamily] = None
    #: regimes, evidence, then one entry per named comparison (its keys depend on the regime compared)
    regime_validity: Optional[Dict[str, Any]] = None
    yehia2021: Optional[Yehia2021] = None


# ---- group options ------------------------------------------------------------------------------------------

@dataclass
class System:
    _target_: str = MISSING


@dataclass
class RigidBody:
    units: str = "nondimensional"
    a: Optional[float] = None
    b: Optional[float] = None
    com_direction: Optional[List[Any]] = None
    allow_nonphysical: bool = False
    inertia: Optional[List[Any]] = None
    mass: Optional[float] = None
    com: Optional[List[Any]] = None
    g: Optional[float] = None


@dataclass
class GyrostatBody:
    units: str = "nondimensional"
    inertia: Optional[List[Any]] = None
    gyrostatic_momentum: Optional[List[Any]] = None
    orbit_rate: Optional[float] = None
    allow_nonphysical: bool = False


@dataclass
class Attitude:
    p0: Optional[float] = None
    q0: Optional[float] = None
    r0: Optional[float] = None
    theta0: Optional[float] = None
    phi0: Optional[float] = None
    psi0: Optional[float] = None
    gamma0: Optional[List[Any]] = None


@dataclass
class GyrostatInitial(Attitude):
    euler_rates0: Optional[List[Any]] = None


@dataclass
class UniformGravity:
    _target_: str = MISSING


@dataclass
class Newtonian:
    _target_: str = MISSING
    k: Optional[float] = None
    R: Optional[float] = None
    N: Optional[float] = None


@dataclass
class Magnetic:
    _target_: str = MISSING
    moment: List[Any] = field(default_factory=lambda: [0.0, 0.0, 1.0])
    field: float = 0.0
    direction: List[Any] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 1.0])


@dataclass
class Tolerances:
    _target_: str = MISSING
    rtol: float = field(default=1e-10, metadata=TOLERANCE)
    atol: float = field(default=1e-10, metadata=TOLERANCE)
    max_step: Optional[float] = None


@dataclass
class FixedStep:
    _target_: str = MISSING
    step: float = field(default=0.01, metadata=OWN_SETTING)


@dataclass
class LiePoisson(FixedStep):
    order: int = 4


@dataclass
class Taylor:
    _target_: str = MISSING
    order: Optional[int] = None
    tol: float = field(default=1e-16, metadata=TOLERANCE)
    precision: str = "double"
    head: int = 0


@dataclass
class Auto:
    _target_: str = MISSING
    accuracy: Optional[float] = field(default=None, metadata=TOLERANCE)
    pilot_fraction: float = 0.1
    safety: float = 1.0
    extended_precision: Optional[bool] = None


@dataclass
class Regime:
    _target_: str = MISSING
    formula: str = "corrected"
    periods: int = 3
    samples_per_period: int = 200


@dataclass
class SmallParameter(Regime):
    order: Optional[int] = None


@dataclass
class ResonantOmega3(Regime):
    branch: str = "i"
    sign: int = 1
    phase_deg: float = 45.0


#: group -> built-in plugin class name -> its schema (the YAML option of that plugin extends it)
BUILTIN = {
    "system": {"FixedPoint": System, "OrbitingGyrostat": System},
    "force": {"UniformGravity": UniformGravity, "Newtonian": Newtonian, "Magnetic": Magnetic},
    "integrator": {"RK4": FixedStep, "RK4Numba": FixedStep, "LiePoisson": LiePoisson, "Taylor": Taylor, "Auto": Auto,
                   **dict.fromkeys(("RK45", "DOP853", "DOP853Numba", "LSODA", "Radau", "BDF"), Tolerances)},
    "regime": {"SmallParameter": SmallParameter, "LargeParameter": Regime, "ResonantOmega3": ResonantOmega3},
}
#: a system's body and initial sections (a third-party system: RigidBody, or its ``default_body``'s keys)
SYSTEM_SECTIONS = {"fixed_point": (RigidBody, Attitude), "orbiting_gyrostat": (GyrostatBody, GyrostatInitial)}


def register() -> None:
    """Store the schemas: ``gyrolab_schema`` (the primary config's) and ``schema/<group>/<name>``."""
    store = ConfigStore.instance()
    primary = OmegaConf.structured(_while_composing(Gyrolab))
    OmegaConf.set_struct(primary, False)  # a user's own group (+notes=lab) composes; validate refuses it for a run
    store.store(name="gyrolab_schema", node=primary)
    for group, schemas in BUILTIN.items():
        for schema in set(schemas.values()):
            store.store(group=f"schema/{group}", name=schema.__name__.lower(), node=schema)
    for body, initial in SYSTEM_SECTIONS.values():
        store.store(group="schema/body", name=body.__name__.lower(), node=body)
        store.store(group="schema/initial", name=initial.__name__.lower(), node=initial)


def _while_composing(schema: type) -> type:
    """The primary config's schema while Hydra composes: its keys and top-level values typed, its sections any
    mapping, so that ``~output.dpi`` and ``~work_precision.methods`` delete as in any Hydra app (the sections are
    typed by :func:`validate` after composing)."""
    hints, fields = typing.get_type_hints(schema), []
    for f in dataclasses.fields(schema):
        base = _strip_optional(hints[f.name])
        if dataclasses.is_dataclass(base) or typing.get_origin(base) is dict:
            fields.append((f.name, Any, field(default=MISSING if "example" in f.metadata else None)))
        else:
            fields.append((f.name, hints[f.name], field(default=f.default, metadata=f.metadata)))
    return dataclasses.make_dataclass(f"{schema.__name__}WhileComposing", fields)


@cache
def plugin_schema(cls: type) -> type:
    """A third-party plugin's schema: its ``schema`` dataclass, else one made from its ``__init__`` keywords
    (their annotations where OmegaConf can check them, else ``Any``)."""
    declared = getattr(cls, "schema", None)
    if dataclasses.is_dataclass(declared):
        return declared
    try:
        hints = typing.get_type_hints(cls.__init__)
    except Exception:  # noqa: BLE001 - an annotation that does not evaluate: the key is checked, not its type
        hints = {}
    fields = [("_target_", str, MISSING)]
    for name, default in registry.default_params(cls).items():
        hint = hints.get(name, Any)
        try:
            OmegaConf.structured(dataclasses.make_dataclass("Probe", [(name, hint, default)]))
        except (OmegaConfBaseException, ValueError, TypeError):
            hint = Any
        fields.append((name, hint, field(default_factory=lambda d=default: d) if isinstance(default, (list, dict))
                       else default))
    return dataclasses.make_dataclass(f"{cls.__name__}Schema", fields)


@cache
def body_schema(keys: tuple[str, ...]) -> type:
    """The body schema of a third-party system's ``default_body``: its keys, any value."""
    return dataclasses.make_dataclass("PluginBody", [(k, Any, None) for k in keys])


# ---- validation ---------------------------------------------------------------------------------------------

def validate(cfg: DictConfig) -> dict[str, Any]:
    """``cfg`` merged into its schemas (the primary config's, then each group's by its ``_target_``) and resolved to
    plain values; ConfigError in one sentence for an unknown key, a value of the wrong type, a bad reference."""
    for group in GROUP_SECTIONS:
        node = cfg.get(group) if group in cfg and not OmegaConf.is_missing(cfg, group) else None
        if node is not None and not isinstance(node, DictConfig):
            raise ConfigError(f"{group}={shorten(repr(node))}: `{group}` is a section (a mapping), not a value; "
                              f"choose an option ({group}=NAME) or set its keys ({group}.KEY=...)")
    try:
        # a plain copy: a key Hydra's ``+key=`` added to a composed structured config is refused here too
        merged = OmegaConf.merge(_structured(Gyrolab), OmegaConf.to_container(cfg, resolve=False))
        for key, schema in _group_schemas(merged):
            node = OmegaConf.select(merged, key)
            if isinstance(node, DictConfig) and OmegaConf.get_type(node) is dict:
                try:
                    typed = OmegaConf.merge(_structured(schema), node)
                except OmegaConfBaseException as error:
                    raise sentence(error, prefix=f"{key}.") from None
                except OverflowError:  # an integer of hundreds of digits for a number
                    raise ConfigError(f"{key}: a number is too large; gyrolab takes numbers up to 1e+100 in "
                                      "magnitude (use nondimensional or scaled units)") from None
                OmegaConf.update(merged, key, typed, merge=False)
    except OmegaConfBaseException as error:
        raise sentence(error) from None
    plain = resolve_plain(merged)
    _check_metadata(plain, Gyrolab, "")
    return plain


#: a schema's config, made once (OmegaConf.merge copies it)
_structured = cache(OmegaConf.structured)


def _group_schemas(cfg: DictConfig) -> list[tuple[str, type]]:
    """(key, schema) of the config's group sections whose ``_target_`` names a registered plugin."""
    found = []
    sections = [("system", "system"), ("integrator", "integrator"), ("regime", "regime")]
    sections += [(f"force.{name}", "force") for name in (cfg.get("force") or {})]
    system = None
    for key, group in sections:
        node = OmegaConf.select(cfg, key)
        target = node.get("_target_") if isinstance(node, DictConfig) else None
        name, schema = _schema_of(group, target)
        if schema is not None:
            found.append((key, schema))
        if group == "system":
            system = name
    body, initial = SYSTEM_SECTIONS.get(system, (None, None)) if system else (None, None)
    if system and system not in SYSTEM_SECTIONS:  # a third-party system: its default_body's keys, else a rigid body
        cls = registry.load("system", system)
        default = getattr(cls, "default_body", None)
        body = body_schema(tuple(default)) if isinstance(default, dict) else RigidBody
        initial = GyrostatInitial
    return found + [(k, s) for k, s in (("body", body), ("initial", initial)) if s is not None]


def _schema_of(group: str, target: Any) -> tuple[str | None, type | None]:
    if not isinstance(target, str):
        return None, None
    by_target = {registry._normalise(t): n for n, t in registry.targets(group).items()}
    name = by_target.get(registry._normalise(target))
    if name is None:
        return None, None  # not registered: Scene.from_config and the trust boundary say so
    builtin = BUILTIN[group].get(registry.targets(group)[name].rpartition(":")[2])
    if builtin is not None and name in registry.BUILTINS[group]:
        return name, builtin
    try:
        return name, plugin_schema(registry.load(group, name))
    except ConfigError:
        return name, None  # an unusable plugin: register_plugin_configs warned, Scene.from_config refuses it


def _check_metadata(node: Any, schema: type, prefix: str) -> None:
    """The checks a type cannot say: a value of an ``Any`` field with ``type`` (and ``alt``), recursively."""
    hints = typing.get_type_hints(schema)
    for f in dataclasses.fields(schema):
        value = node.get(f.name)
        key = f"{prefix}{f.name}"
        expected = f.metadata.get("type")
        if expected is not None and value != f.metadata.get("alt", object()) and (
                isinstance(value, bool) or not isinstance(value, expected)):
            raise ConfigError(_type_sentence(key, value, expected, f.metadata.get("alt")))
        if isinstance(value, dict) and dataclasses.is_dataclass(_strip_optional(hints[f.name])):
            _check_metadata(value, _strip_optional(hints[f.name]), key + ".")


def sentence(error: OmegaConfBaseException, prefix: str = "") -> ConfigError:
    """One sentence for OmegaConf's schema errors: the key (under ``prefix``), the value, what is expected."""
    key = prefix + str(getattr(error, "full_key", None) or "")
    schema = getattr(error, "object_type", None)
    if isinstance(error, MissingMandatoryValue) and key in REQUIRED_SECTIONS:
        return ConfigError(missing_section(key))
    if isinstance(error, ConfigKeyError) and dataclasses.is_dataclass(schema):
        parent = key.rpartition(".")[0]
        known = [f"{parent}.{f.name}" if parent else f.name for f in dataclasses.fields(schema)]
        return ConfigError(unknown_key_sentence(key, known + ([] if parent else list(SELECTABLE_GROUPS))))
    if isinstance(error, ValidationError):
        key, hint, value = _validation_subject(error, key, schema)
        if key and hint is not None:
            return ConfigError(_mismatch_sentence(key, value, hint))
    reason = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
    return ConfigError(f"{key or 'the config'} is not valid ({shorten(reason, 160)})")


def unknown_key_sentence(key: str, known: Sequence[str], override: str = "", cause: str = "") -> str:
    """"`time.ennd` is not a key of `time`; did you mean `time.end`?" (with the valid keys if none is close)."""
    parent = key.rpartition(".")[0]
    where = f"`{parent}`" if parent else "the config"
    close = difflib.get_close_matches(key, known, n=1, cutoff=0.6)
    if "ValidationError" in cause or "ConfigTypeError" in cause:
        return (f"{shorten(override or key)!s}: `{shorten(key)}` is a section, not a value; set one of its keys "
                f"(e.g. {next((k for k in known if k.startswith(key + '.')), key + '.KEY')}=...)")
    if close:
        return f"`{shorten(key)}` is not a key of {where}; did you mean `{close[0]}`?"
    siblings = sorted({k.rpartition(".")[2] for k in known if k.rpartition(".")[0] == parent})  # a key once
    return (f"`{shorten(key)}` is not a key of {where}; valid keys: "
            f"{shorten(', '.join(siblings) or '(none)', 300)}")



def _validation_subject(error: ValidationError, key: str, schema: Any) -> tuple[str, Any, Any]:
    """(key, expected type, value) of a ValidationError; a merge error names only the schema ("Merge error: list is
    not a subclass of Time. value: [1, 2]"): its key is the config's section of that type."""
    merge = re.search(r"Merge error: \w+ is not a subclass of (\w+)\. value: (.*)", str(error))
    if key or merge is None:
        value = getattr(error, "value", None)
        value = OmegaConf.to_container(value) if isinstance(value, (DictConfig, ListConfig)) else value
        name = key.rpartition(".")[2].split("[")[0]
        return key, typing.get_type_hints(schema).get(name) if dataclasses.is_dataclass(schema) else None, value
    parent = getattr(error, "parent_node", None)
    for name in (parent.keys() if isinstance(parent, DictConfig) else ()):
        node = parent._get_node(name)
        if isinstance(node, DictConfig) and OmegaConf.get_type(node).__name__ == merge.group(1):
            try:
                value = ast.literal_eval(merge.group(2))
            except (ValueError, SyntaxError):
                value = merge.group(2)
            return str(name), OmegaConf.get_type(node), value
    return key, None, None


def _mismatch_sentence(key: str, value: Any, hint: Any) -> str:
    """A value of the wrong kind: a list for a section or the reverse, a value for a section, a wrong type."""
    section = dataclasses.is_dataclass(_strip_optional(hint)) or typing.get_origin(_strip_optional(hint)) is dict
    if (section and isinstance(value, list)) or (_is_list(hint) and isinstance(value, dict)):
        return f"{key}={shorten(repr(value))}: a list and a section (a mapping) do not match; {key} must be {_words(hint)}"
    if section:
        base = _strip_optional(hint)
        example = REQUIRED_SECTIONS.get(key) or (dataclasses.fields(base)[0].name if dataclasses.is_dataclass(base)
                                                 else "NAME")
        return (f"{key}={shorten(repr(value))}: `{key}` is a section, not a value; set one of its keys "
                f"(e.g. {key}.{example}=...)")
    return _type_sentence(key, value, hint)


def _is_list(hint: Any) -> bool:
    return typing.get_origin(_strip_optional(hint)) in (list, List)


def _strip_optional(hint: Any) -> Any:
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    return args[0] if typing.get_origin(hint) in (typing.Union, types.UnionType) and len(args) == 1 else hint


_WORDS = {bool: "true or false", int: "an integer", float: "a number", str: "a string"}


def _words(hint: Any) -> str:
    """What a value of type ``hint`` is, in words: "a number or null", "true or false", "a list"."""
    base = _strip_optional(hint)
    words = _WORDS.get(base) or ("a list" if _is_list(base) else "a section (a mapping)"
                                 if dataclasses.is_dataclass(base) or typing.get_origin(base) is dict else "a value")
    if base is not hint:
        words = "true, false or null" if base is bool else f"{words} or null"
    return words


def _type_sentence(key: str, value: Any, hint: Any, alt: Any = None) -> str:
    return f"{key}={shorten(repr(value))} must be {_words(hint)}{f' or {alt}' if alt is not None else ''}"


# ---- tables derived from the schemas ------------------------------------------------------------------------

#: sections every run needs (no default in the schema), each with a key to show in the sentences: ``{"time": "end",
#: ...}`` (``gyrolab.app`` refuses ``~time``)
REQUIRED_SECTIONS = {f.name: f.metadata["example"] for f in dataclasses.fields(Gyrolab) if "example" in f.metadata}


def missing_section(section: str) -> str:
    example = REQUIRED_SECTIONS[section]
    how = f"choose one ({section}=NAME)" if example == "_target_" else f"set its keys instead (e.g. {section}.{example}=...)"
    return f"the config has no `{section}` section (deleted with ~{section}?); every run needs it: {how}"


@cache
def keys_with(flag: str) -> tuple[str, ...]:
    """Field names whose metadata has ``flag`` in any schema (``tolerance``: rtol, atol, tol, accuracy)."""
    schemas = [Gyrolab, Time, Output, Batch, *(s for group in BUILTIN.values() for s in group.values())]
    return tuple(dict.fromkeys(f.name for s in schemas for f in dataclasses.fields(s) if f.metadata.get(flag)))


@cache
def only_declared_keys() -> tuple[str, ...]:
    """Dotted keys only the runs that declare them read (``batch``, ``output.error_estimate``, ...)."""
    return tuple(prefix + f.name for prefix, schema in (("", Gyrolab), ("output.", Output))
                 for f in dataclasses.fields(schema) if f.metadata.get("only_declared"))


# ---- what a task reads and sets -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Task:
    """What a run reads and sets, beside its ``run``: an experiment's ``TASK``, and the plain run's.

    ``reads``: the keys of :func:`only_declared_keys` it reads (``output.error_estimate`` when it runs Scene.run);
    ``sets``: keys it sets itself for the scenes it runs (a value given for them changes nothing), with why;
    ``section``/``settings``: its own config section and that section's schema (a field of :class:`Gyrolab`).
    """

    name: str
    reads: tuple[str, ...] = ()
    sets: dict[str, str] = field(default_factory=dict)
    section: str | None = None
    settings: type | None = None

    def sets_all(self, keys: tuple[str, ...], why: str) -> Task:
        return dataclasses.replace(self, sets={**self.sets, **dict.fromkeys(keys, why)})


def resolve_plain(cfg: DictConfig) -> dict[str, Any]:
    """``OmegaConf.to_container(cfg, resolve=True)`` with a one-sentence error for a broken interpolation."""
    try:
        return OmegaConf.to_container(cfg, resolve=True, throw_on_missing=True)
    except OmegaConfBaseException as error:
        key = getattr(error, "full_key", None) or "?"
        raw = raw_value(cfg, key)
        reason = first_line(error).split(" full_key:")[0]
        raise ConfigError(f"{shorten(key)}={shorten(str('?' if raw is None else raw))} cannot be resolved "
                          f"({shorten(reason, 160)}); refer to an existing key, e.g. ${{time.end}}, or give a plain "
                          "value") from None


def raw_value(cfg: DictConfig, key: str) -> Any:
    """The unresolved value of dotted ``key`` (None when the config has no such key)."""
    node: Any = cfg
    for part in key.split("."):
        node = node._get_node(part, validate_access=False) if isinstance(node, DictConfig) else None
        if node is None:
            return None
    return OmegaConf.to_container(node, resolve=False) if isinstance(node, DictConfig) else node._value()


def first_line(error: Exception) -> str:
    """The first line of a Hydra/OmegaConf message, without its pointer to the online docs."""
    lines = [line.strip() for line in str(error).strip().splitlines() if line.strip()]
    line = lines[0] if lines else type(error).__name__
    if line.endswith(":") and len(lines) > 1:  # "In 'experiment/x': ConfigTypeError raised while composing config:"
        line = f"{line} {lines[1]}"
    for merge in ("Cannot merge DictConfig with ListConfig", "Cannot merge ListConfig with DictConfig"):
        line = line.replace(merge, "a list and a section (a mapping) do not match: one is given where the config "
                                   "has the other")
    return line.split(" See https://")[0]


register()  # at import, as Hydra's structured-config examples do: before any composition
