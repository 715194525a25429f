"""Contract of an integrator plugin: advance y' = f(t, y) and sample it at output times."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np

from gyrolab.contracts.integrator_rules import checked

RightHandSide = Callable[[float, np.ndarray], np.ndarray]
ProgressCallback = Callable[[float], None]


@dataclass(frozen=True)
class CompiledModel:
    """A system in the compiled kernels' form: a model id (``gyrolab.plugins.compiled.models``) and its parameters."""

    model: int
    params: np.ndarray


@dataclass
class IntegratorStats:
    """Work done by one integration; ``n_rejected`` is None where the method does not report it."""

    nfev: int
    n_steps: int
    n_rejected: int | None
    wall_time: float
    njev: int = 0
    nlu: int = 0

    def attributes(self) -> dict[str, Any]:
        """netCDF-safe attributes (unknown counts are left out, not stored as a fake number)."""
        # getattr over the fields: dataclasses.asdict deep-copies every value (~0.1 ms of a run's dataset)
        values = ((f.name, getattr(self, f.name)) for f in fields(self))
        return {f"integrator_{k}": v for k, v in values if v is not None}


@dataclass
class Solution:
    """Samples of the state at the requested output times."""

    t: np.ndarray  # (n,)
    y: np.ndarray  # (n, state size)
    stats: IntegratorStats


class Integrator(ABC):
    """A method that integrates an initial-value problem.

    Rules for implementers:

    1. ``__init__(self, **params)`` takes the plugin's config parameters as
       keyword arguments with defaults (``rtol``/``atol`` for adaptive
       methods, ``step`` for fixed-step ones), validates them and raises
       ``gyrolab.errors.ConfigError`` on bad values.
    2. ``integrate(fun, t_out, y0)`` returns the state at every time in
       ``t_out`` (increasing, ``t_out[0]`` is the initial time), computed by
       dense output or by landing on those times, never by storing every
       internal step.
    3. It counts its work (``IntegratorStats``: right-hand-side evaluations,
       accepted and rejected steps where known, wall time).
    4. It never returns non-finite values: a failure (step size underflow,
       NaN or inf in the state) raises ``gyrolab.errors.IntegrationError``
       with one sentence saying when and why.
    5. It calls ``progress(t)``, when given, every few steps (cheap; the
       callback decides whether to report).
    6. A compiled integrator sets ``needs_compiled_model`` and integrates the
       ``compiled`` model it is given (the system's ``compiled_model()``)
       instead of calling ``fun``; the scene refuses it, before integrating,
       for a system or force that has no compiled form.
    7. ``attributes()`` gives its settings for the dataset.
    8. ``prepare(system)`` is called once by the scene before integrating
       (default: nothing); ``auto`` uses it to consult the system's regimes.

    What gyrolab enforces (``gyrolab.contracts.integrator_rules``): every
    subclass's ``integrate`` — built-in or third-party, under its own name —
    is wrapped when the class is defined, so that each call checks y0 (finite,
    1-D) and ``t_out`` (strictly increasing), then the returned ``Solution``
    (``t`` of len(t_out), ``y`` of shape (len(t_out), len(y0)), all finite,
    ``IntegratorStats``). A violation, or any exception that is not a
    ``gyrolab.errors.GyrolabError``, ends the run as one ``IntegrationError``
    sentence naming the integrator (exit code 3); nothing is written.
    """

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "integrate" in cls.__dict__:  # the class's own integrate, not an inherited (already wrapped) one
            cls.integrate = checked(cls.__dict__["integrate"])

    name: ClassVar[str]
    adaptive: ClassVar[bool]
    needs_compiled_model: ClassVar[bool] = False
    prefers_compiled_model: ClassVar[bool] = False  # use the compiled model when the system has one

    @abstractmethod
    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        """Integrate from t_out[0] and sample the state at t_out."""

    def prepare(self, system: Any) -> None:
        """Called once by the scene with its system, for integrators that need more than the right-hand
        side (``auto`` consults the system's analytic regimes). The default needs nothing."""

    def attributes(self) -> dict[str, Any]:
        return {}
