"""The registered integrators by capability: the valid choices a refusal for a missing capability lists, found by
asking every registered integrator class, never a table of names.
"""

from __future__ import annotations

from collections.abc import Callable

from gyrolab.contracts import registry
from gyrolab.contracts.integrator import Integrator
from gyrolab.errors import GyrolabError


def integrator_classes() -> dict[str, type[Integrator]]:
    """Every registered integrator that loads, by name: fixed-step methods first, then adaptive ones, each in the
    registry's order (built-ins as listed, then entry points)."""
    loaded = []
    for position, name in enumerate(registry.targets("integrator")):
        try:
            cls = registry.load("integrator", name)
        except (GyrolabError, ImportError, AttributeError):   # a broken third-party package: not a valid choice
            continue
        loaded.append((bool(getattr(cls, "adaptive", False)), position, name, cls))
    return {name: cls for _, _, name, cls in sorted(loaded)}


def integrators_with(*capabilities: str, accept: Callable[[type[Integrator]], bool] | None = None) -> list[str]:
    """Names of the registered integrators that declare every one of ``capabilities`` (and pass ``accept``)."""
    return [name for name, cls in integrator_classes().items()
            if all(cls.supports(c) for c in capabilities) and (accept is None or accept(cls))]


def or_list(names: list[str]) -> str:
    """``a, b or c`` (``(none registered)`` for no name)."""
    if not names:
        return "(none registered)"
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"
