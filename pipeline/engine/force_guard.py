"""The scene's Python right-hand side, guarded when a third-party force takes part (docs/plugins.md, "What the
engine checks"): a plugin torque that raises, returns None or the wrong shape, or NaN (on which DOP853 would reject
every step and never return) becomes one ``IntegrationError`` sentence naming the force. gyrolab's own forces run
unguarded.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from gyrolab.contracts import Force, System, registry
from gyrolab.contracts.claims import torque_problem
from gyrolab.errors import GyrolabError, IntegrationError, shorten

_RULE = "torque(omega, axes) must return a finite float array of shape (3,) (gyrolab.contracts.Force, rule 3)"


def plugin_forces(forces: Sequence[Force]) -> list[Force]:
    """The forces that are not gyrolab's own classes (``registry.BUILTINS``, trusted): third-party plugins and
    ad-hoc subclasses."""
    builtin = set(registry.BUILTINS["force"].values())
    return [f for f in forces if f"{type(f).__module__}:{type(f).__qualname__}" not in builtin]


class GuardedRhs:
    """``system.rhs`` that names the plugin force at fault in one sentence (see the module docstring)."""

    def __init__(self, system: System, plugins: Sequence[Force]) -> None:
        self.system, self.plugins = system, list(plugins)
        self.rhs = system.rhs
        self.inspected = False

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        if not self.inspected:
            self.inspect(t, y)
            self.inspected = True
        try:
            dy = self.rhs(t, y)
        except GyrolabError:
            raise
        except Exception as exc:  # noqa: BLE001 - one sentence instead of a traceback through the integrator
            self.inspect(t, y)  # raises naming the force, when a plugin torque is at fault
            raise IntegrationError(f"the right-hand side of system {self.system.name!r} raised "
                                   f"{type(exc).__name__} at t = {t:.6g}: {shorten(str(exc), 160)}") from exc
        if not np.isfinite(dy).all():  # raise now: a NaN derivative makes an adaptive method reject steps forever
            self.inspect(t, y)
            where = "a non-finite state (the step blew up)" if not np.isfinite(y).all() else "a finite state"
            raise IntegrationError(f"the right-hand side of system {self.system.name!r} is not finite at "
                                   f"t = {t:.6g} from {where}; reduce the step or tolerance")
        return dy

    def inspect(self, t: float, y: np.ndarray) -> None:
        """Evaluate the right-hand side at (t, y) with every plugin torque checked; IntegrationError naming the
        first force whose torque raises or breaks rule 3, else return (the fault, if any, is elsewhere)."""
        saved = {id(f): f.__dict__.get("torque") for f in self.plugins}
        try:
            for force in self.plugins:
                force.torque = _Recorder(force, force.torque, t)
            with np.errstate(all="ignore"):
                self.rhs(t, y)
        except GyrolabError:
            raise
        except Exception:  # noqa: BLE001 - not a plugin torque's doing: the caller says what happened
            pass
        finally:
            for force in self.plugins:
                previous = saved[id(force)]
                if previous is None:
                    force.__dict__.pop("torque", None)
                else:
                    force.torque = previous


class _Recorder:
    """A force's torque that raises one sentence when the torque raises or returns a value breaking rule 3."""

    def __init__(self, force: Force, torque: Any, t: float) -> None:
        self.force, self.torque, self.t = force, torque, t

    def __call__(self, omega: np.ndarray, *args: Any) -> Any:
        name = self.force.name
        try:
            value = self.torque(omega, *args)
        except GyrolabError:
            raise
        except Exception as exc:  # noqa: BLE001 - the plugin's own error, named
            raise IntegrationError(f"the torque of force {name!r} raised {type(exc).__name__} at t = {self.t:.6g}: "
                                   f"{shorten(str(exc), 160) or '(no message)'}") from exc
        problem = torque_problem(value)
        if problem:
            raise IntegrationError(f"the torque of force {name!r} {problem} at t = {self.t:.6g}, "
                                   f"ω = {np.round(np.asarray(omega, dtype=float), 6).tolist()}; {_RULE}")
        return value
