"""scipy's RK23 (Bogacki–Shampine 3(2)) behind gyrolab's integrator contract (a gyrolab integrator plugin)."""

import time

import numpy as np
from scipy.integrate import solve_ivp

from gyrolab.contracts import Integrator, IntegratorStats, Solution
from gyrolab.errors import IntegrationError, as_number


class ScipyRK23(Integrator):
    name = "scipy_rk23"
    adaptive = True                       # rtol/atol control the step
    capabilities = frozenset()            # no compiled model, no batch kernel: it integrates the Python rhs

    def __init__(self, *, rtol=1e-6, atol=1e-9):   # keyword defaults are the plugin's config
        self.rtol = as_number(rtol, "integrator.rtol", positive=True)
        self.atol = as_number(atol, "integrator.atol", positive=True)

    def integrate(self, fun, t_out, y0, progress=None, compiled=None):
        start = time.perf_counter()
        t_out = np.asarray(t_out, dtype=float)

        latest = [t_out[0]]               # where the solver got to (with t_eval, done.t holds only the output times)

        def fun_seen(t, y):               # progress on every evaluation is cheap: the callback rate-limits itself
            latest[0] = t
            if progress is not None:
                progress(t)
            return fun(t, y)

        # t_eval lands the samples on the requested times (dense output of each step, nothing else stored)
        with np.errstate(over="ignore", invalid="ignore"):   # a blow-up is reported below, in one sentence
            done = solve_ivp(fun_seen, (t_out[0], t_out[-1]), np.array(y0, dtype=float), method="RK23",
                             t_eval=t_out, rtol=self.rtol, atol=self.atol)
        if done.status != 0 or done.y.shape[1] != len(t_out) or not np.all(np.isfinite(done.y)):
            raise IntegrationError(f"scipy_rk23 stopped near t={latest[0]:.6g} of {t_out[-1]:.6g} with rtol="
                                   f"{self.rtol:g}: {done.message if done.status else 'the state became non-finite'}")
        y = done.y.T.copy()
        y[0] = y0                         # t_out[0] is the initial time: the state there is y0 itself
        # solve_ivp does not report steps: each attempt costs 3 evaluations after the 2 that choose the first step
        stats = IntegratorStats(nfev=int(done.nfev), n_steps=max(1, (int(done.nfev) - 2) // 3), n_rejected=None,
                                wall_time=time.perf_counter() - start)
        return Solution(t=t_out, y=y, stats=stats)

    def attributes(self):                 # stored in run.nc as integrator_rtol, integrator_atol
        return {"integrator_rtol": self.rtol, "integrator_atol": self.atol}
