"""Regular precession ψ = nt + ψ0, θ = θ0, φ = mt of the orbiting gyrostat, and its checks (a), (b).

(a) residual of the equations of motion along the prescribed motion, max over a time window:
    vector form — the ``orbiting_gyrostat`` system's own right-hand side (with its force plugins)
    against the exact derivative of the prescribed state; Euler-angle form — the Lagrange
    equations of ``gyrolab.physics.gyrostat_euler`` (blind to one direction of the vector
    residual at θ0 ∈ {0, π}, where det J = −sin θ0 = 0).
(b) integration of the full vector equations from the precession's initial state, max |θ − θ0|.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gyrolab.physics.attitude import frame_from_angles, nutation_and_spin
from gyrolab.contracts.integrator import Integrator
from gyrolab.plugins.forces.magnetic import Magnetic
from gyrolab.plugins.forces.newtonian import Newtonian
from gyrolab.physics.gyrostat_body import GyrostatBody
from gyrolab.physics.gyrostat_euler import GyrostatParameters, lagrange_equations
from gyrolab.plugins.systems.orbiting_gyrostat import OrbitingGyrostat


@dataclass(frozen=True)
class Precession:
    """ψ = n t + ψ0, θ = θ0, φ = m t relative to the orbital frame."""

    n: float
    m: float
    psi0: float
    theta0: float

    def angles(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        return self.n * t + self.psi0, np.full_like(t, self.theta0), self.m * t

    def initial_config(self) -> dict:
        return {"psi0": self.psi0, "theta0": self.theta0, "phi0": 0.0, "euler_rates0": [self.n, 0.0, self.m],
                "gamma0": None, "p0": None, "q0": None, "r0": None}


def magnetic_config(params: GyrostatParameters) -> dict:
    """The ``magnetic`` plugin's parameters for the paper's field: V = +μ·(h1 α + h2 β + h3 γ) = −μ·B."""
    h = np.asarray(params.h, dtype=float)
    size = float(np.linalg.norm(h))
    direction = (-h / size).tolist() if size > 0 else [0.0, 0.0, 1.0]
    return {"moment": list(map(float, params.mu)), "field": size, "direction": direction}


def body_config(params: GyrostatParameters, allow_nonphysical: bool = True) -> dict:
    return {"units": "nondimensional", "inertia": list(map(float, params.inertia)),
            "gyrostatic_momentum": list(map(float, params.k)), "orbit_rate": float(params.Omega),
            "allow_nonphysical": allow_nonphysical}


def build_system(params: GyrostatParameters, motion: Precession | None = None,
                 allow_nonphysical: bool = True) -> OrbitingGyrostat:
    """The ``orbiting_gyrostat`` system with the ``newtonian`` and ``magnetic`` plugins for the paper's parameters."""
    body = GyrostatBody.from_config(body_config(params, allow_nonphysical))
    forces = [Newtonian(body, N=params.N) if params.N is not None else Newtonian(body),
              Magnetic(body, **magnetic_config(params))]
    motion = motion or Precession(0.0, 0.0, 0.0, 0.0)
    return OrbitingGyrostat(body, forces, motion.initial_config(), {})


def states(system: OrbitingGyrostat, motion: Precession, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact state y(t) = (ω, α, γ) of the prescribed motion and its exact derivative, shapes (len(t), 9)."""
    psi, theta, phi = motion.angles(t)
    alpha, beta, gamma = (np.moveaxis(e, 0, -1) for e in frame_from_angles(psi, theta, phi))
    e3 = np.array([0.0, 0.0, 1.0])
    relative = motion.n * gamma + motion.m * e3  # ω′ = J q̇
    omega = relative + system.Omega * gamma
    gamma_dot = np.cross(gamma, relative)
    alpha_dot = -motion.n * beta + motion.m * np.stack([alpha[:, 1], -alpha[:, 0], np.zeros(len(psi))], axis=1)
    omega_dot = (motion.n + system.Omega) * gamma_dot
    return np.concatenate([omega, alpha, gamma], axis=1), np.concatenate([omega_dot, alpha_dot, gamma_dot], axis=1)


def window(system: OrbitingGyrostat, orbits: float = 5.0, points: int = 1001) -> np.ndarray:
    return np.linspace(0.0, orbits * 2 * np.pi / system.Omega, points)


def defect(system: OrbitingGyrostat, motion: Precession, t: np.ndarray) -> np.ndarray:
    """The residual at times t, shape (len(t), 9): I (ω̇ − f_ω) (torque) and ė − f_e of the Poisson equations."""
    y, y_dot = states(system, motion, t)
    out = y_dot - system.derivative(y)
    out[:, 0:3] *= system.inertia
    return out


def vector_residual(system: OrbitingGyrostat, motion: Precession, t: np.ndarray) -> float:
    """max over t of the residual's components (``defect``)."""
    return float(np.max(np.abs(defect(system, motion, t))))


def euler_residual(params: GyrostatParameters, motion: Precession, t: np.ndarray) -> float:
    """max over t of |E(q, q̇, 0)| of the Lagrange equations in Euler angles."""
    psi, theta, phi = motion.angles(t)
    qd, qdd = np.array([motion.n, 0.0, motion.m]), np.zeros(3)
    return float(max(np.max(np.abs(lagrange_equations((a, b, c), qd, qdd, params)))
                     for a, b, c in zip(psi, theta, phi)))


def theta_deviation(system: OrbitingGyrostat, motion: Precession, integrator: Integrator, orbits: float = 5.0,
                    points: int = 2001) -> dict[str, float]:
    """Integrate the full equations from the precession's initial state; max |θ − θ0| overall and in orbit 1."""
    t = window(system, orbits, points)
    y0 = states(system, motion, t[:1])[0][0]
    solution = integrator.integrate(system.rhs, t, y0)
    theta, _ = nutation_and_spin(solution.y[:, 6:9])
    deviation = np.abs(theta - motion.theta0)
    jacobi = system.jacobi_integral(solution.y)
    first = t <= 2 * np.pi / system.Omega * (1 + 1e-12)
    return {"max_theta_deviation": float(deviation.max()), "max_theta_deviation_orbit1": float(deviation[first].max()),
            "jacobi_drift": float(np.max(np.abs(jacobi - jacobi[0])))}
