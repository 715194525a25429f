"""Speed against accuracy on the reference problem: gyrolab against heyoka and scipy, measured interleaved.

    pip install -e ".[bench]"                      # heyoka (optional: its rows are skipped when absent)
    python benchmarks/perf_reference.py            # full tables (a few minutes)
    python benchmarks/perf_reference.py --quick    # fewer tolerances, fewer rounds
    python benchmarks/perf_reference.py --calibration  # only the measurement behind auto's CALIBRATION
    python benchmarks/perf_reference.py --breakdown --quick  # where auto's Scene.run() spends its time

Reference problem (issue 5, ``experiment=perf_reference``): nondimensional
Euler–Poisson, A, B, C = 2, 1.5, 1, r_c = (0.3, 0.2, 0.9327…), k = 0.5,
ω0 = (0.1, −0.05, 5), γ0 = (sin 1, 0, cos 1), t ∈ [0, 300], 3,001 output
times. Error = max-norm of the final state's error against an
extended-precision Taylor reference (``gyrolab.physics.reference``; two
settings of it agree to ~1e-14).

Peer: heyoka (LLVM Taylor integrator) with ``propagate_grid`` on the same 3,001
times (dense output from its Taylor polynomials), against gyrolab's ``taylor``
and ``auto`` integrating on that grid (``Integrator.integrate``) and the whole
``Scene.run()`` (dataset included). For a target error ε each method's time is
that of its cheapest setting whose final error is ≤ ε (``auto`` has one
setting per ε: ε itself). Every contestant runs once per round, rounds
interleave all of them (a shared machine slows all alike), and a contestant's
time is its minimum over the rounds; the peer table is printed again with the
rounds' medians. The scipy baseline is what a researcher
would write: ``solve_ivp`` with a plain numpy right-hand side.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_batch
from gyrolab.physics.reference import fixed_point_reference

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from results_file import write_results  # noqa: E402  (benchmarks/ is not a package)

INERTIA = np.array([2.0, 1.5, 1.0])
R_C = np.array([0.3, 0.2, 0.9327379053088815])
K = 0.5
Y0 = np.array([0.1, -0.05, 5.0, np.sin(1.0), 0.0, np.cos(1.0)])
T_END = 300.0


def plain_numpy_rhs(t, y):
    """The Euler–Poisson right-hand side as a careful researcher writes it for solve_ivp: component-wise
    (np.cross on 3-vectors would make scipy ~10× slower and every ratio below ~10× larger)."""
    A, B, C = INERTIA
    x0, y0, z0 = R_C
    p, q, r, g1, g2, g3 = y
    return np.array([((B - C) * q * r + y0 * g3 - z0 * g2 + K * (C - B) * g2 * g3) / A,
                     ((C - A) * r * p + z0 * g1 - x0 * g3 + K * (A - C) * g3 * g1) / B,
                     ((A - B) * p * q + x0 * g2 - y0 * g1 + K * (B - A) * g1 * g2) / C,
                     g2 * r - g3 * q, g3 * p - g1 * r, g1 * q - g2 * p])


GRID = np.linspace(0.0, T_END, 3001)
EPSILONS = [10.0 ** -k for k in range(6, 14)]
#: Tolerances 10^(-k/4): each method's cost to reach ε is read off its work-precision curve at this resolution (a
#: decade grid made the comparison hinge on where each curve crosses ε between two decades: up to ~1.2x either way).
QUARTER_DECADES = [10.0 ** (-k / 4) for k in range(72)]
#: heyoka's tolerances, its bare runs' and those doing auto's work alike (the latter are read at the former's choice)
PEER_TOLERANCES = QUARTER_DECADES[24:61] + [float(np.finfo(float).eps)]
WALL = False  # set by --wall
MEDIANS = {}  # contestant -> median time over the rounds of its last ``interleaved`` call


def heyoka_contestants():
    """{tolerance: propagate_grid callable returning the final state}, or {} when heyoka is not installed."""
    try:
        import heyoka as hy
    except ImportError:
        return {}
    A, B, C = INERTIA
    x0, y0, z0 = R_C
    p, q, r, g1, g2, g3 = hy.make_vars("p", "q", "r", "g1", "g2", "g3")
    system = [(p, ((B - C) * q * r + y0 * g3 - z0 * g2 + K * (C - B) * g2 * g3) / A),
              (q, ((C - A) * r * p + z0 * g1 - x0 * g3 + K * (A - C) * g3 * g1) / B),
              (r, ((A - B) * p * q + x0 * g2 - y0 * g1 + K * (B - A) * g1 * g2) / C),
              (g1, g2 * r - g3 * q), (g2, g3 * p - g1 * r), (g3, g1 * q - g2 * p)]

    def contestant(tol):
        ta = hy.taylor_adaptive(system, Y0, tol=tol)

        def call():
            ta.time = 0.0
            ta.state[:] = Y0
            return ta.propagate_grid(GRID)[-1][-1]
        return call, ta.order

    return {tol: contestant(tol) for tol in PEER_TOLERANCES}


def heyoka_same_work():
    """{tolerance: callable} doing with heyoka what ``auto``'s default ``Scene.run()`` does besides its run: the run
    at ``tol`` on the grid, a companion at ``tol``/100 (at least 1e-16) on the same grid compared with it (``output.error_estimate``),
    and one run of the 12-unknown variational equations over the span at auto's tangent tolerance (issue 22's chaos
    measure, ``amplification.TANGENT_TOLERANCE``). heyoka's tangent run keeps only its final state (auto's follows
    the running maximum of ln|δ|): a lower bound of the same work. {} when heyoka is not installed."""
    try:
        import heyoka as hy
    except ImportError:
        return {}
    from gyrolab.kernels.tangent import direction
    from gyrolab.accuracy.calibration import TANGENT_TOLERANCE

    A, B, C = INERTIA
    x0, y0, z0 = R_C
    state = hy.make_vars("p", "q", "r", "g1", "g2", "g3")
    tangent = hy.make_vars("dp", "dq", "dr", "dg1", "dg2", "dg3")
    p, q, r, g1, g2, g3 = state
    rhs = [((B - C) * q * r + y0 * g3 - z0 * g2 + K * (C - B) * g2 * g3) / A,
           ((C - A) * r * p + z0 * g1 - x0 * g3 + K * (A - C) * g3 * g1) / B,
           ((A - B) * p * q + x0 * g2 - y0 * g1 + K * (B - A) * g1 * g2) / C,
           g2 * r - g3 * q, g3 * p - g1 * r, g1 * q - g2 * p]
    variational = list(zip(state, rhs)) + [
        (d, hy.sum([hy.diff(f, x) * dx for x, dx in zip(state, tangent)])) for d, f in zip(tangent, rhs)]
    start = np.concatenate([Y0, direction(Y0[None, :], slice(3, 6))[0]])
    chaos = hy.taylor_adaptive(variational, start, tol=TANGENT_TOLERANCE)
    runs = {tol: hy.taylor_adaptive(list(zip(state, rhs)), Y0, tol=tol) for tol in PEER_TOLERANCES}

    def contestant(tol):
        # auto's companion stops at the Taylor kernel's floor, 1e-16 (``Taylor.TOLERANCE_FLOOR``): so does this one
        main, companion = runs[tol], hy.taylor_adaptive(list(zip(state, rhs)), Y0, tol=max(tol / 100, 1e-16))

        def call():
            for ta, y in ((main, Y0), (companion, Y0), (chaos, start)):
                ta.time = 0.0
                ta.state[:] = y
            chaos.propagate_until(T_END)
            trajectory = main.propagate_grid(GRID)[-1]
            np.max(np.abs(trajectory - companion.propagate_grid(GRID)[-1]), axis=0)
            return trajectory[-1]
        return call

    return {tol: contestant(tol) for tol in runs}


def interleaved(contestants, rounds):
    """Minimum time and last result of each callable, running every one once per round.

    The time is the process's CPU time (``time.process_time``), not the wall time: on a shared machine a
    run longer than a scheduler slice (a few ms) is almost always preempted, so minima of wall times favour
    the short runs; CPU time is what the run itself costs. ``--wall`` switches to wall time (unloaded machine).
    """
    clock = time.perf_counter if WALL else time.process_time
    best = {key: (np.inf, None) for key in contestants}
    times = {key: [] for key in contestants}
    for _ in range(rounds):
        for key, fn in contestants.items():
            start = clock()
            result = fn()
            elapsed = clock() - start
            times[key].append(elapsed)
            best[key] = (min(best[key][0], elapsed), result)
    MEDIANS.update({key: float(np.median(values)) for key, values in times.items()})
    return best


def final_state(ds):
    return np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])


def peer_table(reference, rounds, quick):
    """Time to reach each ε: heyoka propagate_grid against gyrolab taylor/auto (integration and Scene.run)."""
    from gyrolab.accuracy.auto import Auto
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    scene = compose_scene(["experiment=perf_reference"])
    compiled, y0 = scene.compiled, scene.system.initial_state()
    epsilons = EPSILONS[::3] if quick else EPSILONS
    contestants, settings = {}, {}
    for tol, (call, order) in heyoka_contestants().items():
        contestants[("heyoka", tol)] = call
        settings[("heyoka", tol)] = f"tol={tol:.1e}, order {order}"
    for tol in ([1e-9, 1e-12, 1e-16] if quick else QUARTER_DECADES[28:69]):
        taylor = Taylor(tol=tol)
        contestants[("taylor", tol)] = lambda t=taylor: t.integrate(None, GRID, y0, None, compiled).y[-1]
        settings[("taylor", tol)] = f"tol={tol:.1e}, order {taylor.order}"
    scenes = {}
    for eps in epsilons:
        def auto_call(eps=eps):
            auto = Auto(accuracy=eps)
            auto.prepare(scene.system)
            return auto.integrate(None, GRID, y0, None, compiled).y[-1]
        contestants[("auto", eps)] = auto_call
        settings[("auto", eps)] = f"accuracy={eps:.0e}"
        scenes[eps] = compose_scene(["experiment=perf_reference", f"accuracy={eps}"])
        contestants[("auto Scene.run()", eps)] = lambda s=scenes[eps]: final_state(s.run())
        settings[("auto Scene.run()", eps)] = f"accuracy={eps:.0e}"
    interleaved(contestants, 1)  # compile, load caches, build heyoka's kernels
    best = interleaved(contestants, rounds)
    errors = {key: float(np.max(np.abs(np.asarray(result)[:6] - reference))) for key, (_, result) in best.items()}

    def cheapest(method, eps):
        ok = [key for key in best if key[0] == method and errors[key] <= eps]
        return min(ok, key=lambda key: best[key][0]) if ok else None

    def cell(key):
        return "not reached" if key is None else f"{best[key][0] * 1e3:.2f} ({errors[key]:.1e})"

    has_peer = any(key[0] == "heyoka" for key in best)
    print(f"\n{'Wall' if WALL else 'CPU'} time to reach a final error ≤ ε on 3,001 output times, ms (error "
          f"reached); minimum over {rounds} interleaved rounds.\n")
    print("| ε | heyoka propagate_grid | gyrolab auto, integration | gyrolab auto, Scene.run() | "
          "gyrolab taylor, integration | auto / heyoka | Scene.run() / heyoka | taylor / heyoka |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for eps in epsilons:
        peer, taylor = cheapest("heyoka", eps), cheapest("taylor", eps)
        auto, run_ = ("auto", eps), ("auto Scene.run()", eps)
        auto_key = auto if errors[auto] <= eps else None
        run_key = run_ if errors[run_] <= eps else None
        ratios = ["" if peer is None or key is None else f"{best[key][0] / best[peer][0]:.2f}"
                  for key in (auto_key, run_key, taylor)]
        print(f"| {eps:.0e} | {cell(peer) if has_peer else 'not installed'} | {cell(auto_key)} | {cell(run_key)} | "
              f"{cell(taylor)} | {' | '.join(ratios)} |")
    print("\nThe same rounds' medians, ms (heyoka and taylor: the setting with the smallest median reaching ε):\n")
    print("| ε | heyoka | auto, integration | auto, Scene.run() | taylor | auto / heyoka | Scene.run() / heyoka | "
          "taylor / heyoka |\n| --- | --- | --- | --- | --- | --- | --- | --- |")
    median_rows = []
    for eps in epsilons:
        def fastest(method):
            ok = [key for key in best if key[0] == method and errors[key] <= eps]
            return min(ok, key=MEDIANS.get) if ok else None
        keys = [fastest("heyoka"), *[key if errors[key] <= eps else None for key in (("auto", eps),
                                                                                      ("auto Scene.run()", eps))],
                fastest("taylor")]
        cells = ["not reached" if key is None else f"{MEDIANS[key] * 1e3:.2f}" for key in keys]
        ratios = ["" if keys[0] is None or key is None else f"{MEDIANS[key] / MEDIANS[keys[0]]:.2f}"
                  for key in keys[1:]]
        print(f"| {eps:.0e} | {' | '.join(cells)} | {' | '.join(ratios)} |")
        median_rows.append([f"{eps:.0e}", *cells, *(f"{r}×" if r else "" for r in ratios)])
    run_ratios = {}
    for eps in epsilons:
        peer = min((key for key in best if key[0] == "heyoka" and errors[key] <= eps), key=MEDIANS.get, default=None)
        run_key = ("auto Scene.run()", eps)
        if peer is not None:
            run_ratios[eps] = MEDIANS[run_key] / MEDIANS[peer] if errors[run_key] <= eps else float("inf")
    print_verdict(run_ratios)
    if not quick and has_peer:
        write_results("perf_reference", {"rounds": rounds, "errors": {f"{k[0]} {k[1]:.2e}": v for k, v in errors.items()},
                                         "cpu_ms_min": {f"{k[0]} {k[1]:.2e}": best[k][0] * 1e3 for k in best},
                                         "cpu_ms_median": {f"{k[0]} {k[1]:.2e}": MEDIANS[k] * 1e3 for k in best}},
                      {"perf_reference": {
                          "caption": f"Time to reach a final error ≤ ε on the reference scene (t ∈ [0, 300], 3,001 "
                                     f"output times), CPU ms, medians of {rounds} interleaved rounds; heyoka's "
                                     f"`propagate_grid` and gyrolab's `taylor` at their cheapest tolerance reaching ε (a "
                                     f"quarter-decade grid of tolerances), "
                                     f"`auto` at accuracy ε; `Scene.run()` includes the dataset and `auto`'s default "
                                     f"error estimate (a companion run).",
                          "header": ["ε", "heyoka", "`auto`, integration", "`auto`, `Scene.run()`", "`taylor`",
                                     "`auto` / heyoka", "`Scene.run()` / heyoka", "`taylor` / heyoka"],
                          "rows": median_rows}})
    print("\nEvery setting measured:\n\n| method | setting | final error | time [ms] |\n| --- | --- | --- | --- |")
    for key in sorted(best, key=lambda key: (key[0], -key[1])):
        print(f"| {key[0]} | {settings[key]} | {errors[key]:.2e} | {best[key][0] * 1e3:.2f} |")


NO_ESTIMATE = "auto Scene.run(), output.error_estimate=false"
SAME_WORK = "heyoka, auto's work"
#: issue 32, item 3: auto's whole Scene.run() (dataset and error estimate included) / heyoka's bare propagate_grid,
#: ≤ 1.5× at ε = 1e-6 … 1e-11 and ≤ 3× at 1e-12, 1e-13; without the estimate ≤ NO_ESTIMATE_TARGET at every ε
TARGET_TIGHT_BELOW, TARGET, TARGET_TIGHT, NO_ESTIMATE_TARGET = 3e-12, 1.5, 3.0, 1.0


#: issue 32, item 3: auto's whole Scene.run() at ε = SCIPY_EPS at least SCIPY_TARGET× faster than what a researcher
#: writes (scipy's DOP853 through solve_ivp, ``plain_numpy_rhs``) at its cheapest tolerance of SCIPY_TOLS reaching ε
SCIPY_EPS, SCIPY_TARGET, SCIPY_TOLS = 1e-8, 250.0, (1e-9, 10 ** -9.5, 1e-10, 10 ** -10.5, 1e-11, 1e-12)


def target(eps):
    return TARGET_TIGHT if eps < TARGET_TIGHT_BELOW else TARGET


def scipy_baseline(reference, rounds=3):
    """(CPU s, tolerance, final error) of scipy's DOP853 on ``plain_numpy_rhs`` at its cheapest tolerance of
    SCIPY_TOLS reaching SCIPY_EPS (each timed ``rounds`` times, minimum: ~1–3 s a run), None when none does."""
    for tol in SCIPY_TOLS:  # loosest first: the first that reaches ε is the cheapest
        def call(tol=tol):
            return solve_ivp(plain_numpy_rhs, (0, T_END), Y0, method="DOP853", rtol=tol, atol=tol, t_eval=GRID).y[:, -1]
        best = interleaved({tol: call}, rounds)[tol]
        error = float(np.max(np.abs(best[1] - reference)))
        if error <= SCIPY_EPS:
            return best[0], tol, error
    return None


def passes(ratios, goal=target):
    return all(ratio <= goal(eps) for eps, ratio in ratios.items())


def print_verdict(run_ratios, what="auto Scene.run()", goal=target):
    """One line per ε (median Scene.run() / heyoka) and PASS/FAIL against the target (``goal(ε)``) at every ε."""
    if not run_ratios:
        print("\nScene.run() / heyoka: heyoka not installed, no verdict")
        return
    print(f"\n{what} / heyoka propagate_grid (medians, dataset included):")
    for eps, ratio in run_ratios.items():
        print(f"  ε = {eps:.0e}: {ratio:.2f}× (target ≤ {goal(eps):g}×){'' if ratio <= goal(eps) else '  (over)'}")
    print(f"{'PASS' if passes(run_ratios, goal) else 'FAIL'}: {what} within its target at every ε "
          f"(worst {max(run_ratios.values()):.2f}×)")


def tangent_tolerance():
    from gyrolab.accuracy.calibration import TANGENT_TOLERANCE

    return TANGENT_TOLERANCE


def scene_run_only(reference, rounds):
    """Only what issue 24's verdict needs: heyoka at every tolerance and auto's Scene.run() per ε, interleaved."""
    contestants = {("heyoka", tol): call for tol, (call, _) in heyoka_contestants().items()}
    contestants.update({(SAME_WORK, tol): call for tol, call in heyoka_same_work().items()})
    quality = {}  # ε -> the stored estimate at the final time / the actual final error
    for eps in EPSILONS:
        scene = compose_scene(["experiment=perf_reference", f"accuracy={eps}"])
        contestants[("auto Scene.run()", eps)] = lambda s=scene: final_state(s.run())
        ds = scene.run()
        estimated = max(float(ds.error_estimate_omega[-1]), float(ds.error_estimate_attitude[-1]))
        quality[eps] = (estimated / float(np.max(np.abs(final_state(ds) - reference[:6]))),
                        ds.attrs["error_estimate_method"].split(" (")[0])
        bare = compose_scene(["experiment=perf_reference", f"accuracy={eps}", "output.error_estimate=false"])
        contestants[(NO_ESTIMATE, eps)] = lambda s=bare: final_state(s.run())
    interleaved(contestants, 1)
    best = interleaved(contestants, rounds)
    errors = {key: float(np.max(np.abs(np.asarray(result)[:6] - reference))) for key, (_, result) in best.items()}
    ratios, bare_ratios, same_ratios, rows = {}, {}, {}, []
    for eps in EPSILONS:
        peer = min((key for key in best if key[0] == "heyoka" and errors[key] <= eps), key=MEDIANS.get, default=None)
        run_key, bare_key = ("auto Scene.run()", eps), (NO_ESTIMATE, eps)
        if peer is not None:
            same = MEDIANS[(SAME_WORK, peer[1])]  # the same tolerance as the peer's run: the same error
            ratios[eps] = MEDIANS[run_key] / MEDIANS[peer] if errors[run_key] <= eps else float("inf")
            same_ratios[eps] = MEDIANS[run_key] / same if errors[run_key] <= eps else float("inf")
            print(f"ε = {eps:.0e}: heyoka {MEDIANS[peer] * 1e3:.2f} ms ({errors[peer]:.1e}), doing auto's work "
                  f"{same * 1e3:.2f} ms, auto Scene.run() {MEDIANS[run_key] * 1e3:.2f} ms ({errors[run_key]:.1e}), "
                  f"without the error estimate {MEDIANS[bare_key] * 1e3:.2f} ms ({errors[bare_key]:.1e}); the "
                  f"estimate at the final time is {quality[eps][0]:.2f}× the actual error ({quality[eps][1]})")
            rows.append([f"{eps:.0e}", f"{MEDIANS[peer] * 1e3:.2f} ({errors[peer]:.1e})",
                         f"{MEDIANS[run_key] * 1e3:.2f} ({errors[run_key]:.1e})", f"{ratios[eps]:.2f}×",
                         f"{MEDIANS[bare_key] * 1e3:.2f}", f"{MEDIANS[bare_key] / MEDIANS[peer]:.2f}×",
                         f"{same * 1e3:.2f}", f"{MEDIANS[run_key] / same:.2f}×"])
            # without the estimate auto keeps only its prediction: a run that misses ε has no ratio
            bare_ratios[eps] = MEDIANS[bare_key] / MEDIANS[peer] if errors[bare_key] <= eps else float("inf")
    print_verdict(ratios)
    print_verdict(bare_ratios, "auto Scene.run(), output.error_estimate=false", lambda eps: NO_ESTIMATE_TARGET)
    scipy = scipy_baseline(reference)
    speedup = scipy[0] / MEDIANS[("auto Scene.run()", SCIPY_EPS)] if scipy is not None else float("nan")
    scipy_verdict = "PASS" if speedup >= SCIPY_TARGET else "FAIL"
    if scipy is not None:
        print(f"\nscipy DOP853 (solve_ivp, plain numpy right-hand side) reaching ε = {SCIPY_EPS:g}: {scipy[0]:.2f} s "
              f"at tol {scipy[1]:.2g} (final error {scipy[2]:.1e}); auto's Scene.run() is {speedup:.0f}× faster "
              f"(target ≥ {SCIPY_TARGET:g}×): {scipy_verdict}")
    if rows:
        write_results("perf_reference_scene_run", {"rounds": rounds, "ratios": {f"{e:.0e}": r for e, r in ratios.items()}},
                      {"scene_run_verdict": {
                          "caption": f"The verdict: `auto`'s whole `Scene.run()` (dataset and default error "
                                     f"estimate included; beside it with `output.error_estimate=false`) against "
                                     f"heyoka's `propagate_grid` at its cheapest tolerance reaching ε, on the reference "
                                     f"scene's 3,001 output times; CPU ms, medians of {rounds} interleaved rounds "
                                     f"(final error reached). Target (issue 32) ≤ {TARGET:g}× at ε = 1e-6 … "
                                     f"1e-11, ≤ {TARGET_TIGHT:g}× at 1e-12 and 1e-13: "
                                     f"{'PASS' if passes(ratios) else 'FAIL'}; without the estimate ≤ "
                                     f"{NO_ESTIMATE_TARGET:g}×. The last two "
                                     f"columns: heyoka doing the work `auto`'s default call does besides its run "
                                     f"(its run, a companion at tol/100 compared on the grid, one run of the "
                                     f"variational equations at {tangent_tolerance():g}), and `auto` against it.",
                          "header": ["ε", "heyoka", "auto `Scene.run()`", "/ heyoka", "without error estimate",
                                     "/ heyoka", "heyoka doing auto's work", "auto / that"],
                          "rows": rows}},
                      command="benchmarks/perf_reference.py --scene-run",
                      summary=[["`auto`'s whole `Scene.run()` / heyoka `propagate_grid`, worst over ε = 1e-6 … 1e-13 "
                                "(without the error estimate)",
                                f"{max(ratios.values()):.2f}× ({max(bare_ratios.values()):.2f}×)",
                                f"≤ {TARGET:g}× (≤ {TARGET_TIGHT:g}× at 1e-12, 1e-13)",
                                "PASS" if passes(ratios) else "FAIL"],
                               ["`auto`'s whole `Scene.run()` / heyoka doing the same work (its run, the companion "
                                "run of the error estimate, the variational run of the chaos measure), worst over ε",
                                f"{max(same_ratios.values()):.2f}×", "(no target: the like-for-like comparison)",
                                "ahead" if max(same_ratios.values()) <= 1.0 else "behind"],
                               [f"scipy's DOP853 (`solve_ivp`, plain numpy right-hand side) / `auto`'s whole "
                                f"`Scene.run()`, ε = {SCIPY_EPS:g}", f"{speedup:.0f}×", f"≥ {SCIPY_TARGET:g}×",
                                scipy_verdict]])


def run_breakdown(reference, rounds, quick):
    """Where ``Scene.run()`` with ``integrator=auto`` spends its time: the regimes' series check, the pilot and
    final Taylor run (auto without the series check, its error measured: the final run's one pass measures the
    growth of perturbations and the error), the chosen run alone without its one pass, the error estimate's
    decision (``estimate.compare``: the one pass taken, or companion runs near the floor), the dataset, interleaved
    with heyoka's calls as the verdict's benchmark runs them (run alone, the Python parts take about half as long).
    The floor: the series check, the run without its one pass and the dataset, what the call costs with nothing
    measured, against heyoka's cheapest tolerance reaching ε."""
    from gyrolab.output.dataset import build_dataset
    from gyrolab.accuracy import estimate
    from gyrolab.accuracy.auto import Auto

    contestants = {("heyoka", tol): call for tol, (call, _) in heyoka_contestants().items()}
    for eps in EPSILONS[::3] if quick else EPSILONS:
        scene = compose_scene(["experiment=perf_reference", f"accuracy={eps}"])
        compiled, y0 = scene.compiled, scene.system.initial_state()

        def series(scene=scene, eps=eps, compiled=compiled, y0=y0):
            auto = Auto(accuracy=eps)
            auto.prepare(scene.system)
            return auto._series(None, GRID, y0, compiled, 0.0)

        def integration(eps=eps, compiled=compiled, y0=y0):  # no system: auto skips the series check
            return Auto(accuracy=eps).integrate(None, GRID, y0, None, compiled, estimated=True)

        solution = integration()
        contestants[("series check", eps)] = series
        contestants[("pilot + Taylor", eps)] = integration
        contestants[("(the run without its one pass)", eps)] = lambda method=solution.choice.method, compiled=compiled, \
            y0=y0: method.integrate(None, GRID, y0, None, compiled)
        contestants[("error estimate", eps)] = lambda scene=scene, solution=solution: estimate.compare(
            scene, solution.choice.method, solution.y, solution.stats.wall_time, None, solution.estimate)
        contestants[("dataset", eps)] = lambda scene=scene, solution=solution: build_dataset(scene, solution)
        contestants[("Scene.run()", eps)] = scene.run
    interleaved(contestants, 1)
    best = interleaved(contestants, rounds)
    peers = {key: best.pop(key) for key in [key for key in best if key[0] == "heyoka"]}
    errors = {key: float(np.max(np.abs(np.asarray(result)[:6] - reference))) for key, (_, result) in peers.items()}
    parts = list(dict.fromkeys(key[0] for key in best))
    floor_parts = ("series check", "(the run without its one pass)", "dataset")
    print(f"\nWhere `auto`'s Scene.run() spends its time, {'wall' if WALL else 'CPU'} ms (minimum over {rounds} "
          f"rounds interleaved with heyoka's calls; the floor: {' + '.join(floor_parts)}):\n\n"
          f"| ε | {' | '.join(parts)} | heyoka | floor / heyoka |\n| --- |{' --- |' * (len(parts) + 2)}")
    for eps in dict.fromkeys(key[1] for key in best):
        peer = min((key for key in peers if errors[key] <= eps), key=lambda key: peers[key][0], default=None)
        floor = sum(best[(part, eps)][0] for part in floor_parts)
        versus = ("not reached", "") if peer is None else (f"{peers[peer][0] * 1e3:.2f}",
                                                           f"{floor / peers[peer][0]:.2f}×")
        print(f"| {eps:.0e} | {' | '.join(f'{best[(part, eps)][0] * 1e3:.2f}' for part in parts)} | "
              f"{' | '.join(versus)} |")


def calibration(reference):
    """Actual / raw predicted final error of ``integrator=auto`` (``auto_raw_predicted_error``: before CALIBRATION
    and round-off) over the extremes matrix of ``tests/accuracy/test_extremes.py`` and the reference scene, accuracies 1e-3 to
    1e-13: the measurement behind ``gyrolab.accuracy.calibration.CALIBRATION``, reported against the table. Extremes scenes are judged
    against Taylor at tol 1e-17 (ratios marked * are within 100× of its disagreement with compiled DOP853 at 1e-13,
    i.e. not measured); the reference scene against the extended-precision reference."""
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "tests", "accuracy"))
    from test_extremes import SCENES

    from gyrolab.accuracy.auto import Auto
    from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor

    cases = [(name, [*overrides, "time.n_output=51"]) for name, overrides in SCENES.items()]
    cases.append(("reference scene", ["experiment=perf_reference"]))
    accuracies = [10.0 ** -k for k in range(3, 14)]
    print("\n`auto` calibration: actual / raw predicted final error (* not measurable: near the reference's own "
          f"error)\n\n| scene | {' | '.join(f'{a:.0e}' for a in accuracies)} |\n| --- |{' --- |' * len(accuracies)}")
    worst, exceeded = (0.0, ""), 0
    for name, overrides in cases:
        built = compose_scene([*overrides, "integrator=auto", "accuracy=1e-9"])
        system, times, y0 = built.system, built.times, built.system.initial_state()
        if name == "reference scene":
            truth, floor = reference, 1e-15
        else:
            truth = Taylor(tol=1e-17).integrate(system.rhs, times[[0, -1]], y0, None, built.compiled).y[-1]
            other = DOP853Numba(rtol=1e-13, atol=1e-13).integrate(system.rhs, times[[0, -1]], y0, None, built.compiled)
            floor = float(np.max(np.abs(other.y[-1] - truth)))
        cells = []
        for accuracy in accuracies:
            auto = Auto(accuracy=accuracy)
            try:
                auto.prepare(system)  # refuses an accuracy below the scene's floor
                solution = auto.integrate(system.rhs, times, y0, None, built.compiled)
            except Exception as error:  # a refused accuracy (below the round-off floor)
                cells.append(type(error).__name__)
                continue
            actual = float(np.max(np.abs(solution.y[-1][:len(truth)] - truth)))
            ratio = actual / solution.choice.attributes["auto_raw_predicted_error"]
            measured = actual > 100 * floor
            if measured and ratio > worst[0]:
                worst = (ratio, f"{name}, accuracy {accuracy:.0e}")
            exceeded += actual > solution.choice.promised
            bound = "" if actual <= solution.choice.promised else " (prediction exceeded)"
            cells.append(f"{ratio:.2f}{'' if measured else '*'}{bound}")
        print(f"| {name} | {' | '.join(cells)} |")
    print(f"\nlargest measured ratio: {worst[0]:.2f} ({worst[1]})")
    from gyrolab.accuracy import calibration as table

    return table.report(table.CALIBRATE, {"CALIBRATION": (
        worst[0] * 1.5 <= table.CALIBRATION and not exceeded,
        f"the largest actual / raw prediction {worst[0]:.2f} (the value must leave a factor 1.5 above it), "
        f"{exceeded} recorded predictions exceeded")})


FIRST_CHECK = """
import time, numpy as np
from gyrolab import compose_scene
from gyrolab.accuracy.auto import Auto
scene = compose_scene(["experiment=perf_reference", "accuracy=1e-8"])
grid, y0, compiled = np.linspace(0.0, 300.0, 3001), scene.system.initial_state(), scene.compiled
Auto(accuracy=1e-8).integrate(None, grid, y0, None, compiled)  # kernels loaded: what follows is the check alone
auto = Auto(accuracy=1e-8)
auto.prepare(scene.system)
start = time.process_time()
auto._series(None, grid, y0, compiled, 0.0)
print(time.process_time() - start)
"""


def first_series_check():
    """CPU seconds of auto's series check on its first call in a fresh process (regime modules imported, series
    built if the scene is not ruled out first), median of three processes."""
    times = sorted(float(subprocess.run([sys.executable, "-c", FIRST_CHECK], check=True, capture_output=True,
                                        text=True, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"}).stdout)
                   for _ in range(3))
    return times[1]


def batch_throughput(repeats):
    scene = compose_scene(["experiment=perf_reference", "integrator=rk4_numba", "integrator.step=0.01",
                           "time.end=10", "time.n_output=11"])
    rng = np.random.default_rng(0)
    y0s = np.tile(scene.system.initial_state(), (1000, 1))
    y0s[:, 0:3] += rng.normal(scale=0.1, size=(1000, 3))
    integrate_batch(scene, y0s[:4])
    return max(integrate_batch(scene, y0s).trajectory_steps_per_second for _ in range(repeats))


def cold_default_run():
    with tempfile.TemporaryDirectory() as tmp:
        times = []
        for i in range(2):  # the first may fill the kernel cache; the second is a cold process with a warm cache
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "gyrolab", f"hydra.run.dir={tmp}/run{i}"], check=True,
                           capture_output=True, cwd=tmp)
            times.append(time.perf_counter() - start)
    return times


def scipy_and_dop853_rows(reference, repeats, quick):
    """(method, setting, error, time) of scipy DOP853 / RK45 and gyrolab dop853_numba (Scene.run()), interleaved."""
    tols = [1e-9, 1e-12] if quick else [1e-7, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14]
    contestants = {}
    for tol in tols:
        contestants[("scipy DOP853", tol)] = lambda tol=tol: solve_ivp(
            plain_numpy_rhs, (0, T_END), Y0, method="DOP853", rtol=tol, atol=tol, t_eval=GRID).y[:, -1]
        scene = compose_scene(["experiment=perf_reference", "integrator=dop853_numba", f"integrator.rtol={tol}",
                               f"integrator.atol={tol}"])
        contestants[("gyrolab dop853_numba, Scene.run()", tol)] = lambda s=scene: final_state(s.run())
    interleaved(contestants, 1)
    best = interleaved(contestants, repeats)
    return [(key[0], f"tol={key[1]:.0e}", float(np.max(np.abs(result - reference))), wall)
            for key, (wall, result) in best.items()]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer tolerances and rounds")
    parser.add_argument("--wall", action="store_true", help="wall time instead of CPU time (an unloaded machine)")
    parser.add_argument("--calibration", action="store_true",
                        help="only the measurement behind auto's CALIBRATION (about 30 s)")
    parser.add_argument("--scene-run", action="store_true",
                        help="only heyoka against auto's Scene.run() per ε, with the PASS/FAIL verdict (issue 24)")
    parser.add_argument("--breakdown", action="store_true",
                        help="only where auto's Scene.run() spends its time (series check, pilot and run with its "
                             "one pass, the run without it, error estimate, dataset)")
    args = parser.parse_args()
    global WALL
    WALL = args.wall
    rounds = 3 if args.quick else 15
    print(f"# gyrolab perf_reference benchmark, {datetime.date.today()}, {platform.machine()}, "
          f"{os.cpu_count()} cores, {platform.processor() or platform.platform()}, Python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f} at start, OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')} (BLAS threads spinning on small arrays bill CPU time)")
    start = time.perf_counter()
    reference = fixed_point_reference(INERTIA, R_C, K, Y0, [0.0, T_END])[-1].astype(float)
    print(f"# reference: extended-precision Taylor, {time.perf_counter() - start:.1f} s")
    if args.calibration:
        sys.exit(0 if calibration(reference) else 1)
    if args.scene_run:
        scene_run_only(reference, rounds)
        return
    if args.breakdown:
        run_breakdown(reference, rounds, args.quick)
        return
    peer_table(reference, rounds, args.quick)
    run_breakdown(reference, rounds, args.quick)
    print(f"\nauto's series check, first call in a process (regime modules imported then): "
          f"{first_series_check() * 1e3:.0f} ms CPU (median of 3 processes)")

    rows = scipy_and_dop853_rows(reference, 2, args.quick)
    print("\nC-speed DOP853 and scipy (3,001 output times; gyrolab: Scene.run()):\n\n"
          "| method | setting | final error | time [ms] |\n| --- | --- | --- | --- |")
    for method, setting, error, wall in sorted(rows):
        print(f"| {method} | {setting} | {error:.2e} | {wall * 1e3:.2f} |")
    print(f"\nbatch: 1000 trajectories, fixed-step RK4 (rk4_numba): {batch_throughput(3):.3g} trajectory-steps/s "
          f"(goal 1.5e7)")
    cold = cold_default_run()
    print(f"cold `gyrolab` default run, end to end: {cold[1]:.2f} s with warm kernel cache "
          f"(first process {cold[0]:.2f} s; goal 3 s)")
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end (a loaded machine slows every contestant alike)")
    from gyrolab.accuracy import calibration as table

    table.report(table.PERF, tighter_check(reference))


def tighter_check(reference):
    """The companion's gain on the reference scene (``calibration.TIGHTER``): Taylor as auto runs it at 1e-6 (order
    12, tol 1.3e-8) and at tol / TIGHTER, final errors against the extended-precision reference."""
    from gyrolab.accuracy import calibration as table
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    scene = compose_scene(["experiment=perf_reference", "time.n_output=2"])
    y0 = scene.system.initial_state()
    errors = [float(np.max(np.abs(Taylor(order=12, tol=tol).integrate(None, scene.times, y0, None, scene.compiled)
                                  .y[-1][:6] - reference[:6]))) for tol in (1.3e-8, 1.3e-8 / table.TIGHTER)]
    gain = errors[0] / errors[1]
    return {"TIGHTER": (gain >= table.TIGHTER / 3, f"the companion at tol / {table.TIGHTER:g} ends {gain:.0f}× more "
                                                   "accurate on the reference scene (supported from TIGHTER / 3)")}


if __name__ == "__main__":
    main()
