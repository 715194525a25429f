"""Batch throughput at a target accuracy: gyrolab's batch kernels against heyoka's batch mode, side by side.

    pip install -e ".[bench]"                      # heyoka (optional: its rows are skipped when absent)
    python benchmarks/batch_heyoka.py              # N = 100,000 (a few minutes on 2 cores)
    python benchmarks/batch_heyoka.py --n 10000 --rounds 2
    python benchmarks/batch_heyoka.py --n 4000 --order-scan   # gyrolab taylor only: orders 10–18 × tolerances

Issue 14's target: max error 1e-10 over N trajectories of the reference scene's
body (``experiment=perf_reference``: A, B, C = 2, 1.5, 1, r_c = (0.3, 0.2,
0.9327…), Newtonian k = 0.5), ω0 = (0.1, −0.05, 5) perturbed by N(0, 0.1²) per
component (seed 0), γ0 = (sin 1, 0, cos 1), t ∈ [0, 10], 11 output times.

Error of a run = max over all N trajectories of the max-norm error of the
final state, against gyrolab's Taylor batch at tol 1e-15 (order 18), which is
itself checked against scipy's DOP853 at rtol = atol = 1e-13 on a subsample
(the agreement is printed; it must be far below 1e-10).

Contestants (each setting once per round, rounds interleave all of them, a
contestant's time is its minimum wall time over the rounds; compilation and
heyoka's JIT happen before the first round):
- gyrolab ``integrate_arrays`` with ``taylor`` (tol, order from the tolerance; and the two explicit
  (order, tol) settings ``--order-scan`` found cheapest), ``dop853_numba`` (rtol = atol) and ``auto``
  (accuracy 1e-10; its pilot on a few trajectories is included);
- heyoka ``taylor_adaptive_batch`` (batch size 4 = one AVX2 vector, ``propagate_grid``
  on the 11 times), two threads, each with its own integrator, over its share of the
  batches (the GIL is released inside heyoka's propagation).
The cheapest setting of each method whose error is ≤ 1e-10 is its result. CPU time (all threads,
``time.process_time``) is printed beside the wall time: on a shared machine it is the steadier of the two.
"""

from __future__ import annotations

import argparse
import copy
import os
import platform
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.batch.integrate import integrate_arrays
from gyrolab.plugins.integrators.auto import Auto
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, Taylor
from gyrolab.plugins.integrators.step_guard import compiled_rhs

TARGET = 1e-10
TIMES = np.linspace(0.0, 10.0, 11)
HEYOKA_LANES = 4
THREADS = 2
SUBSAMPLE = 20
#: (order, tol) of gyrolab taylor beside the orders from the tolerance: the cheapest under 1e-10 in
#: ``--order-scan`` (N = 4,000, shared machine: within ~15 % of each other and of order 13 at tol 1e-10)
EXPLICIT_ORDERS = [(15, 3e-11), (17, 3e-11)]


def problem(n: int):
    """(compiled model, initial states (n, 6)) of the benchmark."""
    scene = compose_scene(["experiment=perf_reference", "integrator=taylor", "time.end=10", "time.n_output=11"])
    rng = np.random.default_rng(0)
    y0s = np.tile(scene.system.initial_state(), (n, 1))
    y0s[:, 0:3] += rng.normal(scale=0.1, size=(n, 3))
    return scene.system.compiled_model(), y0s


def heyoka_contestant(compiled, y0s: np.ndarray, tol: float):
    """A callable returning the final states (n, 6) from heyoka's batch mode, or None without heyoka."""
    try:
        import heyoka as hy
    except ImportError:
        return None
    p = compiled.params
    A, B, C = p[0:3]
    u0, u1, u2 = p[9:12]  # U_2 = m g r_c: the torque U_2 × γ
    k = p[14]
    w0, w1, w2, g0, g1, g2 = hy.make_vars("w0", "w1", "w2", "g0", "g1", "g2")
    system = [(w0, ((B - C) * w1 * w2 + u1 * g2 - u2 * g1 + k * (C - B) * g1 * g2) / A),
              (w1, ((C - A) * w2 * w0 + u2 * g0 - u0 * g2 + k * (A - C) * g2 * g0) / B),
              (w2, ((A - B) * w0 * w1 + u0 * g1 - u1 * g0 + k * (B - A) * g0 * g1) / C),
              (g0, g1 * w2 - g2 * w1), (g1, g2 * w0 - g0 * w2), (g2, g0 * w1 - g1 * w0)]
    first = np.ascontiguousarray(y0s[:HEYOKA_LANES].T)
    integrators = [hy.taylor_adaptive_batch(system, first, tol=tol)]
    integrators += [copy.deepcopy(integrators[0]) for _ in range(THREADS - 1)]
    grid = np.repeat(TIMES[:, None], HEYOKA_LANES, axis=1)
    n = len(y0s)  # a multiple of HEYOKA_LANES (main checks it)
    final = np.full((n, 6), np.nan)

    def share(worker: int) -> None:
        ta = integrators[worker]
        for b in range(worker, n // HEYOKA_LANES, THREADS):
            rows = slice(b * HEYOKA_LANES, (b + 1) * HEYOKA_LANES)
            ta.set_time(0.0)
            ta.state[:] = y0s[rows].T
            final[rows] = ta.propagate_grid(grid)[-1][-1].T

    def call() -> np.ndarray:
        with ThreadPoolExecutor(THREADS) as pool:
            list(pool.map(share, range(THREADS)))
        return final

    return call, integrators[0].order


def gyrolab_contestant(compiled, y0s: np.ndarray, integrator):
    def call() -> np.ndarray:
        return integrate_arrays(compiled, integrator, TIMES, y0s).y[:, -1]
    return call


def reference(compiled, y0s: np.ndarray) -> tuple[np.ndarray, float]:
    """(final states of gyrolab's Taylor batch at tol 1e-15, its max disagreement with scipy DOP853 on a subsample)."""
    final = integrate_arrays(compiled, Taylor(tol=1e-15), TIMES, y0s).y[:, -1]
    fun = compiled_rhs(compiled)
    rows = np.linspace(0, len(y0s) - 1, min(SUBSAMPLE, len(y0s))).astype(int)
    scipy_final = np.array([solve_ivp(fun, (0.0, TIMES[-1]), y0s[j], method="DOP853", rtol=1e-13,
                                      atol=1e-13).y[:, -1] for j in rows])
    return final, float(np.max(np.abs(scipy_final - final[rows])))


def order_scan(compiled, y0s: np.ndarray, ref: np.ndarray, rounds: int) -> None:
    """Print gyrolab taylor's minimum wall time and max error for orders 10–18 × tolerances, and the cheapest under TARGET."""
    rows = []
    print("\n| order | tol | wall (s) | mean steps | max error over N |")
    print("|---|---|---|---|---|")
    for order in range(10, 19):
        for tol in [3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11]:
            taylor = Taylor(order=order, tol=tol)
            integrate_arrays(compiled, taylor, TIMES, y0s[:HEYOKA_LANES])  # compiles (once: the order is an argument)
            wall = np.inf
            for _ in range(rounds):
                start = time.perf_counter()
                batch = integrate_arrays(compiled, taylor, TIMES, y0s)
                wall = min(wall, time.perf_counter() - start)
            steps = batch.steps.mean()
            error = float(np.max(np.abs(batch.y[:, -1] - ref)))
            rows.append((wall, order, tol, error))
            print(f"| {order} | {tol:.0e} | {wall:.3f} | {steps:.1f} | {error:.1e} |")
            sys.stdout.flush()
    print(f"\ncheapest (order, tol) with max error ≤ {TARGET:g}:")
    for wall, order, tol, error in sorted(row for row in rows if row[3] <= TARGET)[:5]:
        print(f"- order {order}, tol {tol:.0e}: {wall:.3f} s, error {error:.1e}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=100_000, help="trajectories (default 100,000)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (default 3)")
    parser.add_argument("--order-scan", action="store_true",
                        help="only gyrolab taylor: time and error over orders 10–18 and tolerances 3e-9…1e-11")
    args = parser.parse_args()
    if args.n < HEYOKA_LANES or args.n % HEYOKA_LANES:
        parser.error(f"--n={args.n} must be a positive multiple of heyoka's batch size {HEYOKA_LANES}")
    compiled, y0s = problem(args.n)
    print(f"# batch throughput at max error {TARGET:g}: N = {args.n:,}, t ∈ [0, 10], {platform.processor() or 'cpu'}, "
          f"{os.cpu_count()} cores, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    ref, agreement = reference(compiled, y0s)
    print(f"reference: gyrolab taylor tol 1e-15; max difference from scipy DOP853 (rtol=atol=1e-13) on "
          f"{min(SUBSAMPLE, args.n)} trajectories: {agreement:.1e}")
    contestants, settings = {}, {}
    if args.order_scan:
        order_scan(compiled, y0s, ref, args.rounds)
        return
    for order, tol in [(None, 1e-9), (None, 3e-10), (None, 1e-10), (None, 3e-11), (None, 1e-11), *EXPLICIT_ORDERS]:
        taylor = Taylor(order=order, tol=tol)
        contestants[("gyrolab taylor", (tol, order))] = gyrolab_contestant(compiled, y0s, taylor)
        settings[("gyrolab taylor", (tol, order))] = f"tol={tol:.0e}, order {taylor.order}" + (" (explicit)" if order else "")
    for tol in [3e-11, 1e-11, 3e-12, 1e-12]:
        contestants[("gyrolab dop853_numba", tol)] = gyrolab_contestant(compiled, y0s, DOP853Numba(rtol=tol, atol=tol))
        settings[("gyrolab dop853_numba", tol)] = f"rtol=atol={tol:.0e}"
    auto = Auto(accuracy=TARGET)
    contestants[("gyrolab auto", TARGET)] = gyrolab_contestant(compiled, y0s, auto)
    for tol in [1e-9, 3e-10, 1e-10, 3e-11]:
        peer = heyoka_contestant(compiled, y0s, tol)
        if peer is None:
            print("heyoka is not installed (pip install -e '.[bench]'): its rows are skipped")
            break
        contestants[("heyoka batch", tol)] = peer[0]
        settings[("heyoka batch", tol)] = f"tol={tol:.0e}, order {peer[1]}, {HEYOKA_LANES} lanes, {THREADS} threads"
    small = y0s[:64]  # compile gyrolab's kernels before timing
    for key, call in contestants.items():
        if key[0].startswith("gyrolab"):
            gyrolab_contestant(compiled, small, Taylor(tol=1e-10) if "taylor" in key[0] else
                               DOP853Numba(rtol=1e-10, atol=1e-10))()
    best = {key: (np.inf, None) for key in contestants}
    cpu = {key: np.inf for key in contestants}
    for _ in range(args.rounds):
        for key, call in contestants.items():
            start, start_cpu = time.perf_counter(), time.process_time()
            final = call()
            elapsed = time.perf_counter() - start
            cpu[key] = min(cpu[key], time.process_time() - start_cpu)
            best[key] = (min(best[key][0], elapsed), final)
    settings[("gyrolab auto", TARGET)] = f"accuracy={TARGET:g} → {auto.choice.get('auto_method')} " \
                                         f"tol={auto.choice.get('auto_tolerance', float('nan')):.1e}"
    print("\n| method | setting | wall (s) | CPU (s, all threads) | trajectories/s | max error over N |")
    print("|---|---|---|---|---|---|")
    errors = {}
    for key, (wall, final) in best.items():
        errors[key] = float(np.max(np.abs(final - ref)))
        print(f"| {key[0]} | {settings[key]} | {wall:.2f} | {cpu[key]:.2f} | {args.n / wall:,.0f} | {errors[key]:.1e} |")
    print(f"\ncheapest setting reaching max error ≤ {TARGET:g} (by wall time):")
    winners = {}
    for method in dict.fromkeys(key[0] for key in contestants):
        ok = [key for key in contestants if key[0] == method and errors[key] <= TARGET]
        if ok:
            winners[method] = min(ok, key=lambda key: best[key][0])
            key = winners[method]
            print(f"- {method}: {best[key][0]:.2f} s wall, {cpu[key]:.2f} s CPU ({settings[key]}, error {errors[key]:.1e})")
        else:
            print(f"- {method}: no setting reached it")
    if "heyoka batch" in winners:
        peer = winners["heyoka batch"]
        for method, key in winners.items():
            if method != "heyoka batch":
                print(f"  {method} / heyoka batch: {best[key][0] / best[peer][0]:.2f}× the wall time, "
                      f"{cpu[key] / cpu[peer]:.2f}× the CPU time")
    print("\nwall times on a shared machine are noisy (other processes use the cores): compare within one run")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
