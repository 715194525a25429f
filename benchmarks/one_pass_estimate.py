"""Issue 32 item 3: the Taylor run's one-pass error estimate (``taylor.run_measured``), against the long-double
reference at every output time, and its growth of perturbations against the generated tangent run's.

    python benchmarks/one_pass_estimate.py          # five scenes × four tolerances (~1 min)

Each scene runs ``integrator=taylor`` at tol 1e-6 … 1e-12 with ``estimate=True``; printed: the estimated over the
actual max-norm error of (ω, γ) at every output time where the actual one is above round-off (1e-13 × the state's
size), and ln|δ| of the run's tangent vector beside the compiled DOP853 tangent run's (``amplification``). The
constants of the kernel it rests on are gyrolab.accuracy.calibration's ONE_PASS entries, reported at the end: the
series' extra orders and the error's tangent order hold when every ratio is within 2×, the tangent vector's series
(shorter at tighter tolerances) when a scene's growth moves by at most 0.25 in ln|δ| across the tolerances. (The
tangent run's ln|δ| is printed for comparison, not judged; both follow (ω, γ), not the fixed axis α: 1.82 and 1.82
near the vertical, where the run's vector following α too measured 3.41.) (The numpy prototype that chose the design before the kernel
was built is in the git history of this file; its tables: docs/performance.md, "A one-pass estimate".)
"""

from __future__ import annotations

import math

import numpy as np

from gyrolab import compose_scene
from gyrolab.accuracy import calibration as table
from gyrolab.accuracy.amplification import amplification
from gyrolab.kernels import layout, taylor
from gyrolab.physics.reference import fixed_point_reference
from gyrolab.plugins.integrators.compiled_solvers import Taylor

SCENES = {
    "reference scene, t = 300": ["experiment=perf_reference"],
    # a long step's truncation error is a slowly converging tail: two extra terms underestimated it 2.3×
    "slow top r0 = 0.1, t = 100": ["initial.r0=0.1", "time.end=100", "time.n_output=1001"],
    "fast top r0 = 30, t = 50": ["initial.r0=30", "time.end=50", "time.n_output=1001"],
    "near the vertical θ0 = 0.05, t = 100": ["initial.theta0=0.05", "time.end=100", "time.n_output=1001"],
    # a fast top over a long span (audit seed 5, scene 93): the error's tangent series at order 6 drifted to 2× by t = 185
    "fast top r0 = 15, t = 185": ["body.a=1.0957", "body.b=0.8801", "force=[uniform_gravity,newtonian]",
                                  "body.com_direction=[0.724458555891383,-0.679038787806991,-0.1186006975080002]",
                                  "force.newtonian.k=0.6416", "initial.theta0=1.51897", "initial.phi0=2.35697",
                                  "initial.psi0=1.05148", "initial.r0=15.1691", "initial.p0=0.02356", "initial.q0=-0.13",
                                  "time.end=184.78", "time.n_output=1001"],
}
TOLERANCES = (1e-6, 1e-8, 1e-10, 1e-12)
ESTIMATE_FACTOR, GROWTH_SPREAD = 2.0, 0.25
#: a run whose error grows beyond this fraction of the state's size has lost the trajectory: the linearised error
#: equation no longer describes it, and its tangent vector follows another trajectory (the fast top r0 = 15 at tol
#: 1e-6 ends 0.25 away); such a run is printed, not judged (promise_audit.py calls it saturated)
LOST = 1e-3
#: the tangent vector's growth is compared across the tolerances on runs this close to the true trajectory (relative
#: to the state's size): a run farther off follows another trajectory, whose growth differs (the fast top r0 = 15 at
#: tol 1e-8, 8e-4 away: e^8.93 where the runs within 4e-6 measure e^8.49–8.56)
SAME = 1e-6


def main() -> None:
    print("| scene | tol | steps | actual, largest | estimate / actual, every output time | ln|δ| run | ln|δ| tangent run |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    worst_ratio, worst_growth = (math.inf, 0.0), 0.0
    for name, overrides in SCENES.items():
        scene = compose_scene(overrides)
        p = scene.system.compiled_model().built_in
        y0, times = scene.system.initial_state(), scene.times
        truth = fixed_point_reference(p[layout.INERTIA:layout.INERTIA + 3], p[layout.U_Z:layout.U_Z + 3],
                                      p[layout.N_Z], y0[:6], times).astype(float)
        tangent = amplification(scene.compiled_model, None, y0, times[0], times[0] + 0.1 * (times[-1] - times[0]),
                                times[-1], None)
        growths = []
        for tol in TOLERANCES:
            run = Taylor(tol=tol).integrate(None, times, y0, None, scene.compiled_model, estimate=True)
            actual = np.abs(run.y[:, :6] - truth).max(axis=1)
            estimated = np.abs(run.estimate.error[:, :6]).max(axis=1)
            size = max(1.0, float(np.max(np.abs(y0))))
            lost = actual.max() > LOST * size
            judged = actual > 1e-13 * size
            ratio = estimated[judged] / actual[judged] if judged.any() else np.array([math.nan])
            if judged.any() and not lost:
                worst_ratio = (min(worst_ratio[0], ratio.min()), max(worst_ratio[1], ratio.max()))
            growth = float(run.estimate.log_growth[-1])
            growths += [growth] if actual.max() <= SAME * size else []
            print(f"| {name} | {tol:.0e} | {run.estimate.steps} | {actual.max():.2e} | {ratio.min():.2f} – "
                  f"{ratio.max():.2f}{' (lost: not judged)' if lost else ''} | {growth:.2f} | {tangent.log_span:.2f} |")
        worst_growth = max(worst_growth, max(growths, default=0.0) - min(growths, default=0.0))
    held = worst_ratio[0] >= 1 / ESTIMATE_FACTOR and worst_ratio[1] <= ESTIMATE_FACTOR
    what = f"estimate / actual {worst_ratio[0]:.2f} – {worst_ratio[1]:.2f} over every output time above round-off"
    assert (table.EXTRA_ORDERS, table.TANGENT_ORDER, table.GROWTH_PER_STEP) == (
        taylor.EXTRA_ORDERS, taylor.TANGENT_ORDER, taylor.GROWTH_PER_STEP), "the kernel's constants are not the table's"
    supported = table.report(table.ONE_PASS, {
        "EXTRA_ORDERS": (held, what), "TANGENT_ORDER": (held, what),
        "GROWTH_PER_STEP": (worst_growth <= GROWTH_SPREAD, f"a scene's ln|δ| moved by at most {worst_growth:.2f} "
                                                           f"across the tolerances whose runs end within {SAME:g} of "
                                                           "the state's size of the reference")})
    raise SystemExit(0 if supported else 1)


if __name__ == "__main__":
    main()
