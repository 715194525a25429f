"""Magnetic dipole of the body in a uniform field: torque m × B, potential −m·B.

``moment`` is the body's dipole m in body axes, ``field`` the strength B and ``direction`` the field's unit direction
in the system's reference frame (``fixed_point``: X, Y, Z with Z the vertical; ``orbiting_gyrostat``: the orbital
frame). SI: A m² and T; nondimensional: m·B in units of C c². A non-vertical field makes the system carry the full
attitude (and only then).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from gyrolab.physics.body import Body
from gyrolab.contracts.force import Axes, CompiledTerms, Force
from gyrolab.errors import ConfigError, as_number, as_vector3
from gyrolab.physics.vectors import cross, dot

UNIT_TOLERANCE = 1e-9


class Magnetic(Force):
    name = "magnetic"

    def __init__(self, body: Body, *, moment: Sequence[float] = (0.0, 0.0, 1.0), field: float = 0.0,
                 direction: Sequence[float] = (0.0, 0.0, 1.0)) -> None:
        self.moment = np.array(as_vector3(moment, "force.magnetic.moment"))
        self.field = as_number(field, "force.magnetic.field")
        self.direction = np.array(as_vector3(direction, "force.magnetic.direction"))
        length = float(np.linalg.norm(self.direction))
        if abs(length - 1.0) > UNIT_TOLERANCE:
            raise ConfigError(f"force.magnetic.direction={self.direction.tolist()} has norm {length:.12g}; it must be "
                              "a unit vector")
        self.required_axes = frozenset(i for i in range(3) if self.direction[i] != 0.0)
        self.preserves_area_integral = self.required_axes <= {2}

    def _field_in_body(self, axes: Axes) -> np.ndarray:
        return sum(((self.field * self.direction[i]) * axes[i] for i in self.required_axes), 0.0)

    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        return cross(self.moment, self._field_in_body(axes))

    def potential(self, axes: Axes) -> np.ndarray:
        return -dot(self._field_in_body(axes), self.moment)

    def attributes(self) -> dict[str, Any]:
        return {"moment": self.moment.tolist(), "field": self.field, "direction": self.direction.tolist()}

    def compiled_terms(self) -> CompiledTerms:
        return CompiledTerms(linear={i: self.field * self.direction[i] * self.moment for i in self.required_axes})
