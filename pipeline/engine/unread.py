"""Config values a run would not read: refused when the user gave them, said and recorded when a config file did
(docs/configs.md, "Values a run does not read").

The top-level ``accuracy`` is read only by an integrator whose settings refer to it (``accuracy: ${accuracy}``),
which is read off the composed config, never off the integrator's name.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from gyrolab.contracts import registry
from gyrolab.engine.schemas import keys_with, raw_value
from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import CHOOSES_METHOD
from gyrolab.errors import ConfigError, GyrolabError

ACCURACY = "accuracy"
#: the run dataset's global attribute saying that the config's ``accuracy`` was not read, and why
ACCURACY_IGNORED_ATTRIBUTE = "accuracy_ignored"
#: an integrator's own accuracy settings (the schemas' tolerances and steps), named as what the user can set instead
OWN_SETTINGS = keys_with("own")
#: an interpolation's references: ``${key}``, ``${..key}``, ``${oc.select:key,default}`` (a resolver's name is
#: captured too, and found in no config)
_REFERENCE = re.compile(r"\$\{\s*(?:oc\.select:)?\s*(\.*[A-Za-z_][\w.]*)")


def given_overrides(overrides: Sequence[str]) -> dict[str, str]:
    """The keys an override list gives a value, each with its override (``accuracy=1e-8``, ``+accuracy=...``,
    ``++batch.output=final``, ``force=[magnetic]``); a deletion (``~accuracy``) gives none."""
    given = {}
    for text in overrides:
        key, has_value, _ = str(text).partition("=")
        if has_value and not key.startswith("~"):
            given[key.lstrip("+").split("@", 1)[0].strip()] = str(text)
    return given


def covers(key: str, given: str) -> bool:
    """Whether config key ``key`` is ``given`` or a section holding it (``batch`` covers ``batch.output``)."""
    return given == key or given.startswith(key + ".")


def reads_accuracy(cfg: DictConfig) -> bool:
    """Whether the selected integrator's settings refer to the top-level ``accuracy``, directly (``${accuracy}``,
    ``${..accuracy}``) or through other keys of the config (``${my.target}`` with ``my.target: ${accuracy}``)."""
    node = cfg.get("integrator")
    if not isinstance(node, DictConfig):
        return False
    return _refers_to(cfg, OmegaConf.to_container(node, resolve=False), "integrator", set())


def _refers_to(cfg: DictConfig, value: Any, where: str, seen: set[str]) -> bool:
    """Whether the unresolved ``value`` of key ``where`` refers to ``accuracy``, following the keys it refers to."""
    if isinstance(value, dict):
        return any(_refers_to(cfg, v, f"{where}.{k}", seen) for k, v in value.items())
    if isinstance(value, list):
        return any(_refers_to(cfg, v, where, seen) for v in value)
    if not isinstance(value, str):
        return False
    for reference in _REFERENCE.findall(value):
        dots = len(reference) - len(reference.lstrip("."))
        key = reference if not dots else ".".join([*where.split(".")[:-dots], reference.lstrip(".")])
        if key == ACCURACY:
            return True
        if key not in seen:
            seen.add(key)
            if _refers_to(cfg, raw_value(cfg, key), key, seen):
                return True
    return False


def unread_accuracy(cfg: DictConfig) -> str | None:
    """What is wrong when ``cfg`` sets ``accuracy`` and its integrator does not read it (the core of the refusal
    and of the warning: "accuracy=1e-08 is the target of integrator=auto only; integrator=taylor does not read
    it and runs at its own settings (integrator.tol=1e-16)"), else None."""
    try:
        value = OmegaConf.select(cfg, ACCURACY, throw_on_missing=False)
    except OmegaConfBaseException:
        return None  # a broken interpolation: check_scene_config says so
    if value is None or reads_accuracy(cfg):
        return None
    name, own = integrator_name(cfg), _own_settings(cfg.get("integrator"))
    settings = f" ({', '.join(f'integrator.{k}={v!r}' for k, v in own)})" if own else ""
    readers = integrators_with(CHOOSES_METHOD)  # they choose their method for a target: the way to ask for one
    if name in readers:  # its own accuracy setting was given a value: it replaces the top-level one
        return f"{ACCURACY}={value!r} is not read: integrator={name} runs at its own settings{settings}, which replace it"
    target = (f"the target of integrator={or_list(readers)} only" if readers
              else "read by no registered integrator's settings")
    return f"{ACCURACY}={value!r} is {target}; integrator={name} does not read it and runs at its own settings{settings}"


def refusal(cfg: DictConfig, value_sentence: str) -> ConfigError:
    """The one-sentence refusal of an explicitly given ``accuracy`` the integrator does not read, with the ways out."""
    value = OmegaConf.select(cfg, ACCURACY)
    name, own = integrator_name(cfg), [f"integrator.{k}" for k, _ in _own_settings(cfg.get("integrator"))]
    readers = integrators_with(CHOOSES_METHOD)
    if name in readers:
        ways = [f"drop {' and '.join(own)} to aim at {ACCURACY}={value!r}", f"drop {ACCURACY}={value!r}"]
    else:
        ways = [f"ask integrator={readers[0]} {ACCURACY}={value!r}"] if readers else []
        ways.append(f"set {' and '.join(own) or 'the integrator settings'} instead (and drop {ACCURACY}={value!r})")
    return ConfigError(f"{value_sentence}: {' or '.join(ways)}")


def ignored_accuracy(cfg: DictConfig, overrides: Sequence[str]) -> str | None:
    """The warning (and the dataset's ``accuracy_ignored``) for an ``accuracy`` a run proceeds without reading: one a
    config file set, or one a sweep gives to every job while only some jobs' integrators read it; else None."""
    sentence = unread_accuracy(cfg)
    if sentence is None:
        return None
    source = ("the sweep gives it to every job, and the jobs whose integrator reads it aim at it"
              if ACCURACY in given_overrides(overrides) else "a config file set it, as a default for the integrators "
              "that read it")
    return f"{sentence}, so this run does not aim at that accuracy ({source})"


def refuse_given_accuracy(cfg: DictConfig, overrides: Sequence[str]) -> None:
    """ConfigError when ``overrides`` give ``accuracy`` and the integrator of ``cfg`` does not read it."""
    if ACCURACY not in given_overrides(overrides):
        return
    sentence = unread_accuracy(cfg)
    if sentence is not None:
        raise refusal(cfg, sentence)


def integrator_name(cfg: DictConfig) -> str:
    """The registered name of the config's integrator (its ``_target_``), or the target itself if not registered."""
    target = OmegaConf.select(cfg, "integrator._target_", default=None)
    try:
        name, _ = registry.resolve_target("integrator", target, "integrator")
    except GyrolabError:
        return str(target)
    return name


def _own_settings(node: Any) -> list[tuple[str, Any]]:
    try:
        plain = OmegaConf.to_container(node, resolve=True) if isinstance(node, DictConfig) else {}
    except OmegaConfBaseException:
        return []
    return [(key, plain[key]) for key in OWN_SETTINGS if plain.get(key) is not None]
