"""The body section of a rotor body: principal inertia and the rotor's constant momentum, in SI units."""

from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.errors import ConfigError, as_vector3, choices
from gyrolab.physics.body import ModelUnits

#: the plugin's default ``body`` section; gyrolab registers it as the option body=rotor_body (which selects the system)
DEFAULT_BODY = {"units": "si", "inertia": [2.0, 1.5, 1.0], "rotor_momentum": [0.0, 0.0, 0.5]}
KEYS = tuple(DEFAULT_BODY)


@dataclass(frozen=True)
class RotorBody(ModelUnits):
    units: str
    inertia: np.ndarray           # (A, B, C), kg m², principal axes
    rotor_momentum: np.ndarray    # h, kg m² s⁻¹: the rotor's momentum relative to the body, constant in body axes

    time_label = "s"
    rate_label = "rad/s"

    @property
    def gyrostatic_momentum(self) -> np.ndarray:
        """h under the name gyrolab's sampling estimate (``time.n_output: auto``) reads for a rotor's rate."""
        return self.rotor_momentum

    @classmethod
    def from_config(cls, cfg: Any) -> "RotorBody":
        cfg = {k: v for k, v in dict(cfg).items() if v is not None}
        unknown = sorted(set(cfg) - set(KEYS))
        if unknown:
            raise ConfigError(f"body.{unknown[0]} is not a parameter of the rotor body; valid parameters: "
                              f"{choices(KEYS)} (select the body with body=rotor_body)")
        units = cfg.get("units", "si")
        if units != "si":
            raise ConfigError(f"body.units={units!r} is not valid for the rotor body; valid choices: si")
        inertia = np.array(as_vector3(cfg.get("inertia", DEFAULT_BODY["inertia"]), "body.inertia"))
        if np.any(inertia <= 0):
            raise ConfigError(f"body.inertia={inertia.tolist()} must have three positive principal moments")
        h = np.array(as_vector3(cfg.get("rotor_momentum", DEFAULT_BODY["rotor_momentum"]), "body.rotor_momentum"))
        return cls(units, inertia, h)

    def attributes(self) -> dict[str, Any]:
        return {"body_units": self.units, "body_inertia": self.inertia.copy(),
                "body_rotor_momentum": self.rotor_momentum.copy()}
