"""Exact periodic orbits of the heavy body about a fixed point: Newton shooting and Floquet multipliers.

The body-frame motion (ω, γ), I ω̇ = (Iω) × ω + U × γ + N γ × Iγ, γ̇ = γ × ω, is integrated with its variational
equations by a numba-compiled Taylor method of high order (the right-hand sides are quadratic: every coefficient is a
Cauchy product). The return residual has rank 3 (three first integrals), so Newton's step is the least-squares one,
with the exact Jacobian [Φ(T)D − D, f(y(T))] (docs/regimes.md, "Exact orbits").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels import layout
from gyrolab.kernels.compiler import kernel

ORDER = 24
TOL = 1e-17


@kernel
def _cross_acc(out, u, v, s):
    out[0] += s * (u[1] * v[2] - u[2] * v[1])
    out[1] += s * (u[2] * v[0] - u[0] * v[2])
    out[2] += s * (u[0] * v[1] - u[1] * v[0])


@kernel
def _coefficients(inertia, U, N, W, G, dW, dG, order, n_tangent):
    """Taylor coefficients 1..order of ω, γ and the tangent columns (rows 0 are given)."""
    tq = np.zeros(3)
    acc = np.zeros(3)
    IwA = np.zeros(3)
    IwB = np.zeros(3)
    for k in range(order):
        tq[:] = 0.0
        acc[:] = 0.0
        for j in range(k + 1):
            for i in range(3):
                IwA[i] = inertia[i] * W[j, i]
                IwB[i] = inertia[i] * G[k - j, i]
            _cross_acc(tq, IwA, W[k - j], 1.0)
            _cross_acc(tq, G[j], IwB, N)
            _cross_acc(acc, G[j], W[k - j], 1.0)
        _cross_acc(tq, U, G[k], 1.0)
        for i in range(3):
            W[k + 1, i] = tq[i] / inertia[i] / (k + 1)
            G[k + 1, i] = acc[i] / (k + 1)
        for m in range(n_tangent):
            tq[:] = 0.0
            acc[:] = 0.0
            for j in range(k + 1):
                for i in range(3):
                    IwA[i] = inertia[i] * dW[j, m, i]
                    IwB[i] = inertia[i] * W[j, i]
                _cross_acc(tq, IwA, W[k - j], 1.0)
                _cross_acc(tq, IwB, dW[k - j, m], 1.0)
                for i in range(3):
                    IwA[i] = inertia[i] * G[k - j, i]
                    IwB[i] = inertia[i] * dG[k - j, m, i]
                _cross_acc(tq, dG[j, m], IwA, N)
                _cross_acc(tq, G[j], IwB, N)
                _cross_acc(acc, dG[j, m], W[k - j], 1.0)
                _cross_acc(acc, G[j], dW[k - j, m], 1.0)
            _cross_acc(tq, U, dG[k, m], 1.0)
            for i in range(3):
                dW[k + 1, m, i] = tq[i] / inertia[i] / (k + 1)
                dG[k + 1, m, i] = acc[i] / (k + 1)


@kernel
def _flow(inertia, U, N, y0, phi0, t_end, order, tol):
    """(y(t_end), Φ(t_end) = ∂y(t_end)/∂y0 · phi0, steps); phi0 has shape (6, n_tangent)."""
    n_tangent = phi0.shape[1]
    W = np.zeros((order + 1, 3))
    G = np.zeros((order + 1, 3))
    dW = np.zeros((order + 1, n_tangent, 3))
    dG = np.zeros((order + 1, n_tangent, 3))
    y = y0.copy()
    phi = phi0.copy()
    t = 0.0
    steps = 0
    while t < t_end:
        W[0] = y[0:3]
        G[0] = y[3:6]
        for m in range(n_tangent):
            dW[0, m] = phi[0:3, m]
            dG[0, m] = phi[3:6, m]
        _coefficients(inertia, U, N, W, G, dW, dG, order, n_tangent)
        scale = max(1.0, np.max(np.abs(y)))
        h = np.inf
        for kk in (order - 1, order):
            nk = max(np.max(np.abs(W[kk])), np.max(np.abs(G[kk])))
            if nk > 0:
                h = min(h, (tol * scale / nk) ** (1.0 / kk))
        h = 0.9 * h
        if not h < np.inf or t + h >= t_end:  # the last two coefficients vanish, or the step passes t_end
            h = t_end - t
        w, g, dw, dg = W[order], G[order], dW[order], dG[order]
        for kk in range(order - 1, -1, -1):  # Horner, every component at once
            w, g, dw, dg = w * h + W[kk], g * h + G[kk], dw * h + dW[kk], dg * h + dG[kk]
        y[0:3], y[3:6] = w, g
        phi[0:3], phi[3:6] = dw.T, dg.T
        if not np.all(np.isfinite(y)):
            return y, phi, -1
        t += h
        steps += 1
    return y, phi, steps


@dataclass(frozen=True)
class FixedPointModel:
    """The torques the shooting supports: inertia I, weight moment U = M g r_c, Newtonian coefficient N."""

    inertia: np.ndarray
    weight_moment: np.ndarray
    newtonian: float

    @classmethod
    def from_system(cls, system) -> FixedPointModel:
        compiled = system.compiled_model()
        if compiled is None or compiled.built_in is None:  # the built-in torque forms only
            raise ConfigError("periodic orbits need forces with compiled forms; valid forces: uniform_gravity, newtonian")
        p = compiled.built_in
        if layout.torques_on_horizontal_axes(p):
            raise ConfigError("periodic orbits are computed for fields symmetric about the vertical only; "
                              "valid forces: uniform_gravity, newtonian")
        return cls(np.array(p[layout.INERTIA:layout.INERTIA + 3]), np.array(p[layout.U_Z:layout.U_Z + 3]),
                   float(p[layout.N_Z]))

    def rhs(self, y: np.ndarray) -> np.ndarray:
        w, g = y[:3], y[3:6]
        I = self.inertia
        dw = (np.cross(I * w, w) + np.cross(self.weight_moment, g) + self.newtonian * np.cross(g, I * g)) / I
        return np.concatenate([dw, np.cross(g, w)])

    def flow(self, y0: np.ndarray, t: float, tangent: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """State at time t from y0 (6,) and the propagated tangent columns (default: the full 6×6 Φ(t))."""
        phi0 = np.eye(6) if tangent is None else np.asarray(tangent, dtype=float)
        y, phi, steps = _flow(self.inertia, self.weight_moment, self.newtonian, np.asarray(y0, dtype=float),
                              phi0, float(t), ORDER, TOL)
        if steps < 0:
            raise IntegrationError(f"the shooting integration became non-finite before t={t:.6g}")
        return y, phi

    def sample(self, y0: np.ndarray, times: np.ndarray, tangent: np.ndarray | None = None):
        """States y(t) (n, 6) of the flow from y0 at ``times`` (any order, ≥ 0); with ``tangent`` also Φ(t)·tangent,
        returned as the pair (states, tangents)."""
        states, moved = np.empty((len(times), 6)), np.empty((len(times), 6))
        y, phi, now = np.asarray(y0, dtype=float), np.eye(6) if tangent is not None else np.zeros((6, 0)), 0.0
        for i in np.argsort(times):
            if times[i] > now:
                y, phi = self.flow(y, times[i] - now, phi)
                now = times[i]
            states[i] = y
            if tangent is not None:
                moved[i] = phi @ tangent
        return states if tangent is None else (states, moved)


@dataclass
class PeriodicOrbit:
    """A converged periodic orbit: initial state (6,), period, Newton history and Floquet multipliers."""

    y0: np.ndarray
    period: float
    residuals: list[float]
    monodromy: np.ndarray
    multipliers: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.multipliers = np.linalg.eigvals(self.monodromy)


def shoot(model: FixedPointModel, y0: np.ndarray, period: float, *, tol: float = 1e-13, accept: float = 1e-11,
          max_iter: int = 40) -> PeriodicOrbit:
    """Damped Gauss–Newton shooting from a guess y0 = (p, q, r0, γ, 0, γ0'') and period; r, γ', γ'' stay fixed.

    Stops below ``tol`` or at the rounding floor; an orbit only below ``accept`` (IntegrationError otherwise), tight
    on purpose: near Shaker et al.'s amplitude circle a point *not* on an orbit returns to within 1e-10
    (docs/regimes.md, "Exact orbits").
    """
    y0 = np.asarray(y0, dtype=float)
    if abs(y0[4]) > 1e-12:
        raise ConfigError(f"shooting starts on the section γ'(0) = 0; got γ'(0)={y0[4]:.3g}")
    r0, gpp = y0[2], y0[5]
    scale = max(1.0, float(np.max(np.abs(y0))))
    D = np.eye(6, 2)  # ∂y0/∂(p0, q0)

    def attempt(u):
        s0 = np.array([u[0], u[1], r0, np.sqrt(max(0.0, 1.0 - gpp**2)), 0.0, gpp])
        sT, phi = model.flow(s0, u[2])
        res = sT - s0
        return float(np.max(np.abs(res))) / scale, res, s0, sT, phi

    u = np.array([y0[0], y0[1], float(period)])
    norm, res, s0, sT, phi = attempt(u)
    residuals = [norm]
    for _ in range(max_iter):
        if norm < tol:
            break
        J = np.column_stack([phi @ D - D, model.rhs(sT)])
        step = np.linalg.lstsq(J, -res, rcond=None)[0]
        # Non-monotone (watchdog) rule: the full step is taken if it stays below the worst of the last few
        # residuals — near a nearly degenerate family Gauss–Newton zigzags before it converges, and monotone
        # damping would crawl — otherwise it is halved until the residual decreases.
        trial = attempt(u + step)
        damping = 1.0
        if not trial[0] < max(residuals[-4:]):
            for damping in 0.5 ** np.arange(1, 12):
                trial = attempt(u + damping * step)
                if trial[0] < norm:
                    break
            else:
                break  # no decrease along the Newton direction: converged to the floor, or stalled
        u = u + damping * step
        norm, res, s0, sT, phi = trial
        residuals.append(norm)
    if norm > accept:
        raise IntegrationError(f"Newton shooting did not converge: return residual {norm:.2e} (needs < {accept:.0e}) "
                               f"after {len(residuals) - 1} iterations; there is no periodic orbit near the start "
                               "or the start is too far from it")
    return PeriodicOrbit(y0=s0, period=float(u[2]), residuals=residuals, monodromy=phi)
