"""Near the Taylor method's floor, when may the error estimate trust a double companion? (``error_estimate``)

A double-precision Taylor run at tol < 1e-12 may err partly by round-off, which a double companion shares in size.
``gyrolab.accuracy.estimate`` measures it one rung up (a double-double head, or double-double: printed here as the
double-double companion); only for a model without a double-double series (``estimate._double_pair``) does it run two
double companions (``TIGHTER`` times tighter; the run's order, and another order with the rounded numbers moved) and
keep the first one's measurement E when their disagreement R is ``ROUNDOFF_MARGIN`` times below it (until
2026-11-30 for every model: two such agreed within 6.8e-14 where both were 3e-13 from real128, docs/integrators.md,
"Double companions retired"). This measures that rule against the
truth: on random scenes (``promise_audit.random_scene``) and tolerances from 3e-13 to 1.5e-16, E, R and the actual
error (max-norm over every output time and component, against heyoka ``real128``), and for each margin M the
smallest E / actual among the runs it would trust (R · M ≤ E). The estimate's promise is E / actual ≥ 1/2.
It also measures the single double companion (E alone) at each tolerance: the runs whose companion tol is at least
``DOUBLE_DOUBLE_BELOW`` are measured by it alone, without the second companion. And the rule that comes first for the
Taylor method's own estimate (``estimate.one_pass``, C8): where its round-off bound is not trusted, the pass's estimate
P stands when a twin run (the same tolerance and order, the model's rounded numbers moved by an ulp) differs from the
run by a T that is ``ROUNDOFF_MARGIN`` times below P (tried only where the unamplified walk W is as far below P and
the bound, W amplified by the growth of perturbations, is at most P);
measured per output time, P and W in quadrature against the actual error.

    pip install -e ".[bench]"
    python benchmarks/roundoff_margin.py --n 120 --seed 5     # ~5 min
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numpy as np

from gyrolab import compose_scene
from gyrolab.accuracy.amplification import EPS, PILOT_FRACTION, growth_of
from gyrolab.accuracy.calibration import CHAOS_MARGIN, DOUBLE_DOUBLE_BELOW, ROUNDOFF_MARGIN, TIGHTER
from gyrolab.kernels.model import rounding_moved
from gyrolab.kernels.taylor import MAX_ORDER
from gyrolab.plugins.integrators.compiled_solvers import Taylor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from promise_audit import SATURATED, random_scene  # noqa: E402  (benchmarks/ is not a package)
from real128_reference import Real128Reference, covered  # noqa: E402

TOLERANCES = (3e-13, 1e-13, 3e-14, 1e-14, 3e-15, 1e-15, 1.5e-16)
MARGINS = (2.0, 4.0, 6.0, 10.0, 20.0, 50.0)
#: an actual error below this × max(1, |y0|) is at the reference's own level: not judged
RESOLVED = 1e-15


def measure(scene, tol: float) -> tuple[float, float, np.ndarray, dict]:
    """(E, R, the run's states, the one pass's measures) of the Taylor method at ``tol`` on ``scene``, as
    ``error_estimate.compare`` measures them near the floor; the one pass's: P and W at every output time, T and the
    amplified walk B (the pass's round-off bound)."""
    y0, times = scene.system.initial_state(), scene.times
    run = Taylor(tol=tol)
    double_tol = max(tol / TIGHTER, Taylor.TOLERANCE_FLOOR)
    other = run.order + 2 if run.order + 2 <= MAX_ORDER else run.order - 2
    measured = run.integrate(None, times, y0, None, scene.compiled, estimate=True)
    y = measured.y
    first = Taylor(order=run.order, tol=double_tol).integrate(None, times, y0, None, scene.compiled).y
    second = Taylor(order=other, tol=double_tol).integrate(None, times, y0, None, rounding_moved(scene.compiled)).y
    twin = run.integrate(None, times, y0, None, rounding_moved(scene.compiled)).y
    scale = max(1.0, float(np.max(np.abs(y))))
    walk = EPS * scale * np.sqrt(1.0 + measured.estimate.steps * (times - times[0]) / (times[-1] - times[0]))
    growth = math.exp(min(float(measured.estimate.log_growth[-1]), 700.0))  # (estimate.one_pass's bound, unless chaotic)
    chaotic = growth_of(measured.estimate, float(times[-1] - times[0])).chaotic(PILOT_FRACTION)
    own = {"P": np.abs(measured.estimate.error).max(axis=1), "W": walk, "T": float(np.max(np.abs(twin - y))),
           "B": float(walk[-1]) * growth * (CHAOS_MARGIN if chaotic else 1.0)}
    return float(np.max(np.abs(y - first))), float(np.max(np.abs(first - second))), y, own


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=120)
    parser.add_argument("--seed", type=int, default=5)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    reference = Real128Reference()
    rows = []  # (scene, tol, E, R, actual)
    passes = []  # (trusted by the twin rule, smallest and largest estimate / actual over the output times judged)
    for index in range(args.n):
        spec = random_scene(rng, index)
        scene = compose_scene(["integrator=taylor", "time.n_output=101", "output.euler_angles=false", *spec.overrides])
        if not covered(scene):
            continue
        truth = reference.states(scene)
        scale = max(1.0, float(np.max(np.abs(scene.system.initial_state()))))
        for tol in TOLERANCES:
            estimate, roundoff, y, own = measure(scene, tol)
            actual = float(np.max(np.abs(y - truth)))
            if RESOLVED * scale < actual < SATURATED:
                rows.append((index, tol, estimate, roundoff, actual))
                largest = float(own["P"].max())
                trusted = ROUNDOFF_MARGIN * max(float(own["W"][-1]), own["T"]) <= largest and own["B"] <= largest
                at = np.abs(y - truth).max(axis=1)
                judged = at > RESOLVED * scale
                ratio_pass = np.hypot(own["P"], own["W"])[judged] / at[judged]
                passes.append((trusted, float(ratio_pass.min()), float(ratio_pass.max())))
                if estimate >= ROUNDOFF_MARGIN * roundoff and estimate < actual / 2:  # trusted, and more than 2× low
                    dd = Taylor(tol=max(tol / TIGHTER, 1e-30), precision="double-double")
                    exact = float(np.max(np.abs(y - dd.integrate(None, scene.times, scene.system.initial_state(),
                                                                 None, scene.compiled).y)))
                    print(f"  scene {index} tol {tol:g}: E {estimate:.3g}, R {roundoff:.3g}, actual {actual:.3g}, "
                          f"double-double companion {exact:.3g}", flush=True)
        print(f"scene {index}: {len(rows)} runs judged so far", flush=True)
    rows = np.array(rows)
    ratio, trust = rows[:, 2] / rows[:, 4], rows[:, 2] / np.maximum(rows[:, 3], 1e-300)
    print(f"\n{len(rows)} runs (seed {args.seed}, {args.n} scenes, tol {TOLERANCES[0]:g} … {TOLERANCES[-1]:g}); "
          f"current ROUNDOFF_MARGIN = {ROUNDOFF_MARGIN:g}\n")
    print("| margin M | runs trusted (R · M ≤ E) | smallest E / actual among them | trusted with E / actual < 1/2 |")
    print("| --- | --- | --- | --- |")
    for margin in MARGINS:
        kept = trust >= margin
        worst = float(ratio[kept].min()) if kept.any() else float("nan")
        print(f"| {margin:g} | {int(kept.sum())} of {len(rows)} | {worst:.3g} | {int((ratio[kept] < 0.5).sum())} |")
    print("\nthe double estimate alone (no margin): smallest E / actual "
          f"{float(ratio.min()):.3g}, {int((ratio < 0.5).sum())} of {len(rows)} below 1/2")
    print("\n| run tol | runs | E / actual min | max | below 1/2 | above 2 |\n| --- | --- | --- | --- | --- | --- |")
    for tol in TOLERANCES:
        at = ratio[rows[:, 1] == tol]
        if at.size:
            print(f"| {tol:g} | {at.size} | {at.min():.3g} | {at.max():.3g} | {int((at < 0.5).sum())} | "
                  f"{int((at > 2).sum())} |")
    passes = np.array(passes)
    twin_trusted = passes[passes[:, 0] == 1.0]
    twin_low = int((twin_trusted[:, 1] < 0.5).sum())
    print(f"\nthe one pass where the twin rule trusts it (M = {ROUNDOFF_MARGIN:g}): {len(twin_trusted)} of {len(passes)} "
          f"runs; its estimate / actual over their output times {twin_trusted[:, 1].min():.3g} … "
          f"{twin_trusted[:, 2].max():.3g}, {twin_low} runs below 1/2 at some output time, "
          f"{int((twin_trusted[:, 2] > 2).sum())} above 2")
    from gyrolab.accuracy import calibration as table

    trusted = trust >= ROUNDOFF_MARGIN
    low = int((ratio[trusted] < 0.5).sum())
    alone = ratio[rows[:, 1] / TIGHTER >= DOUBLE_DOUBLE_BELOW]
    off = int(((alone < 0.5) | (alone > 2)).sum())
    supported = table.report(table.ROUNDOFF, {
        "ROUNDOFF_MARGIN": (low <= max(1, len(rows) // 1000) and twin_low <= max(1, len(passes) // 1000),
                            f"{low} of {int(trusted.sum())} trusted estimates below 1/2 of the error; by the one pass's "
                            f"twin rule {twin_low} of {len(twin_trusted)} below 1/2 at some output time"),
        "DOUBLE_DOUBLE_BELOW": (off == 0, f"{off} of {alone.size} runs whose companion tol is ≥ {DOUBLE_DOUBLE_BELOW:g} "
                                          f"measured outside 1/2 … 2× by it alone (E / actual {alone.min():.3g} … "
                                          f"{alone.max():.3g})" if alone.size else "no run that tolerance")})
    return 0 if supported else 1


if __name__ == "__main__":
    sys.exit(main())
