"""Heavy rigid body about a fixed point: the Euler–Poisson equations in vector form.

In principal body axes (Ismail (2021) eq. 1, Shaker et al. eq. 1): I ω̇ = (I ω) × ω + Σ torques, γ̇ = γ × ω, with γ
the body components of the fixed vertical Z. The state is (ω, γ), plus α — the fixed X axis, α̇ = α × ω — only when
the scene needs the full attitude: Euler-angle output (ψ needs it) or a force along a non-vertical direction.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts.force import Force
from gyrolab.contracts.integrator import CompiledModel
from gyrolab.contracts.system import System
from gyrolab.kernels import model
from gyrolab.kernels.expression import check_torques
from gyrolab.physics.attitude import euler_angles, frame_from_angles, nutation_and_spin, unwrap
from gyrolab.physics.body import Body
from gyrolab.physics.initial import InitialAttitude
from gyrolab.physics.vectors import cross, dot, norm


class FixedPoint(System):
    name = "fixed_point"
    body_type = Body

    def __init__(self, body: Body, forces: Sequence[Force], initial: Any, output: Any) -> None:
        super().__init__(body, forces, initial, output)
        self.initial = InitialAttitude.from_config(initial)
        needed = set().union(*(f.required_axes for f in self.forces))
        self.euler_angles = bool(output.get("euler_angles", True))
        self.carries_alpha = self.euler_angles or bool(needed & {0, 1})
        self.needs_beta = 1 in needed
        self.inertia = body.inertia

    @property
    def state_size(self) -> int:
        return 9 if self.carries_alpha else 6

    def initial_state(self) -> np.ndarray:
        alpha = [self.initial.alpha] if self.carries_alpha else []
        return np.concatenate([self.initial.omega, self.initial.gamma, *alpha])

    def initial_states(self, initial: Mapping[str, Any],
                       columns: Mapping[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """``initial_state()`` for many points at once (a batch's plan, ``gyrolab.batch.plan``).

        ``initial`` is the config's initial node (valid: this system was built from it) and ``columns``
        maps initial keys to arrays, one value per point (NaN where a value is not a number). Returns the
        states (points × state size) and which rows are valid; an invalid row's error is the single
        run's, found by building that point (``InitialAttitude.from_config``), not here.
        """
        n = len(next(iter(columns.values()))) if columns else 1
        ok = np.ones(n, dtype=bool)
        if "gamma0" in columns or (initial.get("gamma0") is not None and {"theta0", "phi0"} & set(columns)):
            return np.full((n, self.state_size), np.nan), np.zeros(n, dtype=bool)
        value = {}
        for key in ("p0", "q0", "r0", "psi0", "theta0", "phi0"):
            if key in columns:
                value[key] = np.asarray(columns[key], dtype=float)
                ok &= np.isfinite(value[key])
            else:
                value[key] = np.full(n, float(initial.get(key) or 0.0))  # valid numbers (or an unused null θ0, φ0)
        omega = np.stack([value["p0"], value["q0"], value["r0"]], axis=1)
        if initial.get("gamma0") is not None:   # γ0 kept bit for bit; α from its angles (as from_config does)
            theta0, phi0 = (np.full(n, float(x)) for x in nutation_and_spin(self.initial.gamma))
        else:
            theta0, phi0 = value["theta0"], value["phi0"]
        alpha, _, gamma = (np.asarray(v).T for v in frame_from_angles(value["psi0"], theta0, phi0))
        if initial.get("gamma0") is not None:
            gamma = np.broadcast_to(self.initial.gamma, (n, 3))
        parts = [omega, gamma, alpha] if self.carries_alpha else [omega, gamma]
        return np.concatenate(parts, axis=1), ok

    def reference_frame(self, y: np.ndarray) -> np.ndarray:
        """Rows α, β, γ at state ``y``. Without α in the state every force reads γ only, so any frame with
        that γ serves (α is then the unit vector of e × γ, e the body axis least aligned with γ)."""
        gamma = np.asarray(y[3:6], dtype=float)
        if self.carries_alpha:
            alpha = np.asarray(y[6:9], dtype=float)
        else:
            alpha = np.cross(np.eye(3)[int(np.argmin(np.abs(gamma)))], gamma)
            alpha = alpha / np.linalg.norm(alpha)
        return np.array([alpha, np.cross(gamma, alpha), gamma])

    def rhs(self, t: float, y: np.ndarray) -> np.ndarray:
        return euler_poisson(t, y, self.inertia, self.forces, self.carries_alpha, self.needs_beta)

    @property
    def invariants(self) -> tuple[str, ...]:
        kept = {"energy": all(f.conservative for f in self.forces),
                "area_integral": all(f.preserves_area_integral for f in self.forces), "gamma_norm": True,
                "frame_error": self.carries_alpha}
        return tuple(name for name, monitored in kept.items() if monitored)

    def invariant_values(self, y: np.ndarray) -> dict[str, np.ndarray]:
        """Each monitored invariant (``invariants``) along states ``y`` of shape (..., state size)."""
        omega, gamma = y[..., 0:3], y[..., 3:6]
        alpha = y[..., 6:9] if self.carries_alpha else None
        invariants, momentum = self.invariants, self.inertia * omega
        values = {}
        if "energy" in invariants:
            axes = (alpha, cross(gamma, alpha) if self.needs_beta else None, gamma)
            values["energy"] = 0.5 * dot(omega, momentum)
            for force in self.forces:
                values["energy"] = values["energy"] + force.potential(axes)
        if "area_integral" in invariants:
            values["area_integral"] = dot(momentum, gamma)
        values["gamma_norm"] = norm(gamma)
        if self.carries_alpha:
            values["frame_error"] = np.maximum(np.abs(norm(alpha) - 1.0), np.abs(dot(alpha, gamma)))
        return values

    def variables(self, t: np.ndarray, y: np.ndarray) -> dict[str, xr.Variable]:
        body = self.body
        omega, gamma = y[:, 0:3], y[:, 3:6]
        out: dict[str, xr.Variable] = {
            "omega": variable(("time", "axis"), omega, body.rate_unit,
                              f"angular velocity (p, q, r) in body axes [{body.rate_label}]"),
            "gamma": variable(("time", "axis"), gamma, "1", "direction cosines of the fixed vertical Z in body axes"),
        }
        values = self.invariant_values(y)
        if "energy" in values:
            out["energy"] = variable("time", values["energy"], body.energy_unit,
                                     "total energy: kinetic ½ω·Iω plus the forces' potentials")
        if "area_integral" in values:
            out["area_integral"] = variable("time", values["area_integral"], body.momentum_unit,
                                            "area integral: angular momentum about the vertical, Iω·γ")
        out["gamma_norm"] = variable("time", values["gamma_norm"], "1",
                                     "norm of the direction-cosine vector |γ| (exactly 1)")
        if self.carries_alpha:
            out["alpha"] = variable(("time", "axis"), y[:, 6:9], "1",
                                    "direction cosines of the fixed X axis in body axes")
            out["frame_error"] = variable("time", values["frame_error"], "1",
                                          "orthonormality error of (α, γ): max(| |α| − 1 |, |α·γ|)")
        if self.euler_angles:
            psi, theta, phi = euler_angles(y[:, 6:9], gamma)
            out["psi"] = variable("time", psi, "rad", "precession angle ψ (unwrapped)")
        else:
            theta, phi = nutation_and_spin(gamma)
            phi = unwrap(phi)
        out["theta"] = variable("time", theta, "rad", "nutation angle θ")
        out["phi"] = variable("time", phi, "rad", "proper-rotation angle φ (unwrapped)")
        return out

    def attributes(self) -> dict[str, Any]:
        return system_attributes(self, initial_omega=self.initial.omega, initial_gamma=self.initial.gamma)

    def compiled_model(self) -> CompiledModel | None:
        """The equations traced (``System``), carrying the built-in forms' parameters when every torque has one
        (``built_in``: what the Lie–Poisson splitting and the regimes read)."""
        from gyrolab.kernels import fixed_point  # start-up: the compiled kernels import numba

        packed = fixed_point.built_in(self.inertia, self.forces, self.carries_alpha)
        compiled = super().compiled_model()
        return compiled if compiled is None or packed is None else replace(compiled, built_in=packed)

    def title(self) -> str:
        nd = self.body.nondimensional()
        forces = " + ".join(f.name for f in self.forces) or "no force (Euler–Poinsot)"
        p, q, r = self.initial.omega
        return (f"body about a fixed point, a={nd['a']:.4g}, b={nd['b']:.4g}; {forces}; "
                f"ω0=({p:.3g}, {q:.3g}, {r:.3g}) {self.body.rate_label}")


def euler_poisson(t: Any, y: np.ndarray, inertia: np.ndarray, forces: Sequence[Force], carries_alpha: bool,
                  needs_beta: bool) -> np.ndarray:
    """dy/dt of the Euler–Poisson equations: I ω̇ = (Iω) × ω + Σ torques, γ̇ = γ × ω (α̇ = α × ω), for one state.

    Numbers or symbols (``gyrolab.kernels.model`` traces it into every compiled kernel of a scene with a plugin
    torque): the equations are written here once.
    """
    omega, gamma = y[0:3], y[3:6]
    alpha = y[6:9] if carries_alpha else None
    axes = (alpha, cross(gamma, alpha) if needs_beta else None, gamma)
    torque = cross(inertia * omega, omega)
    # summed in the order of the forces' names, not the config's: a dataset's stored config (its keys sorted by the
    # YAML writer) reproduces the run bit for bit
    for force in sorted(forces, key=lambda f: f.name):
        torque = torque + (force.torque(omega, axes, t) if force.time_dependent else force.torque(omega, axes))
    parts = [torque / inertia, cross(gamma, omega)]
    if carries_alpha:
        parts.append(cross(alpha, omega))
    return np.concatenate(parts)


def traced_model(inertia: np.ndarray, forces: Sequence[Force], carries_alpha: bool) -> CompiledModel:
    """The fixed-point equations with ``forces`` compiled from their trace, whatever forms the forces have.
    Raises NotCompilable."""
    check_torques(forces)
    needs_beta = any(1 in f.required_axes for f in forces)
    names = " + ".join(f.name for f in forces) or "no torque"
    return model.compile(model.trace(lambda t, y: euler_poisson(t, y, inertia, forces, carries_alpha, needs_beta),
                                     9 if carries_alpha else 6, f"system fixed_point ({names})"))


def system_attributes(system: System, **initial: Any) -> dict[str, Any]:
    """A built-in system's dataset attributes: its name and state size, the body's, ``initial`` and every force's
    (``force_<name>_<key>``, a list as a float array)."""
    attrs: dict[str, Any] = {"system": system.name, "state_size": system.state_size, **system.body.attributes(),
                             **initial}
    for force in system.forces:
        for key, value in force.attributes().items():
            attrs[f"force_{force.name}_{key}"] = np.asarray(value, dtype=float) if isinstance(value, list) else value
    return attrs


def variable(dims: str | tuple[str, ...], data: np.ndarray, units: str, long_name: str) -> xr.Variable:
    # fastpath: the data is a float ndarray already, so xarray need not probe it for duck arrays (whose first
    # probe imports dask.array, ~1 s, when dask is installed: a batch's final variables paid it)
    attrs = {"units": units, "long_name": long_name}
    return xr.Variable(dims, np.asarray(data, dtype=float), attrs=attrs, fastpath=True)
