"""The settings every tolerance-controlled method shares: rtol, atol, max_step."""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from gyrolab.errors import as_number

log = logging.getLogger(__name__)


class Tolerances:
    """Mixin of adaptive integrator plugins: validated rtol, atol, max_step, and their dataset attributes."""

    def __init__(self, *, rtol: float = 1e-10, atol: float = 1e-10, max_step: float | None = None) -> None:
        self.rtol = as_number(rtol, "integrator.rtol", positive=True)
        self.atol = as_number(atol, "integrator.atol", positive=True)
        self.max_step = np.inf if max_step is None else as_number(max_step, "integrator.max_step", positive=True)
        #: the tolerances the method really ran with (a solver may raise a request to its floor)
        self.used_rtol, self.used_atol = self.rtol, self.atol

    def record_used_tolerances(self, rtol: float, atol: float) -> None:
        """The tolerances the solver really applies; a request it raised is logged once and stored as such."""
        if (rtol, atol) != (self.rtol, self.atol) and (rtol, atol) != (self.used_rtol, self.used_atol):
            log.warning("%s runs at rtol=%.3g, atol=%.3g, not the requested rtol=%.3g, atol=%.3g: the solver's "
                        "floor (about 100 machine epsilons); run.nc stores the tolerances used",
                        getattr(self, "name", type(self).__name__), rtol, atol, self.rtol, self.atol)
        self.used_rtol, self.used_atol = rtol, atol

    #: the smallest rtol the method honours (scipy raises a smaller one to 100 machine epsilons)
    tolerance_floor: float = 100 * float(np.finfo(float).eps)

    def more_accurate(self, factor: float):
        """The same method at tolerances ``factor`` times smaller (rule 9), or None below its floor."""
        rtol, atol = self.rtol / factor, self.atol / factor
        if rtol < self.tolerance_floor:
            return None
        kwargs = {"rtol": rtol, "atol": atol, **({"max_step": self.max_step} if np.isfinite(self.max_step) else {})}
        return type(self)(**kwargs), 1.0, f"{self.name} at rtol {rtol:.3g}, atol {atol:.3g} ({factor:g}× tighter)"

    def attributes(self) -> dict[str, Any]:
        attrs: dict[str, Any] = {"integrator_rtol": self.used_rtol, "integrator_atol": self.used_atol}
        if (self.used_rtol, self.used_atol) != (self.rtol, self.atol):
            attrs.update(integrator_rtol_requested=self.rtol, integrator_atol_requested=self.atol)
        if np.isfinite(self.max_step):
            attrs["integrator_max_step"] = self.max_step
        return attrs
