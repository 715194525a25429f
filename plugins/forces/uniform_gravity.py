"""Uniform gravity on a heavy body: torque M g r_c × γ (Ismail (2021) eq. 1, Shaker et al. eq. 1).

γ is the unit vector of the fixed vertical Z, which in the papers points along the weight (towards the attracting
centre); the potential is V = −M g r_c · γ. The weight moment M g r_c comes from the body (SI), or is the unit direction
r_c' with c² = 1 (nondimensional form).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gyrolab.physics.body import Body
from gyrolab.contracts.force import Axes, CompiledTerms, Force
from gyrolab.physics.vectors import cross, dot


class UniformGravity(Force):
    name = "uniform_gravity"
    required_axes = frozenset({2})
    preserves_area_integral = True

    def __init__(self, body: Body) -> None:
        self.weight_moment = body.weight_moment

    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        return cross(self.weight_moment, axes[2])

    def potential(self, axes: Axes) -> np.ndarray:
        return -dot(axes[2], self.weight_moment)

    def attributes(self) -> dict[str, Any]:
        return {"weight_moment": self.weight_moment.tolist()}

    def compiled_terms(self) -> CompiledTerms:
        return CompiledTerms(linear={2: self.weight_moment})
