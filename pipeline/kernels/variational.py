"""Variational equations of the fixed-point system, and the chaos indicators they give (compiled, batched).

State x = (ω, γ) of the Euler–Poisson equations with the built-in torques acting on the vertical
(``fixed_point.pack``: uniform gravity U × γ with U = p[U_Z:U_Z + 3], Newtonian N γ × Iγ with N = p[N_Z]):

    I ω̇ = (Iω) × ω + U × γ + N γ × Iγ,        γ̇ = γ × ω.

The tangent vector δ = (δω, δγ) obeys δ̇ = J(x) δ with the analytic 6×6 Jacobian J (``jacobian``; the kernel
applies it without forming it).
Along it two indicators are integrated in the same RK4 steps as the state (14 unknowns per trajectory):

* MEGNO (Cincotta & Simó 2000): Y(t) = (2/t) ∫₀ᵗ s ρ(s) ds with ρ = δ̇·δ / δ·δ = d ln‖δ‖/dt, and its
  time mean ⟨Y⟩(t) = (1/t) ∫₀ᵗ Y(s) ds, as two quadratures a' = s ρ, b' = 2a/s (Y = 2a/t, ⟨Y⟩ = b/t).
  ρ is invariant under a rescaling of δ, so δ is renormalised to unit length after every step without
  touching the indicator; the logarithms of the norms are summed instead.
* FLI (Froeschlé, Lega & Gonczi 1997): max over the steps of ln‖δ(t)‖ with ‖δ(0)‖ = 1, from that sum.

The constraint |γ| = 1 is an invariant of the flow, and the linearised flow keeps γ·δγ constant
(d/dt(γ·δγ) = (γ×ω)·δγ + γ·(δγ×ω) = 0), so a tangent vector whose δγ starts tangent to the sphere
stays tangent: δ lives on the constraint manifold. The initial δ is chosen so (``initial_tangent``).

Only 6-D (ω, γ) states with p[CARRIES_ALPHA] = 0 (α not carried): torques on the fixed horizontal axes (which need α) are
refused by the caller.
"""

from __future__ import annotations

import numba
import numpy as np

from gyrolab.kernels.layout import INERTIA, INV_INERTIA, N_Z, U_Z
from gyrolab.kernels import dop853
from gyrolab.kernels.compiler import inline_kernel, kernel
from gyrolab.kernels.fixed_point import rhs_block
from gyrolab.kernels.fixed_point import rhs  # (ω, γ) states

#: unknowns of the augmented system: x (6), δ (6), the MEGNO quadratures a and b
AUGMENTED = 14
#: an arbitrary fixed direction (no symmetry of the problem singles it out) for the initial tangent vector
_DIRECTION = np.array([0.31, -0.47, 0.59, 0.23, -0.71, 0.37])


def initial_tangent(y0s: np.ndarray) -> np.ndarray:
    """Unit tangent vectors (one row per trajectory) with δγ ⟂ γ0: on the constraint manifold |γ| = 1."""
    y0s = np.asarray(y0s, dtype=float)
    d = np.tile(_DIRECTION, (len(y0s), 1))
    g = y0s[:, 3:6] / np.linalg.norm(y0s[:, 3:6], axis=1, keepdims=True)
    d[:, 3:6] -= np.sum(d[:, 3:6] * g, axis=1, keepdims=True) * g
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def jacobian(y: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The 6×6 Jacobian ∂f/∂(ω, γ) at state y, written out entry by entry (rows: ω̇, γ̇)."""
    I0, I1, I2 = p[INERTIA:INERTIA + 3]
    w0, w1, w2, g0, g1, g2 = y[:6]
    u0, u1, u2 = p[U_Z:U_Z + 3]
    n = p[N_Z]
    J = np.zeros((6, 6))
    J[0, 1:3] = (I1 - I2) * w2, (I1 - I2) * w1
    J[1, 0], J[1, 2] = (I2 - I0) * w2, (I2 - I0) * w0
    J[2, 0:2] = (I0 - I1) * w1, (I0 - I1) * w0
    J[0, 4:6] = -u2 + n * (I2 - I1) * g2, u1 + n * (I2 - I1) * g1
    J[1, 3], J[1, 5] = u2 + n * (I0 - I2) * g2, -u0 + n * (I0 - I2) * g0
    J[2, 3:5] = -u1 + n * (I1 - I0) * g1, u0 + n * (I1 - I0) * g0
    J[0:3] /= np.array([I0, I1, I2])[:, None]
    # γ̇ = γ × ω: ∂/∂ω = [γ]×, ∂/∂γ = −[ω]×
    J[3:6, 0:3] = [[0, -g2, g1], [g2, 0, -g0], [-g1, g0, 0]]
    J[3:6, 3:6] = [[0, w2, -w1], [-w2, 0, w0], [w1, -w0, 0]]
    return J


@inline_kernel
def _nutation(g2):
    return np.arccos(min(1.0, max(-1.0, g2)))


#: trajectories advanced in lock step by one thread: 2.6× faster than one trajectory per thread (measured on a loaded
#: machine; 16 and 64 were not faster)
BLOCK = 32


@kernel
def _augmented_block(s, Z, P, out, count):
    """Right-hand side of (x, δ, a, b) at time s since the start — ẋ = f, δ̇ = Jδ (``jacobian`` applied to δ
    without forming J), ȧ = s ρ, ḃ = 2a/s — for a block of trajectories stored by columns (Z[:, j] is
    trajectory j): the loop runs across trajectories, so the arithmetic vectorises. ẋ is ``fixed_point.rhs_block``."""
    rhs_block(Z, P, out, count)  # rows 0-5: the state's right-hand side
    for j in range(count):
        I0, I1, I2 = P[INERTIA, j], P[INERTIA + 1, j], P[INERTIA + 2, j]
        u0, u1, u2 = P[U_Z, j], P[U_Z + 1, j], P[U_Z + 2, j]
        n = P[N_Z, j]
        w0, w1, w2, g0, g1, g2 = Z[0, j], Z[1, j], Z[2, j], Z[3, j], Z[4, j], Z[5, j]
        a0, a1, a2, c0, c1, c2 = Z[6, j], Z[7, j], Z[8, j], Z[9, j], Z[10, j], Z[11, j]
        d0 = ((I1 - I2) * (a1 * w2 + w1 * a2) + u1 * c2 - u2 * c1 + n * (I2 - I1) * (c1 * g2 + g1 * c2)) * P[INV_INERTIA, j]
        d1 = ((I2 - I0) * (a2 * w0 + w2 * a0) + u2 * c0 - u0 * c2 + n * (I0 - I2) * (c2 * g0 + g2 * c0)) * P[INV_INERTIA + 1, j]
        d2 = ((I0 - I1) * (a0 * w1 + w0 * a1) + u0 * c1 - u1 * c0 + n * (I1 - I0) * (c0 * g1 + g0 * c1)) * P[INV_INERTIA + 2, j]
        e0 = c1 * w2 + g1 * a2 - c2 * w1 - g2 * a1
        e1 = c2 * w0 + g2 * a0 - c0 * w2 - g0 * a2
        e2 = c0 * w1 + g0 * a1 - c1 * w0 - g1 * a0
        out[6, j], out[7, j], out[8, j], out[9, j], out[10, j], out[11, j] = d0, d1, d2, e0, e1, e2
        dd = a0 * a0 + a1 * a1 + a2 * a2 + c0 * c0 + c1 * c1 + c2 * c2
        dj = a0 * d0 + a1 * d1 + a2 * d2 + c0 * e0 + c1 * e1 + c2 * e2
        out[12, j] = s * dj / dd
        out[13, j] = 2.0 * Z[12, j] / s if s > 0.0 else 0.0  # a = O(s²), so 2a/s → 0 at s = 0


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_indicators(P, t_out, steps_per_interval, Y0, D0, megno, fli, deviation, final):
    """Integrate state and tangent vector of every trajectory with fixed-step RK4, in parallel.

    P[j], Y0[j], D0[j]: parameters, initial (ω, γ) and unit initial tangent vector of trajectory j.
    Fills megno[j, i] = ⟨Y⟩ at t_out[i] (0 at the start; megno with one column: ⟨Y⟩ at t_out[-1] only, so a
    chunk's memory does not grow with the output times), fli[j] = max ln‖δ‖ over the steps,
    deviation[j] = max |θ − θ0| over the steps (θ = arccos γ3) and final[j] = the state at t_out[-1].
    A trajectory that becomes non-finite is NaN from there on. Blocks of BLOCK trajectories advance in
    lock step, stored by columns so that every loop runs across trajectories; blocks run in parallel.
    """
    count = Y0.shape[0]
    n = AUGMENTED
    for b in numba.prange((count + BLOCK - 1) // BLOCK):
        j0 = b * BLOCK
        m = min(BLOCK, count - j0)
        z = np.zeros((n, BLOCK))
        p = np.zeros((P.shape[1], BLOCK))
        theta0, log_norm = np.zeros(BLOCK), np.zeros(BLOCK)
        best, worst = np.zeros(BLOCK), np.zeros(BLOCK)
        for j in range(m):
            z[0:6, j] = Y0[j0 + j]
            z[6:12, j] = D0[j0 + j]
            p[:, j] = P[j0 + j]
            theta0[j] = _nutation(z[5, j])
            megno[j0 + j, 0] = 0.0
        every = megno.shape[1] > 1
        k1, k2, k3 = np.empty((n, BLOCK)), np.empty((n, BLOCK)), np.empty((n, BLOCK))
        k4, tmp = np.empty((n, BLOCK)), np.empty((n, BLOCK))
        for i in range(1, t_out.size):
            steps = steps_per_interval[i - 1]
            h = (t_out[i] - t_out[i - 1]) / steps
            for k in range(steps):
                s = (t_out[i - 1] - t_out[0]) + k * h
                _augmented_block(s, z, p, k1, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = z[c, j] + 0.5 * h * k1[c, j]
                _augmented_block(s + 0.5 * h, tmp, p, k2, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = z[c, j] + 0.5 * h * k2[c, j]
                _augmented_block(s + 0.5 * h, tmp, p, k3, m)
                for c in range(n):
                    for j in range(m):
                        tmp[c, j] = z[c, j] + h * k3[c, j]
                _augmented_block(s + h, tmp, p, k4, m)
                for c in range(n):
                    for j in range(m):
                        z[c, j] += (h / 6.0) * (k1[c, j] + 2.0 * k2[c, j] + 2.0 * k3[c, j] + k4[c, j])
                for j in range(m):
                    norm = np.sqrt(z[6, j] * z[6, j] + z[7, j] * z[7, j] + z[8, j] * z[8, j]
                                   + z[9, j] * z[9, j] + z[10, j] * z[10, j] + z[11, j] * z[11, j])
                    for c in range(6, 12):
                        z[c, j] /= norm
                    log_norm[j] += np.log(norm)
                    best[j] = max(best[j], log_norm[j])
                    worst[j] = max(worst[j], abs(_nutation(z[5, j]) - theta0[j]))
            if every or i == t_out.size - 1:
                for j in range(m):
                    megno[j0 + j, i if every else 0] = z[13, j] / (t_out[i] - t_out[0])
        for j in range(m):
            ok = np.isfinite(log_norm[j] + z[0, j] + z[1, j] + z[2, j] + z[12, j] + z[13, j])
            for i in range(megno.shape[1]):  # NaN from the first non-finite output on
                if not np.isfinite(megno[j0 + j, i]):
                    ok = False
                if not ok:
                    megno[j0 + j, i] = np.nan
            fli[j0 + j] = best[j] if ok else np.nan
            deviation[j0 + j] = worst[j] if ok else np.nan
            for c in range(6):
                final[j0 + j, c] = z[c, j] if ok else np.nan


@numba.njit(cache=True, parallel=True, error_model="numpy")
def run_indicators_dop853(P, t_out, Y0, D0, rtol, atol, max_step, megno, fli, deviation, final, steps):
    """``run_indicators`` with DOP853 (Hairer, Nørsett & Wanner §II.10; scipy's controller and error norm, as in
    ``dop853.run``), one trajectory per thread: each has its own steps. The error is controlled on x and δ
    (δ renormalised after every step), not on the MEGNO quadratures; steps land on every output time.
    steps[j] counts the accepted steps; 0 with NaN results if the step fell below rounding or went non-finite.
    """
    for j in numba.prange(Y0.shape[0]):
        _dop853_trajectory(P[j], t_out, Y0[j], D0[j], rtol, atol, max_step, megno[j], fli, deviation, final[j],
                           steps, j)


def tangent_growths(p: np.ndarray, y0: np.ndarray, t_pilot: float, t_end: float, tol: float) -> tuple[float, float]:
    """(max ln|δ(t)| over [0, t_pilot], over [0, t_end]) of the unit tangent vector ``initial_tangent`` of the (ω, γ)
    state ``y0``, by DOP853 at rtol = atol = ``tol`` in this thread (no thread pool: one trajectory). ``p`` with
    CARRIES_ALPHA = 0; NaNs when a run fails.

    Two runs, one to each end, as ``auto`` has always measured them: on a chaotic scene the growth over the span
    of a run at this loose tolerance scatters by up to e^±4 with any change of its steps (slow_spin over t = 300
    at 1e-5: e^19.6 from a run to t_end, e^15.0 from one whose steps land on t_pilot on the way), and
    ``auto.CHAOS_MARGIN`` is calibrated on the former (benchmarks/chaos_promise.py broke 3 of 40 promises with
    the latter). ``_tangent_run`` carries the 12 unknowns of state and tangent only (no MEGNO quadratures, flat
    arrays) and takes the steps of ``_dop853_trajectory``: 0.47 ms for both runs on the reference scene where
    ``_dop853_trajectory`` took 0.77 ms (AMD EPYC with AVX-512, 2026-11-27)."""
    y = np.ascontiguousarray(y0[:6], dtype=float)
    d = initial_tangent(y[None, :])[0]
    p = np.ascontiguousarray(p, dtype=float)
    logs = (_tangent_run(p, y, d, float(t_pilot), float(tol)), _tangent_run(p, y, d, float(t_end), float(tol)))
    return logs[0], logs[1]


@inline_kernel
def _state_and_tangent(y, p, out):
    """ẋ = f(x) and δ̇ = J(x) δ for y = (x, δ), one trajectory: the arithmetic of ``_augmented_block`` (and of
    ``fixed_point.rhs_block``) term for term, so that a tangent run takes the same steps as there."""
    I0, I1, I2 = p[INERTIA], p[INERTIA + 1], p[INERTIA + 2]
    u0, u1, u2 = p[U_Z], p[U_Z + 1], p[U_Z + 2]
    n = p[N_Z]
    w0, w1, w2, g0, g1, g2 = y[0], y[1], y[2], y[3], y[4], y[5]
    a0, a1, a2, c0, c1, c2 = y[6], y[7], y[8], y[9], y[10], y[11]
    out[0] = ((I1 - I2) * w1 * w2 + u1 * g2 - u2 * g1 + n * (I2 - I1) * g1 * g2) * p[INV_INERTIA]
    out[1] = ((I2 - I0) * w2 * w0 + u2 * g0 - u0 * g2 + n * (I0 - I2) * g2 * g0) * p[INV_INERTIA + 1]
    out[2] = ((I0 - I1) * w0 * w1 + u0 * g1 - u1 * g0 + n * (I1 - I0) * g0 * g1) * p[INV_INERTIA + 2]
    out[3] = g1 * w2 - g2 * w1
    out[4] = g2 * w0 - g0 * w2
    out[5] = g0 * w1 - g1 * w0
    out[6] = ((I1 - I2) * (a1 * w2 + w1 * a2) + u1 * c2 - u2 * c1 + n * (I2 - I1) * (c1 * g2 + g1 * c2)) * p[INV_INERTIA]
    out[7] = ((I2 - I0) * (a2 * w0 + w2 * a0) + u2 * c0 - u0 * c2 + n * (I0 - I2) * (c2 * g0 + g2 * c0)) * p[INV_INERTIA + 1]
    out[8] = ((I0 - I1) * (a0 * w1 + w0 * a1) + u0 * c1 - u1 * c0 + n * (I1 - I0) * (c0 * g1 + g0 * c1)) * p[INV_INERTIA + 2]
    out[9] = c1 * w2 + g1 * a2 - c2 * w1 - g2 * a1
    out[10] = c2 * w0 + g2 * a0 - c0 * w2 - g0 * a2
    out[11] = c0 * w1 + g0 * a1 - c1 * w0 - g1 * a0


@kernel
def _tangent_run(p, y0, d0, t_end, tol):
    """max ln|δ| over [0, t_end] by DOP853 on (x, δ), with scipy's controller on all 12 unknowns and δ renormalised
    after every step: the steps and arithmetic of ``_dop853_trajectory`` without its MEGNO rows. NaN when the run
    fails."""
    n = 12
    K = np.empty((dop853.N_STAGES + 1, n))
    y, f, ytmp, y_new = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
    y[0:6] = y0
    y[6:12] = d0
    _state_and_tangent(y, p, f)
    scale0 = 0.0
    scale1 = 0.0
    for m in range(n):
        sc = tol + abs(y[m]) * tol
        scale0 += (y[m] / sc) ** 2
        scale1 += (f[m] / sc) ** 2
    h_abs = 1e-6 if (scale0 < 1e-10 * n or scale1 < 1e-10 * n) else 0.01 * np.sqrt(scale0 / scale1)
    h_abs = min(h_abs, t_end)
    t = 0.0
    log_norm = best = 0.0
    while t < t_end:
        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        while True:
            if h_abs < min_step or not np.isfinite(h_abs):
                return np.nan
            t_new = min(t + h_abs, t_end)
            h = t_new - t
            K[0] = f
            for s in range(1, dop853.N_STAGES):
                for m in range(n):
                    acc = 0.0
                    for q in range(s):
                        acc += K[q, m] * dop853.A[s, q]
                    ytmp[m] = y[m] + acc * h
                _state_and_tangent(ytmp, p, K[s])
            for m in range(n):
                acc = 0.0
                for q in range(dop853.N_STAGES):
                    acc += K[q, m] * dop853.B[q]
                y_new[m] = y[m] + h * acc
            _state_and_tangent(y_new, p, K[dop853.N_STAGES])
            e5 = 0.0
            e3 = 0.0
            for m in range(n):
                sc = tol + max(abs(y[m]), abs(y_new[m])) * tol
                a5 = 0.0
                a3 = 0.0
                for q in range(dop853.N_STAGES + 1):
                    a5 += K[q, m] * dop853.E5[q]
                    a3 += K[q, m] * dop853.E3[q]
                e5 += (a5 / sc) ** 2
                e3 += (a3 / sc) ** 2
            error = 0.0 if e5 == 0.0 and e3 == 0.0 else abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * n)
            if not np.isfinite(error):
                return np.nan
            if error < 1.0:
                factor = dop853.MAX_FACTOR if error == 0.0 else min(
                    dop853.MAX_FACTOR, dop853.SAFETY * error ** dop853.ERROR_EXPONENT)
                h_abs *= min(1.0, factor) if rejected else factor
                break
            h_abs *= max(dop853.MIN_FACTOR, dop853.SAFETY * error ** dop853.ERROR_EXPONENT)
            rejected = True
        t = t_new
        norm = 0.0
        for m in range(6, 12):
            norm += y_new[m] * y_new[m]
        norm = np.sqrt(norm)
        for m in range(n):
            y[m] = y_new[m] / norm if m >= 6 else y_new[m]
        log_norm += np.log(norm)
        best = max(best, log_norm)
        _state_and_tangent(y, p, f)  # δ rescaled: its derivative too
    return best if np.isfinite(log_norm + y[0] + y[1] + y[2]) else np.nan


@kernel
def _dop853_trajectory(p, t_out, y0, d0, rtol, atol, max_step, megno, fli, deviation, final, steps, j):
    n = AUGMENTED
    controlled = 12  # x and δ
    P = np.empty((p.size, 1))  # the parameters as the single column of a transposed (parameter, trajectory) table
    for i in range(p.size):
        P[i, 0] = p[i]
    y = np.zeros((n, 1))
    y[0:6, 0] = y0
    y[6:12, 0] = d0
    K = np.empty((dop853.N_STAGES + 1, n, 1))
    f = np.empty((n, 1))
    ytmp, y_new = np.empty((n, 1)), np.empty((n, 1))
    theta0 = _nutation(y[5, 0])
    log_norm = best = worst = 0.0
    megno[0] = 0.0
    every = megno.size > 1
    _augmented_block(0.0, y, P, f, 1)
    scale0 = 0.0
    scale1 = 0.0
    for m in range(controlled):
        sc = atol + abs(y[m, 0]) * rtol
        scale0 += (y[m, 0] / sc) ** 2
        scale1 += (f[m, 0] / sc) ** 2
    h_abs = 1e-6 if (scale0 < 1e-10 * controlled or scale1 < 1e-10 * controlled) else 0.01 * np.sqrt(scale0 / scale1)
    h_abs = min(h_abs, max_step, t_out[-1] - t_out[0])
    t = t_out[0]
    accepted = 0
    for i in range(1, t_out.size):
        t_bound = t_out[i]
        while t < t_bound:
            min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
            h_abs = min(max(h_abs, min_step), max_step)
            rejected = False
            while True:
                if h_abs < min_step or not np.isfinite(h_abs):
                    return _dop853_failed(megno, fli, deviation, final, steps, j)
                t_new = min(t + h_abs, t_bound)
                h = t_new - t
                K[0] = f
                for s in range(1, dop853.N_STAGES):
                    for m in range(n):
                        acc = 0.0
                        for q in range(s):
                            acc += K[q, m, 0] * dop853.A[s, q]
                        ytmp[m, 0] = y[m, 0] + acc * h
                    _augmented_block(t + dop853.C[s] * h - t_out[0], ytmp, P, K[s], 1)
                for m in range(n):
                    acc = 0.0
                    for q in range(dop853.N_STAGES):
                        acc += K[q, m, 0] * dop853.B[q]
                    y_new[m, 0] = y[m, 0] + h * acc
                _augmented_block(t_new - t_out[0], y_new, P, K[dop853.N_STAGES], 1)
                e5 = 0.0
                e3 = 0.0
                for m in range(controlled):
                    sc = atol + max(abs(y[m, 0]), abs(y_new[m, 0])) * rtol
                    a5 = 0.0
                    a3 = 0.0
                    for q in range(dop853.N_STAGES + 1):
                        a5 += K[q, m, 0] * dop853.E5[q]
                        a3 += K[q, m, 0] * dop853.E3[q]
                    e5 += (a5 / sc) ** 2
                    e3 += (a3 / sc) ** 2
                error = 0.0 if e5 == 0.0 and e3 == 0.0 else abs(h) * e5 / np.sqrt((e5 + 0.01 * e3) * controlled)
                if not np.isfinite(error):
                    return _dop853_failed(megno, fli, deviation, final, steps, j)
                if error < 1.0:
                    factor = dop853.MAX_FACTOR if error == 0.0 else min(
                        dop853.MAX_FACTOR, dop853.SAFETY * error ** dop853.ERROR_EXPONENT)
                    h_abs *= min(1.0, factor) if rejected else factor
                    break
                h_abs *= max(dop853.MIN_FACTOR, dop853.SAFETY * error ** dop853.ERROR_EXPONENT)
                rejected = True
            accepted += 1
            t = t_new
            norm = 0.0
            for m in range(6, 12):
                norm += y_new[m, 0] * y_new[m, 0]
            norm = np.sqrt(norm)
            for m in range(n):
                y[m, 0] = y_new[m, 0] / norm if 6 <= m < 12 else y_new[m, 0]
            log_norm += np.log(norm)
            best = max(best, log_norm)
            worst = max(worst, abs(_nutation(y[5, 0]) - theta0))
            _augmented_block(t - t_out[0], y, P, f, 1)  # δ rescaled: its derivative too
        if every or i == t_out.size - 1:
            megno[i if every else 0] = y[13, 0] / (t - t_out[0])
    if not np.isfinite(log_norm + y[0, 0] + y[1, 0] + y[2, 0] + y[12, 0] + y[13, 0]):
        return _dop853_failed(megno, fli, deviation, final, steps, j)
    fli[j] = best
    deviation[j] = worst
    final[:] = y[0:6, 0]
    steps[j] = accepted
    return 0


@kernel
def _dop853_failed(megno, fli, deviation, final, steps, j):
    megno[1:] = np.nan
    megno[-1] = np.nan
    fli[j] = deviation[j] = np.nan
    final[:] = np.nan
    steps[j] = 0
    return 1


@kernel
def section_crossings(p, y0, h, n_steps, level, out):
    """Upward crossings of γ3 = level by one trajectory (RK4, step h, n_steps steps), at most len(out).

    Each crossing is located by the cubic Hermite interpolant of the step (values and derivatives at
    both ends: error O(h⁴), the order of RK4) and refined by bisection on it; out[k] = (t, ω, γ) there.
    Returns the number of crossings recorded.
    """
    y = y0.copy()
    k1, k2, k3, k4, tmp = np.empty(6), np.empty(6), np.empty(6), np.empty(6), np.empty(6)
    f0, f1, prev = np.empty(6), np.empty(6), np.empty(6)
    found = 0
    rhs(0.0, y, p, f0)
    for step in range(n_steps):
        prev[:] = y
        rhs(0.0, y, p, k1)
        for m in range(6):
            tmp[m] = y[m] + 0.5 * h * k1[m]
        rhs(0.0, tmp, p, k2)
        for m in range(6):
            tmp[m] = y[m] + 0.5 * h * k2[m]
        rhs(0.0, tmp, p, k3)
        for m in range(6):
            tmp[m] = y[m] + h * k3[m]
        rhs(0.0, tmp, p, k4)
        for m in range(6):
            y[m] += (h / 6.0) * (k1[m] + 2.0 * k2[m] + 2.0 * k3[m] + k4[m])
        rhs(0.0, y, p, f1)
        if prev[5] < level <= y[5]:
            lo, hi = 0.0, 1.0
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if _hermite(prev[5], y[5], f0[5], f1[5], h, mid) < level:
                    lo = mid
                else:
                    hi = mid
            u = 0.5 * (lo + hi)
            out[found, 0] = (step + u) * h
            for m in range(6):
                out[found, 1 + m] = _hermite(prev[m], y[m], f0[m], f1[m], h, u)
            found += 1
            if found == out.shape[0]:
                return found
        if not np.isfinite(y[5]):
            return found
        f0[:] = f1
    return found


@inline_kernel
def _hermite(y0, y1, f0, f1, h, u):
    """Cubic Hermite interpolant on a step of length h at fraction u."""
    u2 = u * u
    u3 = u2 * u
    return ((2 * u3 - 3 * u2 + 1) * y0 + (u3 - 2 * u2 + u) * h * f0 + (-2 * u3 + 3 * u2) * y1
            + (u3 - u2) * h * f1)
