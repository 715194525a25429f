"""The error estimate's companion near double precision's floor: the Taylor method with its state and only the series'
first ``head`` orders in double-double (``Taylor(head=...)``), against the whole series in double-double.

    python benchmarks/companion_head.py          # three scenes × heads 0 … 6 (~20 s)

Each scene runs at tol 1e-18 (the companion's tolerance at ε = 1e-13 on the reference scene is 7.4e-19), heads 0 … 6,
against double-double at tol 1e-28 (the reference) and at tol 1e-18 (the companion it replaces). Printed: the final
max-norm error in ulps of the state's size and the CPU time (minimum of 5). ``COMPANION_HEAD`` (gyrolab.accuracy.
calibration) is supported when, on every scene, that head ends within 2 ulps of the reference, as double-double at the
same tolerance does, in at most a third of its time.
"""

from __future__ import annotations

import time

import numpy as np

from gyrolab import compose_scene
from gyrolab.accuracy import calibration as table
from gyrolab.kernels import series_dd, taylor_dd
from gyrolab.plugins.integrators.compiled_solvers import Taylor

SCENES = {
    "reference scene, t = 300": ["experiment=perf_reference"],
    "chaotic top (slow_spin), t = 60": ["initial=slow_spin", "time.end=60", "time.n_output=601"],
    "gyrostat on a circular orbit, t = 50": ["body=gyrostat_symmetric", "initial=gyrostat_precession",
                                             "force=[newtonian]", "force.newtonian.k=null", "time.end=50",
                                             "time.n_output=501"],
}
TOL, HEADS, ULPS, SHARE = 1e-18, range(7), 2.0, 1 / 3


def _timed(method, scene, y0):
    best, y = np.inf, None
    for _ in range(5):
        start = time.process_time()
        y = method.integrate(None, scene.times, y0, None, scene.compiled).y
        best = min(best, time.process_time() - start)
    return y, best


def main() -> None:
    print(f"| scene | {' | '.join(f'head {h}' for h in HEADS)} | double-double |")
    print(f"| --- |{' --- |' * (len(HEADS) + 1)}")
    held, what = True, []
    for name, overrides in SCENES.items():
        scene = compose_scene([*overrides, "integrator=taylor", "output.euler_angles=false"])
        series_dd.ready(scene.compiled)
        y0 = scene.system.initial_state()
        truth, _ = taylor_dd.propagate(scene.compiled.params, 1e-28, scene.times, y0)
        ulp = float(np.spacing(max(1.0, float(np.max(np.abs(y0))))))
        cells, costs = [], {}
        for head in [*HEADS, None]:
            method = Taylor(tol=TOL, precision="double-double") if head is None else Taylor(tol=TOL, head=head)
            y, cost = _timed(method, scene, y0)
            ulps = float(np.max(np.abs(y - truth))) / ulp
            costs[head] = (ulps, cost)
            cells.append(f"{ulps:.3g} ulp, {cost * 1e3:.2f} ms")
        print(f"| {name} | {' | '.join(cells)} |")
        (ulps, cost), (_, whole) = costs[table.COMPANION_HEAD], costs[None]
        held &= ulps <= ULPS and cost <= SHARE * whole
        what.append(f"{name}: {ulps:.2g} ulp in {cost / whole:.2f} of double-double's time")
    supported = table.report(table.HEAD, {"COMPANION_HEAD": (held, "; ".join(what))})
    raise SystemExit(0 if supported else 1)


if __name__ == "__main__":
    main()
