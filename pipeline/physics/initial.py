"""Initial state of a fixed-point scene: ω0 = (p0, q0, r0) and the attitude.

The attitude is given either by the Euler angles (θ0, φ0) of the vertical,
γ0 = (sin θ0 sin φ0, sin θ0 cos φ0, cos θ0), or by ``gamma0`` directly (then
|γ0| must be 1 within 1e-9: it is never normalised silently). ψ0 fixes the
rotation about the vertical; it matters only when the scene carries the
horizontal axes (Euler-angle output, a non-vertical field).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from gyrolab.physics.attitude import frame_from_angles, nutation_and_spin
from gyrolab.errors import ConfigError, as_number, as_vector3

UNIT_TOLERANCE = 1e-9


@dataclass(frozen=True)
class InitialAttitude:
    omega: np.ndarray  # (p0, q0, r0), model units
    alpha: np.ndarray  # body components of the fixed X axis
    gamma: np.ndarray  # body components of the fixed vertical Z

    @classmethod
    def from_config(cls, cfg: Any) -> InitialAttitude:
        cfg = dict(cfg)
        omega = np.array([as_number(cfg.get(k), f"initial.{k}") for k in ("p0", "q0", "r0")])
        psi0 = as_number(cfg.get("psi0", 0.0), "initial.psi0")
        if cfg.get("gamma0") is not None:
            if cfg.get("theta0") is not None or cfg.get("phi0") is not None:
                raise ConfigError(
                    "initial.gamma0 and initial.theta0/phi0 both give the attitude; set one form and null the other"
                )
            gamma = np.array(as_vector3(cfg["gamma0"], "initial.gamma0"))
            length = float(np.linalg.norm(gamma))
            if abs(length - 1.0) > UNIT_TOLERANCE:
                raise ConfigError(
                    f"initial.gamma0={gamma.tolist()} has norm {length:.15g}, but the direction cosines of the "
                    f"vertical must satisfy |γ0| = 1 within {UNIT_TOLERANCE:g}"
                )
            theta0, phi0 = (float(x) for x in nutation_and_spin(gamma))
        else:
            if cfg.get("theta0") is None or cfg.get("phi0") is None:
                raise ConfigError("initial.theta0 and initial.phi0 (rad) are needed when initial.gamma0 is not given")
            theta0 = as_number(cfg["theta0"], "initial.theta0")
            phi0 = as_number(cfg["phi0"], "initial.phi0")
            gamma = None
        alpha, _, gamma_from_angles = frame_from_angles(psi0, theta0, phi0)
        # Keep a user-given γ0 bit for bit; α from the angles is orthogonal to it to rounding.
        return cls(omega=omega, alpha=alpha, gamma=gamma if gamma is not None else gamma_from_angles)
