"""The settings every tolerance-controlled method shares: rtol, atol, max_step."""

from __future__ import annotations

from typing import Any

import numpy as np

from gyrolab.errors import as_number


class Tolerances:
    """Mixin of adaptive integrator plugins: validated rtol, atol, max_step, and their dataset attributes."""

    def __init__(self, *, rtol: float = 1e-10, atol: float = 1e-10, max_step: float | None = None) -> None:
        self.rtol = as_number(rtol, "integrator.rtol", positive=True)
        self.atol = as_number(atol, "integrator.atol", positive=True)
        self.max_step = np.inf if max_step is None else as_number(max_step, "integrator.max_step", positive=True)

    def attributes(self) -> dict[str, Any]:
        attrs: dict[str, Any] = {"integrator_rtol": self.rtol, "integrator_atol": self.atol}
        if np.isfinite(self.max_step):
            attrs["integrator_max_step"] = self.max_step
        return attrs
