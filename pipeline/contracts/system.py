"""Contract of a mechanical system plugin: its state, equations of motion and outputs."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import numpy as np
import xarray as xr

from gyrolab.contracts.force import Force
from gyrolab.contracts.integrator import CompiledModel
from gyrolab.kernels import model


class System(ABC):
    """The equations of motion of one kind of body, with their outputs and invariants.

    Rules for implementers (``gyrolab.testing.check_system`` checks them; run it in your tests):

    1. ``body_type`` is the class that reads the ``body`` config section
       (``body_type.from_config(cfg)``); forces are built with that body.
       ``default_body`` (a dict, optional) becomes the body option ``body=NAME``
       (docs/plugins.md, "System plugins").
    2. ``__init__(self, body, forces, initial, output, *, param=default, ...)``
       validates the ``initial`` section (one-sentence ``ConfigError``) and
       decides the state layout: only the state its forces and requested
       outputs need. Its own parameters are keywords with defaults.
    3. ``initial_state()`` returns y0; ``rhs(t, y)`` returns dy/dt (model
       units) for one state; it is the integrators' inner loop.
    4. ``variables(t, y)`` turns a trajectory (n, size) into xarray
       variables on dims ``time`` and ``axis``, each with CF ``units`` and
       ``long_name``; it includes the monitored first integrals
       (``invariants``), which are exactly those every force preserves.
    5. ``attributes()`` describes the system's parameters and initial state
       for the dataset; ``title()`` names the scene in a few words for figures.
    6. ``compiled_model()`` returns the system (with its forces) in the
       compiled kernels' form. The default traces ``rhs`` once on symbols
       (``gyrolab.kernels.model``; docs/plugins.md, "System plugins"); when it
       cannot be traced it returns None and sets ``compile_error`` to one
       sentence saying why. Override it to return None for a system that must
       not be compiled.
    7. Optionally, ``invariant_values(y)`` returns each monitored invariant
       (``invariants``) along states of shape (..., state size), vectorised
       over any leading dimensions; ``gyrolab batch`` (``gyrolab.batch.outputs``)
       uses it for the drifts of many trajectories at once. None (the
       default): ``gyrolab batch`` computes them from ``variables``, one trajectory
       at a time.
    8. Optionally, ``initial_states(initial, columns)`` returns
       ``initial_state()`` for many points at once (``gyrolab.batch.plan``):
       ``initial`` is the config's initial node, ``columns`` maps initial keys
       to arrays (one value per point); it returns the states (points × state
       size) and a boolean array of valid rows. None (the default): the batch
       builds one system per distinct point.
    9. Optionally, ``reference_frame(y)`` returns the body components of the
       reference axes at state ``y`` as a (3, 3) array (rows α, β, γ), or
       None when the state does not carry them (the default); the scene checks
       a third-party force's claims at that frame (``gyrolab.contracts.claims``).
    10. ``_batch_units`` is a cache the batch owns (the units of the system's
        variables, ``gyrolab.batch.outputs``); implementers leave it alone.
    """

    name: ClassVar[str]
    body_type: ClassVar[type]
    #: rule 6: why ``compiled_model()`` returned None, or None
    compile_error: str | None = None
    #: rule 7: ``invariant_values(y) -> {name: values}``, or None when the system has no vectorised form
    invariant_values: Callable[[np.ndarray], dict[str, np.ndarray]] | None = None
    #: rule 8: ``initial_states(initial, columns) -> (states, valid)``, or None when the system has no batch form
    initial_states: Callable[..., tuple[np.ndarray, np.ndarray]] | None = None
    #: rule 10: the batch's cache of the variables' units
    _batch_units: dict[str, str] | None = None
    default_body: ClassVar[dict[str, Any] | None] = None  # a third-party system's body section (rule 1)

    def __init__(self, body: Any, forces: Sequence[Force], initial: Any, output: Any) -> None:
        self.body = body
        self.forces = list(forces)

    @property
    @abstractmethod
    def state_size(self) -> int:
        """Length of the state vector."""

    @abstractmethod
    def initial_state(self) -> np.ndarray:
        """y0."""

    @abstractmethod
    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        """dy/dt for one state."""

    @property
    @abstractmethod
    def invariants(self) -> tuple[str, ...]:
        """Names of the first integrals this scene conserves (dataset variable names)."""

    @abstractmethod
    def variables(self, t: np.ndarray, y: np.ndarray) -> dict[str, xr.Variable]:
        """Dataset variables of a trajectory."""

    def attributes(self) -> dict[str, Any]:
        return {}

    def compiled_model(self) -> CompiledModel | None:
        """Rule 6: the system compiled from its traced ``rhs``, or None (then only Python integrators run it)."""
        try:
            return model.compiled_system(self)
        except model.NotCompilable as exc:
            self.compile_error = str(exc)
            return None

    def reference_frame(self, y: np.ndarray) -> np.ndarray | None:
        """Rule 9: rows α, β, γ (body components of the reference axes) at state ``y``, or None."""
        return None

    def title(self) -> str:
        return self.name
