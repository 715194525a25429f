"""The orbiting satellite-gyrostat written for heyoka, independently of gyrolab's kernels: double and real128.

Yehia & El-kenani (2021) in the vector form of ``plugins/systems/orbiting_gyrostat.py``'s docstring
(docs/gyrostat.md), written here from that form, not from gyrolab's traced equations:

    I ω̇ = (Iω + k) × ω + N α × Iα + μ × (h0 α + h1 β + h2 γ),   β = γ × α,
    α̇ = α × (ω − Ωγ),   γ̇ = γ × ω,

state y = (ω, α, γ), I = diag(A, B, C), k the rotors' momentum, N the gravity-gradient coefficient (3Ω² on a
Keplerian orbit), μ the body's dipole and (h0, h1, h2) = field · direction the magnetic field in the orbital frame
(α radial, β along-track, γ orbit normal). The constants are read from the scene's body and force objects (not
from the compiled model's packed parameters). ``check_against_python_rhs`` compares these equations with gyrolab's
own numpy right-hand side at random states before any number is trusted.

``Real128Gyrostat`` compiles the system once in quadruple precision (tol 1e-30) with the constants as runtime
parameters, 1/A, 1/B, 1/C as real128 numbers (a division by a constant would become a product by a reciprocal
rounded to double, benchmarks/real128_reference.py), for the speed benchmark's reference and the audit of many
random scenes (benchmarks/promise_audit_gyrostat.py).
"""

from __future__ import annotations

import numpy as np

TOL = "1e-30"
N_PARS = 17  # A, B, C, 1/A, 1/B, 1/C, k (3), Ω, N, μ (3), h (3)


def constants(scene) -> dict:
    """The physical constants of an orbiting-gyrostat scene, from its body and force plugins."""
    system = scene.system
    if system.name != "orbiting_gyrostat":
        raise ValueError(f"not an orbiting gyrostat scene: {system.name}")
    N, mu, h = 0.0, np.zeros(3), np.zeros(3)
    for force in system.forces:
        if force.name == "newtonian":
            if getattr(force, "axis", None) != 0:
                raise ValueError("the gravity gradient must act about the radial axis α")
            N += float(force.N)
        elif force.name == "magnetic":
            if h.any():
                raise ValueError("one magnetic dipole only")
            mu = np.array(force.moment, dtype=float)
            h = np.array([force.field * force.direction[i] for i in range(3)], dtype=float)
        else:
            raise ValueError(f"force {force.name} is outside these equations")
    return {"inertia": np.array(system.inertia, dtype=float), "k": np.array(system.k, dtype=float),
            "Omega": float(system.Omega), "N": N, "mu": mu, "h": h}


def _cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def equations(hy, c, inverse=None):
    """[(variable, right-hand side)] of the nine state variables; ``c`` maps the constants' names to numbers or
    heyoka expressions (inertia, inv_inertia, k, Omega, N, mu, h); ``inverse``: multiply by these 1/I instead of
    dividing by I."""
    w = hy.make_vars("w1", "w2", "w3")
    a = hy.make_vars("a1", "a2", "a3")
    g = hy.make_vars("g1", "g2", "g3")
    I, k = c["inertia"], c["k"]
    momentum = [I[i] * w[i] + k[i] for i in range(3)]
    gyroscopic = _cross(momentum, w)
    gradient = _cross(a, [I[i] * a[i] for i in range(3)])
    b = _cross(g, a)  # β = γ × α
    field = [c["h"][0] * a[i] + c["h"][1] * b[i] + c["h"][2] * g[i] for i in range(3)]
    magnetic = _cross(c["mu"], field)
    torque = [gyroscopic[i] + c["N"] * gradient[i] + magnetic[i] for i in range(3)]
    rates = [torque[i] * inverse[i] if inverse is not None else torque[i] / I[i] for i in range(3)]
    relative = [w[i] - c["Omega"] * g[i] for i in range(3)]
    return list(zip([*w, *a, *g], [*rates, *_cross(a, relative), *_cross(g, w)]))


def double_system(hy, scene):
    """The equations with the scene's constants as double numbers (heyoka folds them into its kernel)."""
    c = constants(scene)
    return equations(hy, {**c, "inertia": [float(x) for x in c["inertia"]], "k": [float(x) for x in c["k"]],
                          "mu": [float(x) for x in c["mu"]], "h": [float(x) for x in c["h"]]})


def parametric_system(hy):
    """The equations with the constants as heyoka runtime parameters (``pack`` orders them)."""
    p = [hy.par[i] for i in range(N_PARS)]
    c = {"inertia": p[0:3], "k": p[6:9], "Omega": p[9], "N": p[10], "mu": p[11:14], "h": p[14:17]}
    return equations(hy, c, inverse=p[3:6])


def pack(scene, real128=None) -> list:
    """The runtime parameters of ``parametric_system`` for the scene (real128 numbers when ``real128`` is heyoka's
    real128 type: 1/I rounded in quadruple precision)."""
    c = constants(scene)
    cast = real128 if real128 is not None else float
    inertia = [cast(float(x)) for x in c["inertia"]]
    return [*inertia, *(cast(1) / x for x in inertia), *(cast(float(x)) for x in c["k"]), cast(c["Omega"]),
            cast(c["N"]), *(cast(float(x)) for x in c["mu"]), *(cast(float(x)) for x in c["h"])]


def check_against_python_rhs(scene, samples: int = 20, seed: int = 0) -> float:
    """Max relative difference between these equations (heyoka's compiled function, double) and gyrolab's numpy
    ``System.rhs`` at random states (random ω, a random orthonormal pair α, γ): signs and conventions checked."""
    import heyoka as hy

    system = parametric_system(hy)
    variables = [v for v, _ in system]
    cf = hy.cfunc([f for _, f in system], variables)
    pars = np.array(pack(scene), dtype=float)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(samples):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        y = np.concatenate([rng.normal(scale=2.0, size=3), q[:, 0], q[:, 1]])
        ours = cf(y, pars=pars)
        theirs = np.asarray(scene.system.rhs(0.0, y), dtype=float)
        worst = max(worst, float(np.max(np.abs(ours - theirs)) / max(1.0, np.max(np.abs(theirs)))))
    return worst


class Real128Gyrostat:
    """One compiled real128 integrator (tol 1e-30) for every orbiting-gyrostat scene."""

    def __init__(self) -> None:
        import heyoka as hy

        self.hy = hy
        self.ta = hy.taylor_adaptive(parametric_system(hy), np.zeros(9, dtype=hy.real128), tol=hy.real128(TOL),
                                     fp_type=hy.real128, pars=np.zeros(N_PARS, dtype=hy.real128))

    def states(self, scene, times=None, y0=None) -> np.ndarray:
        """The state (ω, α, γ) at ``times`` (default the scene's output times), one row per time, as doubles."""
        hy = self.hy
        ta = self.ta
        ta.pars[:] = np.array(pack(scene, hy.real128), dtype=hy.real128)
        start = np.asarray(scene.system.initial_state() if y0 is None else y0, dtype=float)
        ta.state[:] = np.array([hy.real128(float(v)) for v in start], dtype=hy.real128)
        ta.time = hy.real128(0)
        grid = np.asarray(scene.times if times is None else times, dtype=float)
        outcome, *_, values = ta.propagate_grid(np.array([hy.real128(float(t)) for t in grid], dtype=hy.real128))
        values = np.asarray(values).astype(float)
        if outcome != hy.taylor_outcome.time_limit or values.shape != (len(grid), 9):
            raise RuntimeError(f"heyoka's real128 run stopped early ({outcome})")
        return values
