"""Newtonian attracting centre on the fixed Z axis: torque N γ × Iγ with N = 3g/R.

The papers' Newtonian field (seed 000 eq. 1, seed 001 eq. 7): a centre at
distance R from the fixed point along Z adds, to first order in ℓ/R, the
gravity-gradient torque N γ × Iγ with potential V = ½ N γ·Iγ. Give ``R`` (m)
for an SI body, which uses its g, or ``k = N/c²`` for a nondimensional body.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pipeline.body import Body
from pipeline.contracts.force import Axes, CompiledTerms, Force
from pipeline.errors import ConfigError, as_number
from pipeline.vectors import cross, dot


class Newtonian(Force):
    name = "newtonian"
    required_axes = frozenset({2})
    preserves_area_integral = True

    def __init__(self, body: Body, *, k: float | None = None, R: float | None = None) -> None:
        if (k is None) == (R is None):
            raise ConfigError(f"force.newtonian needs exactly one of k = N/c² or R (m), got k={k}, R={R}")
        self._nondim = body.nondimensional()
        c2 = self._nondim.get("c2", 1.0)  # model units of a nondimensional body have c² = 1
        if k is not None:
            k = as_number(k, "force.newtonian.k", nonnegative=True)
            if body.units == "si" and not c2 > 0:
                raise ConfigError("force.newtonian.k = N/c² needs c² = Mgl/C > 0; give R (m) for a body without weight")
            self.N = k * c2
        else:
            R = as_number(R, "force.newtonian.R", positive=True)
            if body.units != "si" or not body.g:
                raise ConfigError(f"force.newtonian.R={R:g} needs an SI body with g > 0 (N = 3g/R); "
                                  "a nondimensional body takes k = N/c²")
            self.N = 3.0 * body.g / R
        self.inertia = body.inertia

    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        gamma = axes[2]
        return self.N * cross(gamma, self.inertia * gamma)

    def potential(self, axes: Axes) -> np.ndarray:
        gamma = axes[2]
        return 0.5 * self.N * dot(gamma, self.inertia * gamma)

    def attributes(self) -> dict[str, Any]:
        attrs: dict[str, Any] = {"N": self.N}
        c2 = self._nondim.get("c2")
        if c2:
            attrs["k"] = self.N / c2
        return attrs

    def compiled_terms(self) -> CompiledTerms:
        return CompiledTerms(gradient={2: self.N})
