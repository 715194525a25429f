"""The Taylor step's cost: scalar against vectorised (``taylor.run_scalar`` / ``run_vector``), and against heyoka.

    pip install -e ".[bench]"                  # heyoka (optional: its columns are skipped when absent)
    python benchmarks/taylor_step.py           # a few minutes
    python benchmarks/taylor_step.py --quick   # fewer rounds

On the reference problem (``experiment=perf_reference``, ``benchmarks/perf_reference.py``: t ∈ [0, 300],
3,001 output times): (1) the cost of one Taylor step at orders 8, 12, 16, 20, the coefficients alone
(a compiled loop over one state, no step) and the whole run (``run_scalar`` / ``run_vector``: coefficients, step size, dense
output at ~1 output per step, compensated update) divided by its steps, scalar and vectorised; (2) the
``taylor`` integrator (``Integrator.integrate``, the vectorised step) and ``run_scalar`` against heyoka's
``propagate_grid`` on the same grid at tolerances 1e-8..1e-16, and the time each needs to reach a final error
≤ ε (1e-6..1e-13) against the extended-precision reference. CPU time
(``time.process_time``), contestants interleaved, minima over the rounds.
"""

from __future__ import annotations

import argparse
import math
import os
import sys

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from perf_reference import GRID, INERTIA, K, R_C, T_END, Y0, heyoka_contestants, interleaved  # noqa: E402

from gyrolab import compose_scene  # noqa: E402
from gyrolab.physics.reference import fixed_point_reference  # noqa: E402
from gyrolab.kernels import fixed_point, taylor  # noqa: E402

ORDERS = (8, 12, 16, 20)
REPEATS = 20000  # coefficient evaluations per timing


@numba.njit
def _scalar_coefficients(p, y, order, repeats):
    T = np.zeros((order + 1, 6))
    work = np.zeros((order + 1, 3))
    total = 0.0
    for r in range(repeats):
        T[0] = y
        T[0, 0] += r * 1e-12  # a new state each time: nothing to hoist
        fixed_point.taylor_coefficients(p, T, order, work)
        total += T[order, 0]
    return total


@numba.njit
def _vector_coefficients(p, y, order, repeats):
    T = np.zeros((order + 1, taylor.ROWS, taylor.LANES))
    Q = np.zeros((4, taylor.LANES))
    taylor._constants(p, Q)
    z = y.copy()
    total = 0.0
    for r in range(repeats):
        z[0] = y[0] + r * 1e-12
        taylor._set_state(T, z)
        taylor._coefficients(T, order, Q)
        total += T[order, 0, 0]
    return total


def _run(kernel, params, order, tol):
    out = np.empty((GRID.size, 6))
    out[0] = Y0
    state, carry, stats = np.array([0.0]), np.zeros(6), np.zeros(2, dtype=np.int64)
    if kernel is taylor.run_scalar:
        code, _ = kernel(taylor.FIXED_POINT, params, order, tol, GRID, out, 1, GRID.size, state, Y0.copy(), carry,
                         stats)
    else:
        code, _ = kernel(params, order, tol, GRID, out, 1, GRID.size, state, Y0.copy(), carry, stats)
    assert code == taylor.OK
    return out[-1], int(stats[1])


def step_table(params, rounds):
    contestants = {}
    for order in ORDERS:
        tol = math.exp(-2.0 * (order - 1.0)) * 1.01  # order_for(tol) = order
        assert taylor.order_for(tol) == order
        for name, fn in (("scalar", _scalar_coefficients), ("vector", _vector_coefficients)):
            contestants[("coefficients", name, order)] = lambda fn=fn, order=order: fn(params, Y0, order, REPEATS)
        for name, kernel in (("scalar", taylor.run_scalar), ("vector", taylor.run_vector)):
            contestants[("step", name, order)] = lambda k=kernel, order=order, tol=tol: _run(k, params, order, tol)
    interleaved(contestants, 1)  # compile
    best = interleaved(contestants, rounds)
    print("\nCost of one Taylor step (µs, CPU time, minimum over "
          f"{rounds} interleaved rounds); steps: those of the reference run at that order.\n")
    print("| order | steps | coefficients scalar | coefficients vector | speed-up | whole step scalar | "
          "whole step vector | speed-up |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for order in ORDERS:
        c = [best[("coefficients", name, order)][0] / REPEATS * 1e6 for name in ("scalar", "vector")]
        n = best[("step", "vector", order)][1][1]
        assert best[("step", "scalar", order)][1][1] == n
        s = [best[("step", name, order)][0] / n * 1e6 for name in ("scalar", "vector")]
        print(f"| {order} | {n} | {c[0]:.3f} | {c[1]:.3f} | {c[0] / c[1]:.2f} | {s[0]:.3f} | {s[1]:.3f} | "
              f"{s[0] / s[1]:.2f} |")


def peer_table(params, reference, rounds):
    from gyrolab.plugins.integrators.compiled_solvers import Taylor

    scene = compose_scene(["experiment=perf_reference"])
    compiled = scene.compiled
    tols = [10.0 ** -k for k in range(7, 18)]
    contestants = {}
    peers = heyoka_contestants()
    for tol in tols:
        integrator = Taylor(tol=tol)
        contestants[("taylor", tol)] = lambda t=integrator: t.integrate(None, GRID, Y0, None, compiled).y[-1]
        contestants[("scalar", tol)] = lambda t=integrator: _run(taylor.run_scalar, params, t.order, t.tol)[0]
    for tol, (call, _) in peers.items():
        contestants[("heyoka", tol)] = call
    interleaved(contestants, 1)
    best = interleaved(contestants, rounds)
    error = {key: float(np.max(np.abs(np.asarray(result)[:6] - reference))) for key, (_, result) in best.items()}
    print(f"\nThe reference scene, 3,001 output times: CPU ms (final error), minimum over {rounds} interleaved "
          "rounds. taylor = the integrator (``Integrator.integrate``, vectorised step); scalar = ``run_scalar`` "
          "at the same order, called directly.\n")
    print("| tol | order | taylor | taylor scalar | heyoka (order) | taylor / heyoka | scalar / heyoka |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for tol in tols[1:-1]:
        cells = [f"{best[(m, tol)][0] * 1e3:.2f} ({error[(m, tol)]:.1e})" for m in ("taylor", "scalar")]
        if ("heyoka", tol) in best:
            peer = best[("heyoka", tol)][0]
            ratios = [f"{best[(m, tol)][0] / peer:.2f}" for m in ("taylor", "scalar")]
            peer_cell = f"{peer * 1e3:.2f} ({error[('heyoka', tol)]:.1e}) ({peers[tol][1]})"
        else:
            ratios, peer_cell = ["", ""], "not installed" if not peers else "(no such setting)"
        print(f"| {tol:.0e} | {taylor.order_for(tol)} | {cells[0]} | {cells[1]} | {peer_cell} | {' | '.join(ratios)} |")

    def cheapest(method, eps):
        ok = [key for key in best if key[0] == method and error[key] <= eps]
        return min(ok, key=lambda key: best[key][0]) if ok else None

    print("\nTime to reach a final error ≤ ε: each method's cheapest tolerance that reaches it (chosen in hindsight, "
          "as in perf_reference.py's table), CPU ms (its tolerance).\n")
    print("| ε | heyoka | taylor | taylor scalar | taylor / heyoka | scalar / heyoka |")
    print("| --- | --- | --- | --- | --- | --- |")
    for eps in [10.0 ** -k for k in range(6, 14)]:
        keys = [cheapest(m, eps) for m in ("heyoka", "taylor", "scalar")]
        cells = ["not reached" if key is None else f"{best[key][0] * 1e3:.2f} ({key[1]:.0e})" for key in keys]
        ratios = ["" if keys[0] is None or key is None else f"{best[key][0] / best[keys[0]][0]:.2f}"
                  for key in keys[1:]]
        print(f"| {eps:.0e} | {' | '.join(cells)} | {' | '.join(ratios)} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer rounds")
    args = parser.parse_args()
    rounds = 5 if args.quick else 20
    print(f"# gyrolab Taylor step benchmark, load average {os.getloadavg()[0]:.1f} at start "
          "(a shared machine slows every contestant alike; minima of interleaved rounds)")
    params = compose_scene(["experiment=perf_reference"]).compiled.params
    assert params[15] == 0.0
    step_table(params, rounds)
    reference = fixed_point_reference(INERTIA, R_C, K, Y0, [0.0, T_END])[-1].astype(float)
    peer_table(params, reference, max(3, rounds // 2))
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
