"""A double-double head (``Taylor(head=...)``: the state's update and the series' first ``head`` orders in
double-double, the rest in double): as the error estimate's companion near double precision's floor, against the whole
series in double-double, and in ``auto``'s own run near the floor, whose one pass then measures its round-off.

    python benchmarks/companion_head.py          # four scenes (~40 s)

Each scene runs at tol 1e-18 (the companion's tolerance at ε = 1e-13 on the reference scene is 7.4e-19), heads 0 … 6,
against double-double at tol 1e-28 (the reference) and at tol 1e-18 (the companion it replaces). Printed: the final
max-norm error in ulps of the state's size and the CPU time (minimum of 5). ``HEAD_ORDERS`` (gyrolab.accuracy.
calibration) is supported when, on every scene, that head ends within 2 ulps of the reference (as double-double at the
same tolerance does) or 10× closer than double precision (head 0), the run it measures, in at most a third of
double-double's time.

Then the round-off a head run measures of itself (``OwnEstimate.roundoff``: the ulps of each step's terms computed in
double, added up): each scene at tol 1e-13 … 2e-16, heads 1 … ``HEAD_ORDERS``, against the same steps with an 8-order
head (the same truncation error; round-off far below). ``HEAD_WALK`` is supported when every distance is within it
times that measure amplified by the growth of perturbations, plus an ulp. Last, the head companion on the chaotic top
over t = 200, whose perturbations grow ~10¹⁰: ``HEAD_COMPANION_GROWTH`` is supported when it lies between the growths
of the scenes above (their head companion as above) and that one's (its head companion far off).
"""

from __future__ import annotations

import time

import numpy as np

import math

from gyrolab import compose_scene
from gyrolab.accuracy import calibration as table
from gyrolab.accuracy.amplification import EPS
from gyrolab.accuracy.auto import measured_order
from gyrolab.kernels import series_dd, taylor_dd
from gyrolab.plugins.integrators.compiled_solvers import Taylor

SCENES = {
    "reference scene, t = 300": ["experiment=perf_reference"],
    "chaotic top (slow_spin), t = 60": ["initial=slow_spin", "time.end=60", "time.n_output=601"],
    # promise_audit.py --seed 2026, scene 82: a fast asymmetric top whose round-off adds up coherently (1/I's rounding)
    "fast asymmetric top (audit scene 82), t = 48.8": [
        "body.a=1.3241", "body.b=0.9081", "body.com_direction=[0.5033034681080145,-0.3989679978049124,-0.7664921106691082]",
        "force=[uniform_gravity]", "initial.theta0=1.16621", "initial.phi0=0.555892", "initial.psi0=4.56161",
        "initial.r0=11.8878", "initial.p0=-0.03959", "initial.q0=-0.2597", "time.end=48.787", "time.n_output=101"],
    "gyrostat on a circular orbit, t = 50": ["body=gyrostat_symmetric", "initial=gyrostat_precession",
                                             "force=[newtonian]", "force.newtonian.k=null", "time.end=50",
                                             "time.n_output=501"],
}
TOL, HEADS, ULPS, SHARE, SHARPER = 1e-18, range(7), 2.0, 1 / 3, 10.0
RUN_TOLERANCES, REFERENCE_HEAD = (1e-13, 1e-14, 1e-15, 2e-16), 8
#: the docs' chaotic top (tests/helpers/accuracy.CHAOTIC_TOP) over t = 200
AMPLIFIED = ["initial.theta0=1", "initial.r0=2", "initial.p0=0.3", "initial.q0=-0.2", "time.end=200", "time.n_output=201"]


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
        (ulps, cost), (_, whole), (double, _) = costs[table.HEAD_ORDERS], costs[None], costs[0]
        held &= ulps <= max(ULPS, double / SHARPER) and cost <= SHARE * whole
        what.append(f"{name}: {ulps:.2g} ulp (double {double:.3g}) in {cost / whole:.2f} of double-double's time")
    walked, growth = head_walks()
    amplified = amplified_companion()
    supported = table.report(table.HEAD, {
        "HEAD_ORDERS": (held, "; ".join(what)),
        "HEAD_WALK": (walked <= table.HEAD_WALK, f"a head run's distance from an {REFERENCE_HEAD}-order head's ≤ "
                                                 f"{walked:.2f}× its measured round-off amplified, plus an ulp"),
        "HEAD_COMPANION_GROWTH": (growth <= table.HEAD_COMPANION_GROWTH < amplified[0] and amplified[1] > 1e3, (
            f"the scenes above grow ≤ {growth:.3g}× (head companion as above), the chaotic top "
            f"{amplified[0]:.3g}× (head companion {amplified[1]:.3g} ulps off)"))})
    raise SystemExit(0 if supported else 1)


def head_walks() -> tuple[float, float]:
    """(the largest distance of a head run from the same steps with REFERENCE_HEAD orders, over its measured round-off
    amplified plus an ulp; the largest growth of perturbations) over the scenes and RUN_TOLERANCES."""
    print(f"\n| scene | tol | growth | distance from head {REFERENCE_HEAD} / (measured round-off × growth + ulp), heads "
          f"1 … {table.HEAD_ORDERS} |\n| --- | --- | --- | --- |")
    worst, growths = 0.0, []
    for name, overrides in SCENES.items():
        scene = compose_scene([*overrides, "integrator=taylor", "output.euler_angles=false"])
        series_dd.ready(scene.compiled)
        y0 = scene.system.initial_state()
        ulp = float(np.spacing(max(1.0, float(np.max(np.abs(y0))))))
        for tol in RUN_TOLERANCES:
            order = measured_order(tol)

            def run(head):
                return Taylor(tol=tol, order=order, head=head).integrate(None, scene.times, y0, None, scene.compiled,
                                                                         estimate=True)

            reference = run(REFERENCE_HEAD).y
            ratios = []
            for head in range(1, table.HEAD_ORDERS + 1):
                measured = run(head)
                growth = math.exp(measured.estimate.log_growth[-1])
                ratios.append(float(np.max(np.abs(measured.y - reference))) / (
                    EPS * measured.estimate.roundoff * growth + ulp))
            growths.append(growth)
            worst = max(worst, *ratios)
            print(f"| {name} | {tol:.0e} | {growth:.3g} | {' · '.join(f'{r:.2f}' for r in ratios)} |")
    return worst, max(growths)


def amplified_companion() -> tuple[float, float]:
    """(growth of perturbations, the head companion's error in ulps) on the chaotic top over t = 200."""
    scene = compose_scene([*AMPLIFIED, "integrator=taylor", "output.euler_angles=false"])
    series_dd.ready(scene.compiled)
    y0 = scene.system.initial_state()
    truth, _ = taylor_dd.propagate(scene.compiled.params, 1e-28, scene.times, y0)
    run = Taylor(tol=TOL, head=table.HEAD_ORDERS).integrate(None, scene.times, y0, None, scene.compiled,
                                                               estimate=True)
    ulps = float(np.max(np.abs(run.y - truth))) / float(np.spacing(max(1.0, float(np.max(np.abs(y0))))))
    growth = math.exp(run.estimate.log_growth[-1])
    print(f"\nchaotic top over t = 200: perturbations grow {growth:.3g}×; the head companion ends {ulps:.3g} ulps off")
    return growth, ulps


if __name__ == "__main__":
    main()
