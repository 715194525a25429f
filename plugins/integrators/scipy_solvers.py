"""scipy's ODE solvers (``scipy.integrate``) behind gyrolab's integrator contract.

The solver is stepped directly (as ``solve_ivp`` does) so that gyrolab can count accepted and rejected steps, sample the
dense output only at the requested times, and stop with a clear error on a non-finite state. Rejected steps are known
for the explicit Runge–Kutta pairs: each attempt costs exactly ``n_stages`` evaluations, so the evaluations spent inside
one ``step()`` call count its attempts. Radau, BDF and LSODA do not expose them. ``dop853`` steps with scipy's DOP853
copied into numpy (``dop853_stepper``), the same steps bit for bit, so that the default run need not import
``scipy.integrate`` (~0.4 CPU s); the others import it when they first integrate.
"""

from __future__ import annotations

import time
import warnings
from typing import ClassVar

import numpy as np

from gyrolab.contracts.integrator import (TIME_DEPENDENT, VARIATIONAL, CompiledModel, Integrator, IntegratorStats,
                                          ProgressCallback, RightHandSide, Solution, VariationalSettings)
from gyrolab.errors import IntegrationError
from gyrolab.plugins.integrators import dop853_stepper
from gyrolab.plugins.integrators.tolerances import Tolerances


class ScipySolver(Tolerances, Integrator):
    """Adaptive scipy solver; subclasses name the scipy class."""

    adaptive = True
    capabilities = frozenset({TIME_DEPENDENT})
    #: the class of ``scipy.integrate`` that steps
    scipy_name: ClassVar[str]

    @property
    def solver_class(self) -> type:
        from scipy import integrate  # start-up: scipy.integrate imports scipy.optimize and scipy.special (~0.4 s)

        return getattr(integrate, self.scipy_name)

    def integrate(self, fun: RightHandSide, t_out: np.ndarray, y0: np.ndarray,
                  progress: ProgressCallback | None = None, compiled: CompiledModel | None = None) -> Solution:
        start = time.perf_counter()
        t_out = np.asarray(t_out, dtype=float)
        out = np.empty((len(t_out), len(y0)))
        out[0] = y0
        with warnings.catch_warnings():  # scipy warns when it raises rtol to its floor: said below, once
            warnings.simplefilter("ignore", UserWarning)
            solver = self.solver_class(fun, t_out[0], np.array(y0, dtype=float), t_out[-1],
                                       rtol=self.rtol, atol=self.atol, max_step=self.max_step)
        # scipy's Runge-Kutta, Radau and BDF solvers keep the tolerances they apply (raised to their floor);
        # LSODA hands them to ODEPACK unchanged
        self.record_used_tolerances(float(np.max(getattr(solver, "rtol", self.rtol))),
                                    float(np.max(getattr(solver, "atol", self.atol))))
        stages = getattr(solver, "n_stages", None)
        n_steps, n_rejected, filled = 0, 0, 1
        while solver.status == "running" and filled < len(t_out):
            nfev_before, t_before = solver.nfev, solver.t
            try:
                message = solver.step()
            except (ValueError, ArithmeticError, np.linalg.LinAlgError) as error:  # e.g. LU of a NaN Jacobian
                raise IntegrationError(f"{self.name} failed near t={solver.t:.6g}: {error}") from None
            if solver.status == "failed":
                raise IntegrationError(f"{self.name} failed near t={solver.t:.6g}: {message}")
            if solver.t == t_before:  # LSODA near a blow-up: its step size reaches 0 and it "succeeds" forever
                raise IntegrationError(f"{self.name} stalled at t={solver.t:.6g}: its step size fell to zero "
                                       "(a singularity of the solution?)")
            if not np.all(np.isfinite(solver.y)):
                raise IntegrationError(f"{self.name} produced a non-finite state at t={solver.t:.6g}")
            n_steps += 1
            if stages:
                n_rejected += (solver.nfev - nfev_before) // stages - 1
            if progress is not None:
                progress(solver.t)
            reached = int(np.searchsorted(t_out, solver.t, side="right"))
            if reached > filled:
                dense = solver.dense_output()
                out[filled:reached] = dense(t_out[filled:reached]).T
                filled = reached
        if solver.t == t_out[-1]:
            out[-1] = solver.y  # the solver lands on t_bound exactly: no interpolation error at the end
        stats = IntegratorStats(nfev=solver.nfev, n_steps=n_steps, n_rejected=n_rejected if stages else None,
                                wall_time=time.perf_counter() - start, njev=solver.njev, nlu=solver.nlu)
        return Solution(t=t_out, y=out, stats=stats)


class RK45(ScipySolver):
    name = "rk45"
    scipy_name = "RK45"


class DOP853(ScipySolver):
    name = "dop853"
    # the chaos indicators' compiled DOP853 takes scipy's steps (dop853_numba is scipy's method, compiled)
    capabilities = frozenset({TIME_DEPENDENT, VARIATIONAL})
    solver_class = dop853_stepper.DOP853

    def variational_settings(self) -> VariationalSettings:
        return VariationalSettings(rtol=self.rtol, atol=self.atol, max_step=self.max_step)


class LSODA(ScipySolver):
    name = "lsoda"
    scipy_name = "LSODA"


#: scipy's implicit solvers stop their Newton iterations at max(10 ε / rtol, min(0.03, √rtol)), which loosens below
#: (10 ε)^(2/3) ≈ 1.7e-10: a tighter run is then not more accurate, and their error estimate takes the compiled Taylor
#: method's stand-in (docs/integrators.md, "scipy's Radau stalls")
IMPLICIT_NEWTON_FLOOR = (10 * float(np.finfo(float).eps)) ** (2.0 / 3.0)


class Radau(ScipySolver):
    name = "radau"
    scipy_name = "Radau"
    tolerance_floor = IMPLICIT_NEWTON_FLOOR


class BDF(ScipySolver):
    name = "bdf"
    scipy_name = "BDF"
    tolerance_floor = IMPLICIT_NEWTON_FLOOR
