"""A free rigid body carrying a rotor of constant momentum: a torque-free gyrostat (a gyrolab system plugin).

In principal body axes, with h the rotor's momentum relative to the body (constant in body axes),
the body's total angular momentum is L = Iω + h and, with no external torque, L is fixed in space:

    I ω̇ = (Iω + h) × ω,        γ̇ = γ × ω,

γ being the body components of a direction fixed in space (the Z axis). State y = (ω, γ).
First integrals: the body's kinetic energy ½ ω·Iω (the rotor's relative spin energy is constant, left out)
and |L|², L = Iω + h being fixed in space.
"""

from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts import System
from gyrolab.errors import ConfigError
from gyrolab.physics.attitude import nutation_and_spin
from gyrolab.physics.initial import InitialAttitude

from gyrolab_rotor_body.body import DEFAULT_BODY, RotorBody


class RotorBodySystem(System):
    name = "rotor_body"
    body_type = RotorBody
    default_body = DEFAULT_BODY           # gyrolab registers it as body=rotor_body, which selects this system

    def __init__(self, body, forces, initial, output):
        super().__init__(body, forces, initial, output)
        if self.forces:                   # no torque term: a force would be silently ignored, so refuse it
            raise ConfigError(f"system rotor_body is torque-free and takes no force, got force="
                              f"[{','.join(f.name for f in self.forces)}]; valid choice: force=[]")
        self.initial = InitialAttitude.from_config(initial)   # ω0 and γ0 (θ0, φ0 or gamma0), validated as gyrolab does
        self.inertia, self.h = body.inertia, body.rotor_momentum

    @property
    def state_size(self):
        return 6

    def initial_state(self):
        return np.concatenate([self.initial.omega, self.initial.gamma])

    def rhs(self, t, y):
        omega, gamma = y[0:3], y[3:6]
        return np.concatenate([np.cross(self.inertia * omega + self.h, omega) / self.inertia,
                               np.cross(gamma, omega)])

    @property
    def invariants(self):
        return ("kinetic_energy", "momentum_squared", "gamma_norm")

    def variables(self, t, y):
        omega, gamma = y[:, 0:3], y[:, 3:6]
        momentum = self.inertia * omega + self.h
        theta, phi = nutation_and_spin(gamma)
        return {
            "omega": _var(("time", "axis"), omega, "rad s-1", "angular velocity (p, q, r) of the body in body axes"),
            "gamma": _var(("time", "axis"), gamma, "1", "direction cosines of the fixed Z axis in body axes"),
            "kinetic_energy": _var("time", 0.5 * np.sum(omega * self.inertia * omega, axis=1), "J",
                                   "kinetic energy of the body's rotation ½ω·Iω"),
            "momentum_squared": _var("time", np.sum(momentum * momentum, axis=1), "kg2 m4 s-2",
                                     "squared total angular momentum |Iω + h|²"),
            "gamma_norm": _var("time", np.linalg.norm(gamma, axis=1), "1", "norm of the direction cosines |γ|"),
            # the angles γ alone fixes (ψ needs a second fixed axis, which this state does not carry)
            "theta": _var("time", theta, "rad", "nutation angle θ: body z axis from the fixed Z axis"),
            "phi": _var("time", np.unwrap(phi), "rad", "proper-rotation angle φ (unwrapped)"),
        }

    def attributes(self):
        return {"system": self.name, "state_size": self.state_size, **self.body.attributes(),
                "initial_omega": self.initial.omega.copy(), "initial_gamma": self.initial.gamma.copy()}

    def title(self):
        A, B, C = self.inertia
        return (f"free body with a rotor, A,B,C=({A:.4g}, {B:.4g}, {C:.4g}) kg m², "
                f"h=({', '.join(f'{x:.3g}' for x in self.h)}) kg m²/s")


def _var(dims: Any, data: np.ndarray, units: str, long_name: str) -> xr.Variable:
    return xr.Variable(dims, np.asarray(data, dtype=float), attrs={"units": units, "long_name": long_name})
