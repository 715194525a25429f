"""Contract of an expansion-regime plugin: an analytic approximation valid in a stated domain."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from pipeline.contracts.system import System


class Regime(ABC):
    """An asymptotic expansion of a system's motion (a paper's analytic periodic solution).

    Rules for implementers:

    1. ``systems`` lists the system names the expansion is derived for; a
       scene pairing it with another system is refused before integrating.
    2. ``check_domain(system)`` returns a list of one-sentence warnings
       (recorded in the dataset) or raises ``ConfigError`` when the scene is
       outside the domain the expansion assumes.
    3. ``solution(system, t)`` returns the analytic approximation of the
       system's state at times ``t`` (shape (n, state size)), in model units.
    """

    name: ClassVar[str]
    systems: ClassVar[tuple[str, ...]]

    @abstractmethod
    def check_domain(self, system: System) -> list[str]:
        """Warnings for a scene inside but near the edge of the domain; ConfigError outside it."""

    @abstractmethod
    def solution(self, system: System, t: np.ndarray) -> np.ndarray:
        """The analytic approximation of the state at times t."""

    def attributes(self) -> dict[str, Any]:
        return {}
