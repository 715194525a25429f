"""An independent reference for the fixed-point scenes: heyoka's Taylor integrator in quadruple precision.

The Euler–Poisson equations of a heavy body about a fixed point with the torques about the vertical that the
papers use — uniform gravity U × γ (U = M g r_c) and a Newtonian centre on the fixed Z axis, N γ × Iγ — written
here from the papers, not from gyrolab's kernels, integrated by heyoka with ``fp_type=real128`` at tol 1e-30.
1/I enters as real128 numbers: heyoka turns a division by a constant into a product by its reciprocal rounded to
double otherwise, which moves the reference by ~5e-8 on chaotic scenes (benchmarks/chaos_promise.py).

``reference(scene)`` (the final (ω, γ)) is what benchmarks/chaos_promise.py has always computed;
``Real128Reference`` compiles the system once with the body's constants as runtime parameters, so that an audit of
many random scenes (benchmarks/promise_audit.py) pays heyoka's compilation once, and returns the whole state —
(ω, γ) and, where the scene carries it, the fixed horizontal axis α (α̇ = α × ω, like γ) — at every output time.
Scenes with torques on the horizontal axes (``layout.torques_on_horizontal_axes``) are outside these equations.
"""

from __future__ import annotations

import numpy as np

from gyrolab.kernels import layout

TOL = "1e-30"


def reference(scene) -> np.ndarray:
    """The final (ω, γ) in real128 (heyoka, tol 1e-30) on equations written from the papers."""
    import heyoka as hy

    p = scene.system.compiled_model().built_in
    A, B, C = (float(p[layout.INERTIA + k]) for k in range(3))
    U1, U2, U3 = (float(p[layout.U_Z + k]) for k in range(3))
    N = float(p[layout.N_Z])
    w1, w2, w3, g1, g2, g3 = hy.make_vars("w1", "w2", "w3", "g1", "g2", "g3")
    # 1/I as a real128 constant: heyoka turns a division by a constant into a product by its reciprocal rounded
    # to double otherwise, which moves this reference by ~5e-8 on the chaotic scenes
    inv_A, inv_B, inv_C = (hy.expression(hy.real128(1) / hy.real128(x)) for x in (A, B, C))
    system = [(w1, ((B - C) * w2 * w3 + U2 * g3 - U3 * g2 + N * (C - B) * g2 * g3) * inv_A),
              (w2, ((C - A) * w3 * w1 + U3 * g1 - U1 * g3 + N * (A - C) * g3 * g1) * inv_B),
              (w3, ((A - B) * w1 * w2 + U1 * g2 - U2 * g1 + N * (B - A) * g1 * g2) * inv_C),
              (g1, g2 * w3 - g3 * w2), (g2, g3 * w1 - g1 * w3), (g3, g1 * w2 - g2 * w1)]
    y0 = np.array(scene.system.initial_state()[:6], dtype=hy.real128)
    ta = hy.taylor_adaptive(system, y0, tol=hy.real128(TOL), fp_type=hy.real128)
    ta.propagate_until(hy.real128(float(scene.times[-1])))
    return np.array([float(v) for v in ta.state])


def covered(scene) -> bool:
    """Whether the scene is a fixed-point scene whose torques these equations hold (about the vertical only)."""
    compiled = scene.system.compiled_model()  # (built_in: every torque a built-in form, with α carried or not)
    return compiled is not None and compiled.built_in is not None \
        and not layout.torques_on_horizontal_axes(compiled.built_in)


class Real128Reference:
    """One compiled real128 integrator for every scene: the body's constants are heyoka runtime parameters."""

    def __init__(self) -> None:
        import heyoka as hy

        self.hy = hy
        w1, w2, w3, g1, g2, g3, a1, a2, a3 = hy.make_vars("w1", "w2", "w3", "g1", "g2", "g3", "a1", "a2", "a3")
        A, B, C, iA, iB, iC, U1, U2, U3, N = (hy.par[k] for k in range(10))
        system = [(w1, ((B - C) * w2 * w3 + U2 * g3 - U3 * g2 + N * (C - B) * g2 * g3) * iA),
                  (w2, ((C - A) * w3 * w1 + U3 * g1 - U1 * g3 + N * (A - C) * g3 * g1) * iB),
                  (w3, ((A - B) * w1 * w2 + U1 * g2 - U2 * g1 + N * (B - A) * g1 * g2) * iC),
                  (g1, g2 * w3 - g3 * w2), (g2, g3 * w1 - g1 * w3), (g3, g1 * w2 - g2 * w1),
                  (a1, a2 * w3 - a3 * w2), (a2, a3 * w1 - a1 * w3), (a3, a1 * w2 - a2 * w1)]
        self.ta = hy.taylor_adaptive(system, np.zeros(9, dtype=hy.real128), tol=hy.real128(TOL),
                                     fp_type=hy.real128, pars=np.zeros(10, dtype=hy.real128))

    def states(self, scene, times: np.ndarray | None = None) -> np.ndarray:
        """The state (ω, γ[, α]) at ``times`` (default: the scene's output times), one row per time, as doubles."""
        hy = self.hy
        if not covered(scene):
            raise ValueError("the real128 reference covers fixed-point scenes with torques about the vertical only")
        p = scene.system.compiled_model().built_in
        moments = [hy.real128(float(p[layout.INERTIA + k])) for k in range(3)]
        pars = [*moments, *(hy.real128(1) / m for m in moments),
                *(hy.real128(float(p[layout.U_Z + k])) for k in range(3)), hy.real128(float(p[layout.N_Z]))]
        y0 = np.asarray(scene.system.initial_state(), dtype=float)
        state = np.zeros(9)
        state[:len(y0)] = y0
        if len(y0) < 9:  # (ω, γ) only: α is integrated from an arbitrary axis ⟂ γ and dropped
            state[6:] = np.cross(y0[3:6], [1.0, 0.0, 0.0] if abs(y0[3]) < 0.9 else [0.0, 1.0, 0.0])
        ta = self.ta
        ta.pars[:] = np.array(pars, dtype=hy.real128)
        ta.state[:] = np.array([hy.real128(float(v)) for v in state], dtype=hy.real128)
        ta.time = hy.real128(0)
        grid = np.asarray(scene.times if times is None else times, dtype=float)
        # (outcome, min step, max step, steps, callback, states)
        outcome, *_, values = ta.propagate_grid(np.array([hy.real128(float(t)) for t in grid], dtype=hy.real128))
        values = np.asarray(values).astype(float)
        if outcome != hy.taylor_outcome.time_limit or values.shape != (len(grid), 9):
            raise RuntimeError(f"heyoka's real128 run stopped early ({outcome})")
        return values[:, :len(y0)]
