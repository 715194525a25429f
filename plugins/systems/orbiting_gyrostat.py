"""Satellite-gyrostat on a circular orbit: gravity-gradient and magnetic torques (Yehia & El-kenani (2021)).

In body axes (principal, I = diag(A, B, C); k the rotors' constant momentum), with ω the absolute angular velocity,
ω′ = ω − Ωγ the one relative to the orbital frame (axis 0 = α radial, 1 = β along-track, 2 = γ orbit normal):

    I ω̇ = (I ω + k) × ω + Σ torques,     α̇ = α × ω′,     γ̇ = γ × ω′  (= γ × ω),

state y = (ω, α, γ); β = γ × α is computed when a force needs it. The torques are the ``newtonian`` plugin about
axis 0 and the ``magnetic`` plugin with its direction in the orbital frame; the model, the paper's sign conventions
and the Jacobi integral: docs/gyrostat.md.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from gyrolab.physics.attitude import euler_angles
from gyrolab.contracts.force import Force
from gyrolab.contracts.system import System
from gyrolab.errors import ConfigError, as_vector3
from gyrolab.physics.initial import InitialAttitude
from gyrolab.physics.vectors import cross, dot, norm
from gyrolab.physics.gyrostat_body import GyrostatBody
from gyrolab.physics.gyrostat_euler import GyrostatParameters, kinematic_matrix
from gyrolab.plugins.systems.fixed_point import system_attributes, variable

INITIAL_KEYS = ("p0", "q0", "r0", "psi0", "theta0", "phi0", "gamma0", "euler_rates0")


FIXED_POINT_FORCES = ("uniform_gravity",)  # a weight needs a fixed point to have a moment about


class OrbitingGyrostat(System):
    name = "orbiting_gyrostat"
    body_type = GyrostatBody

    def __init__(self, body: GyrostatBody, forces: Sequence[Force], initial: Any, output: Any) -> None:
        super().__init__(body, forces, initial, output)
        if not isinstance(body, GyrostatBody):
            raise ConfigError("system orbiting_gyrostat needs a gyrostat body (body=gyrostat_symmetric, "
                              "gyrostat_asymmetric)")
        foreign = [f.name for f in self.forces if f.name in FIXED_POINT_FORCES]
        if foreign:
            raise ConfigError(f"force {foreign[0]} acts on a body about a fixed point, not on a satellite on a "
                              "circular orbit; valid choices here: newtonian (gravity gradient), magnetic")
        self.inertia, self.k, self.Omega = body.inertia, body.gyrostatic_momentum, body.orbit_rate
        self.needs_beta = any(1 in f.required_axes for f in self.forces)
        self.angles, self.omega0, self.alpha0, self.gamma0 = _initial(dict(initial), self.Omega)

    @property
    def state_size(self) -> int:
        return 9

    def initial_state(self) -> np.ndarray:
        return np.concatenate([self.omega0, self.alpha0, self.gamma0])

    def axes(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        alpha, gamma = y[..., 3:6], y[..., 6:9]
        return alpha, (cross(gamma, alpha) if self.needs_beta else None), gamma

    def reference_frame(self, y: np.ndarray) -> np.ndarray:
        """Rows α (radial), β (along-track), γ (orbit normal) at state ``y``."""
        alpha, gamma = np.asarray(y[3:6], dtype=float), np.asarray(y[6:9], dtype=float)
        return np.array([alpha, np.cross(gamma, alpha), gamma])

    def derivative(self, y: np.ndarray) -> np.ndarray:
        """dy/dt for one state (9,) or a stack (n, 9); real or complex (complex-step Jacobians)."""
        omega = y[..., 0:3]
        axes = self.axes(y)
        torque = cross(self.inertia * omega + self.k, omega)
        for force in self.forces:
            torque = torque + force.torque(omega, axes)
        relative = omega - self.Omega * axes[2]
        return np.concatenate([torque / self.inertia, cross(axes[0], relative), cross(axes[2], relative)], axis=-1)

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        return self.derivative(y)

    @property
    def invariants(self) -> tuple[str, ...]:
        conservative = all(f.conservative for f in self.forces)
        return ("jacobi_integral", "frame_error") if conservative else ("frame_error",)

    def potential(self, y: np.ndarray) -> np.ndarray:
        alpha, gamma = y[..., 3:6], y[..., 6:9]
        axes = (alpha, cross(gamma, alpha), gamma)
        total = np.zeros(y.shape[:-1])
        for force in self.forces:
            total = total + force.potential(axes)
        return total

    def jacobi_integral(self, y: np.ndarray) -> np.ndarray:
        omega, gamma = y[..., 0:3], y[..., 6:9]
        return (0.5 * dot(omega, self.inertia * omega) - self.Omega * dot(gamma, self.inertia * omega + self.k)
                + self.potential(y))

    def parameters(self) -> GyrostatParameters:
        """(A, B, C, k, μ, h, Ω, N) of the paper's model; ConfigError for forces outside it."""
        N, mu, h = 0.0, np.zeros(3), np.zeros(3)
        magnets = 0
        for force in self.forces:
            if force.name == "newtonian" and getattr(force, "axis", 2) == 0:
                N += force.N
            elif force.name == "magnetic":
                magnets += 1
                mu, h = force.moment.copy(), -force.field * force.direction
            else:
                raise ConfigError(f"force {force.name!r} is outside the paper's model (newtonian about the radial "
                                  "axis, one magnetic dipole); the Euler-angle form cannot include it")
        if magnets > 1:
            raise ConfigError("the paper's model has one magnetic dipole; give one magnetic force")
        return GyrostatParameters(tuple(self.inertia), tuple(self.k), tuple(mu), tuple(h), self.Omega, N)

    def variables(self, t: np.ndarray, y: np.ndarray) -> dict[str, xr.Variable]:
        body = self.body
        omega, alpha, gamma = y[:, 0:3], y[:, 3:6], y[:, 6:9]
        beta = cross(gamma, alpha)
        rate = f"[{body.rate_label}]"
        out: dict[str, xr.Variable] = {
            "omega": variable(("time", "axis"), omega, body.rate_unit,
                              f"absolute angular velocity (p, q, r) in body axes {rate}"),
            "omega_relative": variable(("time", "axis"), omega - self.Omega * gamma, body.rate_unit,
                                       f"angular velocity relative to the orbital frame ω′ = ω − Ωγ in body axes "
                                       f"{rate}"),
            "alpha": variable(("time", "axis"), alpha, "1", "direction cosines of the radial axis α in body axes"),
            "beta": variable(("time", "axis"), beta, "1", "direction cosines of the along-track axis β in body axes"),
            "gamma": variable(("time", "axis"), gamma, "1", "direction cosines of the orbit normal γ in body axes"),
        }
        if "jacobi_integral" in self.invariants:
            out["jacobi_integral"] = variable("time", self.jacobi_integral(y), body.energy_unit,
                                              "Jacobi integral ½ω·Iω − Ωγ·(Iω + k) + V")
        frame_error = np.maximum.reduce([np.abs(norm(alpha) - 1), np.abs(norm(gamma) - 1), np.abs(dot(alpha, gamma))])
        out["frame_error"] = variable("time", frame_error, "1",
                                      "orthonormality error of (α, γ): max(| |α| − 1 |, | |γ| − 1 |, |α·γ|)")
        psi, theta, phi = euler_angles(alpha, gamma)
        out["psi"] = variable("time", psi, "rad", "precession angle ψ relative to the orbital frame (unwrapped)")
        out["theta"] = variable("time", theta, "rad", "nutation angle θ: body z axis from the orbit normal")
        out["phi"] = variable("time", phi, "rad", "proper-rotation angle φ (unwrapped)")
        axis_orbital = np.stack([alpha[:, 2], beta[:, 2], gamma[:, 2]], axis=1)
        out["body_axis_orbital"] = variable(("time", "frame_axis"), axis_orbital, "1",
                                            "body z axis in the orbital frame (radial, along-track, normal)")
        c, s = np.cos(self.Omega * t), np.sin(self.Omega * t)  # the orbital frame turned by Ωt about the normal
        axis_inertial = np.stack([c * alpha[:, 2] - s * beta[:, 2], s * alpha[:, 2] + c * beta[:, 2], gamma[:, 2]],
                                 axis=-1)
        out["body_axis_inertial"] = variable(("time", "frame_axis"), axis_inertial, "1", "body z axis in the "
                                             "inertial frame (X = radial at t = 0, Z = orbit normal)")
        return out

    def attributes(self) -> dict[str, Any]:
        return system_attributes(self, initial_euler_angles=np.array(self.angles), initial_omega=self.omega0)

    def title(self) -> str:
        A, B, C = self.inertia
        forces = " + ".join(f.name for f in self.forces) or "no torque"
        return (f"satellite-gyrostat on a circular orbit, A,B,C=({A:.4g}, {B:.4g}, {C:.4g}), "
                f"k=({', '.join(f'{x:.3g}' for x in self.k)}), Ω={self.Omega:.4g}; {forces}")


def _initial(cfg: dict[str, Any], Omega: float) -> tuple[tuple[float, float, float], np.ndarray, np.ndarray, np.ndarray]:
    """Orbital Euler angles and absolute ω0 from ``initial``: the fixed-point keys (p0, q0, r0 = absolute ω0;
    ψ0, θ0, φ0 or γ0 = orbit normal in body axes) or ``euler_rates0`` = (ψ̇0, θ̇0, φ̇0) instead of p0, q0, r0."""
    unknown = sorted(k for k, v in cfg.items() if v is not None and k not in INITIAL_KEYS)
    if unknown:
        raise ConfigError(f"initial.{unknown[0]} is not a setting of the orbiting gyrostat; valid settings: "
                          f"{', '.join(INITIAL_KEYS)}")
    rates = cfg.get("euler_rates0")
    if rates is not None:
        given = [k for k in ("p0", "q0", "r0") if cfg.get(k) is not None]
        if given:
            raise ConfigError(f"initial.euler_rates0 and initial.{given[0]} both give the angular velocity; "
                              "set one form and null the other")
        rates = np.array(as_vector3(rates, "initial.euler_rates0"))
        cfg = {**cfg, "p0": 0.0, "q0": 0.0, "r0": 0.0}
    attitude = InitialAttitude.from_config(cfg)
    alpha, gamma = attitude.alpha, attitude.gamma
    psi, theta, phi = (float(x[0]) for x in euler_angles(alpha[None], gamma[None]))
    omega = attitude.omega if rates is None else kinematic_matrix(theta, phi) @ rates + Omega * gamma
    return (psi, theta, phi), omega, alpha, gamma

