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
from pipeline.contracts.force import Axes, Force
from pipeline.errors import ConfigError, as_number
from pipeline.vectors import cross, dot


class Newtonian(Force):
    name = "newtonian"
    required_axes = frozenset({2})
    preserves_area_integral = True

    def __init__(self, body: Body, *, R: float | None = None, k: float | None = None) -> None:
        if body.units == "si":
            if k is not None or R is None:
                raise ConfigError(
                    f"force.newtonian needs the distance R (m) of the attracting centre for an SI body, got R={R}, k={k}"
                )
            R = as_number(R, "force.newtonian.R", positive=True)
            if not body.g:
                raise ConfigError("force.newtonian needs body.g > 0 to set N = 3g/R")
            self.N = 3.0 * body.g / R
        else:
            if R is not None or k is None:
                raise ConfigError(
                    f"force.newtonian needs k = N/c² for a nondimensional body, got k={k}, R={R}"
                )
            self.N = as_number(k, "force.newtonian.k", nonnegative=True)
        self.inertia = body.inertia
        self._nondim = body.nondimensional()

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
