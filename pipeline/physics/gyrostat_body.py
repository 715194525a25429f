"""The body of an orbiting satellite-gyrostat: principal inertia, rotor momentum, orbit rate.

Config section ``body`` (``conf/body/gyrostat_*.yaml``):

* ``inertia = [A, B, C]``: principal moments of inertia (kg m² for ``units: si``,
  any consistent unit for ``units: nondimensional`` — the papers' form);
* ``gyrostatic_momentum = [k1, k2, k3]``: constant angular momentum of the rotors
  in body axes (kg m² s⁻¹, or inertia × rate units);
* ``orbit_rate`` Ω > 0: mean motion of the circular orbit (rad/s, or the model's
  rate unit; with Ω = 1 time is measured in units of 1/Ω and one orbit lasts 2π);
* ``allow_nonphysical``: admit inertia violating A + B ≥ C (and cyclic).

The orbit fixes the gravity-gradient coefficient N = 3Ω² (Ω² = GM/R³) and the
direction of the attracting centre: reference axis 0 (α, the radial axis of
the orbital frame) — the ``newtonian`` force reads both from the body.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.physics.body import UNITS, ModelUnits, _check_inertia, _netcdf_safe, _satisfies_triangle
from gyrolab.errors import ConfigError, as_number, as_vector3, choices

KEYS = ("units", "inertia", "gyrostatic_momentum", "orbit_rate", "allow_nonphysical")


@dataclass(frozen=True)
class GyrostatBody(ModelUnits):
    """A satellite-gyrostat on a circular orbit, in model units (see module docstring)."""

    units: str
    inertia: np.ndarray  # (A, B, C)
    gyrostatic_momentum: np.ndarray  # k, body axes
    orbit_rate: float  # Ω > 0
    nonphysical: bool
    source: dict[str, Any]

    #: reference axis pointing from the attracting centre to the body (α, radial)
    attracting_axis = 0

    @property
    def gravity_gradient(self) -> float:
        """N = 3Ω²: the gravity-gradient torque is N α × Iα."""
        return 3.0 * self.orbit_rate**2

    @property
    def weight_moment(self) -> np.ndarray:
        """Zero: a uniform field acts at the centre of mass, the reference point, so ``uniform_gravity``
        adds no torque; the orbit's gravity acts through its gradient (``newtonian``)."""
        return np.zeros(3)

    g = None  # no uniform gravity

    # units: gyrolab.physics.body.ModelUnits, with the orbit's rate as the nondimensional unit
    @property
    def time_label(self) -> str:
        return "s" if self.units == "si" else "1/Ω" if self.orbit_rate == 1.0 else "model time"

    @property
    def rate_label(self) -> str:
        return "rad/s" if self.units == "si" else "Ω" if self.orbit_rate == 1.0 else "model rate"

    @classmethod
    def from_config(cls, cfg: Any) -> GyrostatBody:
        """Validate a ``body`` section; one-sentence ConfigError naming the bad value otherwise."""
        cfg = {k: v for k, v in dict(cfg).items() if v is not None}
        unknown = sorted(set(cfg) - set(KEYS))
        if unknown:
            raise ConfigError(f"body.{unknown[0]} is not a parameter of the orbiting gyrostat's body; valid "
                              f"parameters: {choices(KEYS)} (use a gyrostat body: body=gyrostat_symmetric, "
                              "gyrostat_asymmetric)")
        units = cfg.get("units", "nondimensional")
        if units not in UNITS:
            raise ConfigError(f"body.units={units!r} is not valid; valid choices: {choices(UNITS)}")
        for key in ("inertia", "orbit_rate"):
            if key not in cfg:
                raise ConfigError(f"body.{key} is missing; the orbiting gyrostat needs inertia [A, B, C] and "
                                  "orbit_rate Ω > 0")
        inertia = np.array(as_vector3(cfg["inertia"], "body.inertia"))
        k = np.array(as_vector3(cfg.get("gyrostatic_momentum", (0.0, 0.0, 0.0)), "body.gyrostatic_momentum"))
        rate = as_number(cfg["orbit_rate"], "body.orbit_rate")
        if rate <= 0:
            raise ConfigError(f"body.orbit_rate={rate:g} must be positive (the mean motion Ω of the circular orbit; "
                              "reverse the orbit by turning the body instead)")
        allow = cfg.get("allow_nonphysical", False)
        if not isinstance(allow, bool):
            raise ConfigError(f"body.allow_nonphysical={allow!r} must be true or false")
        _check_inertia(inertia, allow)
        return cls(units, inertia, k, rate, not _satisfies_triangle(inertia), cfg)

    def nondimensional(self) -> dict[str, Any]:
        A, B, C = self.inertia
        return {"a": A / C, "b": B / C, "orbit_rate": self.orbit_rate}

    def attributes(self) -> dict[str, Any]:
        attrs: dict[str, Any] = {"body_units": self.units, "body_nonphysical": int(self.nonphysical),
                                 "body_inertia": self.inertia.copy(),
                                 "body_gyrostatic_momentum": self.gyrostatic_momentum.copy(),
                                 "body_orbit_rate": self.orbit_rate,
                                 "body_gravity_gradient_N": self.gravity_gradient}
        for key, value in self.source.items():
            attrs.setdefault(f"body_{key}", _netcdf_safe(value))
        return attrs
