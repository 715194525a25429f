"""Contract of an expansion-regime plugin: an analytic periodic solution valid in a stated domain."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from gyrolab.contracts.system import System
from gyrolab.errors import ConfigError, choices

FORMULAS = ("corrected", "printed")


class Regime(ABC):
    """An asymptotic expansion of a system's motion (a paper's analytic periodic solution).

    Rules for implementers (``gyrolab.testing.check_regime`` checks them; run it in your tests):

    1. ``__init__(self, *, formula="corrected", param=default, ...)`` takes
       the plugin's config, each parameter a keyword with a default
       (``**params`` is refused); ``formula`` selects the corrected formulas or
       the paper's printed ones (``FORMULAS``); bad values raise ``ConfigError``.
    2. ``systems`` lists the system names the expansion is derived for; a
       scene pairing it with another system is refused before integrating.
    3. ``parameter``/``parameter_long_name`` name the expansion's small or
       large parameter; ``parameter_value(system)`` computes it from the scene,
       and ``order`` gives the theory's error order in it, per variable.
    4. ``check_domain(system)`` returns a list of one-sentence warnings
       (recorded in the dataset) or raises ``ConfigError`` (one sentence,
       naming the bad value and what is valid) when the scene is outside the
       domain the expansion assumes (parameter range, resonances, physical
       admissibility, forces).
    5. The expansion describes one periodic orbit through the scene's spin r0
       and nutation θ0 (other initial values are the orbit's own):
       ``initial_state(system)`` is its state (ω, γ) at t = 0 (shape (6,)),
       ``period(system)`` its period and ``solution(system, t)`` its state at
       times t (shape (n, 6)), all in the scene's model units.
    6. ``euler_angles(system, t)`` returns ``{"psi", "theta", "phi"}`` of the
       analytic solution (ψ(0) = scene's ψ0).
    7. ``attributes()`` describes the regime for the dataset (netCDF-safe values).
    8. A regime run (``gyrolab regime=NAME``) also reads ``periods``,
       ``samples_per_period`` and ``full_initial_state(system)``: a fixed-point
       regime subclasses ``gyrolab.plugins.regimes.base.FixedPointRegime``, which
       provides them (docs/plugins.md, "Regime plugins").
    9. Optionally, ``diagnostics(system)`` returns extra evidence for a
       regime run's dataset as (data variables, coordinates, attributes)
       (``gyrolab.experiments.regime_run``); the default has none.
    10. Optionally, ``series_candidates(system, accuracy)`` lists variants of
        the regime (lowest series order first) with their predicted max error
        (NaN: not predicted), for ``integrator=auto``; the default is the
        regime itself, unpredicted.
    11. Optionally, ``period_spread`` (a class attribute ≥ 1) bounds the
        scene's true period to [T/spread, T·spread] around ``period(system)``;
        ``integrator=auto`` then rules the regime out cheaply when the scene's
        motion never comes back near its start over that range. None (the
        default): no such screen.
    """

    name: ClassVar[str]
    systems: ClassVar[tuple[str, ...]] = ("fixed_point",)
    parameter: ClassVar[str]
    parameter_long_name: ClassVar[str]
    #: the theory's error order of each variable in the parameter (error ∝ parameter**order)
    order: ClassVar[dict[str, float]] = {}
    #: rule 11: bound of the true period around ``period(system)``, or None (no screen)
    period_spread: ClassVar[float | None] = None

    def __init__(self, *, formula: str = "corrected") -> None:
        if formula not in FORMULAS:
            raise ConfigError(f"regime.formula={formula!r} is not valid; valid choices: {choices(FORMULAS)}")
        self.formula = formula

    @abstractmethod
    def parameter_value(self, system: System) -> float:
        """The expansion parameter of the scene."""

    @abstractmethod
    def check_domain(self, system: System) -> list[str]:
        """Warnings for a scene inside but near the edge of the domain; ConfigError outside it."""

    @abstractmethod
    def initial_state(self, system: System) -> np.ndarray:
        """(ω, γ) of the analytic periodic orbit at t = 0."""

    @abstractmethod
    def period(self, system: System) -> float:
        """Period of the body-frame motion of the analytic orbit (model time units)."""

    @abstractmethod
    def solution(self, system: System, t: np.ndarray) -> np.ndarray:
        """The analytic approximation of (ω, γ) at times t, shape (n, 6)."""

    @abstractmethod
    def euler_angles(self, system: System, t: np.ndarray) -> dict[str, np.ndarray]:
        """ψ, θ, φ of the analytic solution at times t."""

    def diagnostics(self, system: System) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
        """Rule 9: (data variables, coordinates, attributes) of extra evidence; none by default."""
        return {}, {}, {}

    def series_candidates(self, system: System, accuracy: float) -> list[tuple[Regime, float]]:
        """Rule 10: variants predicted to meet ``accuracy`` with their predicted max error; itself, unpredicted."""
        return [(self, float("nan"))]

    def attributes(self) -> dict[str, Any]:
        return {"regime": self.name, "regime_formula": self.formula, "regime_parameter": self.parameter}
