"""Speed against accuracy on the reference problem: gyrolab against scipy, as ratios measured in one run.

    python benchmarks/perf_reference.py            # full table (about a minute)
    python benchmarks/perf_reference.py --quick    # fewer tolerances, fewer repeats

Reference problem (issue 5, ``experiment=perf_reference``): nondimensional
Euler–Poisson, A, B, C = 2, 1.5, 1, r_c = (0.3, 0.2, 0.9327…), k = 0.5,
ω0 = (0.1, −0.05, 5), γ0 = (sin 1, 0, cos 1), t ∈ [0, 300]. Error = max-norm
of the final state's error against an extended-precision Taylor reference
(``gyrolab.physics.reference``; two settings of it agree to ~1e-14).

The scipy baseline is what a researcher would write: ``solve_ivp`` with a
plain numpy right-hand side. For each target error, a method's time is that
of its cheapest tolerance reaching the target (best of several runs).
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
from gyrolab.engine.batch import integrate_batch
from gyrolab.physics.reference import fixed_point_reference

INERTIA = np.array([2.0, 1.5, 1.0])
R_C = np.array([0.3, 0.2, 0.9327379053088815])
K = 0.5
Y0 = np.array([0.1, -0.05, 5.0, np.sin(1.0), 0.0, np.cos(1.0)])
T_END = 300.0
TARGETS = (1e-8, 1e-11)
BASE = ["experiment=perf_reference", "time.n_output=2"]


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


def best_time(fn, repeats):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return min(times), result


def scipy_row(method, tol, reference, repeats):
    wall, sol = best_time(lambda: solve_ivp(plain_numpy_rhs, (0, T_END), Y0, method=method, rtol=tol, atol=tol),
                          repeats)
    return {"method": f"scipy {method}", "setting": f"tol={tol:.1e}", "error": np.max(np.abs(sol.y[:, -1] - reference)),
            "time": wall, "integration": wall, "nfev": sol.nfev}


def gyrolab_row(overrides, label, setting, reference, repeats):
    scene = compose_scene(BASE + overrides)
    scene.run()  # compile / load cached kernels once
    wall, ds = best_time(scene.run, repeats)
    final = np.concatenate([ds.omega.values[-1], ds.gamma.values[-1]])
    integration = min(scene.run().attrs["integrator_wall_time"] for _ in range(repeats))
    return {"method": f"gyrolab {label}", "setting": setting, "error": np.max(np.abs(final - reference)),
            "time": wall, "integration": integration, "nfev": int(ds.attrs["integrator_nfev"])}


def cheapest(rows, prefix, target):
    ok = [r for r in rows if r["method"] == prefix and r["error"] <= target]
    return min(ok, key=lambda r: r["time"]) if ok else None


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer tolerances and repeats")
    args = parser.parse_args()
    repeats = 2 if args.quick else 5
    print(f"# gyrolab perf_reference benchmark, {datetime.date.today()}, {platform.machine()}, "
          f"{os.cpu_count()} cores, {platform.processor() or platform.platform()}, Python {platform.python_version()}")
    start = time.perf_counter()
    reference = fixed_point_reference(INERTIA, R_C, K, Y0, [0.0, T_END])[-1].astype(float)
    print(f"# reference: extended-precision Taylor, {time.perf_counter() - start:.1f} s")
    tols = [3.2e-11, 1e-14] if args.quick else [1e-9, 1e-10, 3.2e-11, 1e-11, 1e-12, 1e-13, 3.2e-14, 1e-14]
    rows = [scipy_row("DOP853", tol, reference, repeats) for tol in tols]
    rows += [scipy_row("RK45", tol, reference, max(1, repeats // 2)) for tol in (1e-9, 1e-11)]
    rows += [gyrolab_row(["integrator=dop853_numba", f"integrator.rtol={tol}", f"integrator.atol={tol}"],
                         "dop853_numba", f"tol={tol:.1e}", reference, repeats) for tol in tols]
    for tol in ([1e-10, 1e-13] if args.quick else [1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14]):
        rows.append(gyrolab_row(["integrator=taylor", f"integrator.tol={tol}"], "taylor", f"order 20, tol={tol:.0e}",
                                reference, repeats))
    for target in TARGETS:
        rows.append(gyrolab_row(["integrator=auto", f"accuracy={target}"], "auto", f"accuracy={target:.0e}",
                                reference, repeats))

    print("\n`time` is the whole call (scipy: solve_ivp; gyrolab: Scene.run(), which also builds the dataset with"
          " its invariants and metadata, ~1 ms); `integration` is gyrolab's integrator alone.\n")
    print("| method | setting | final error | time [s] | integration [s] | nfev |\n| --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r['method']} | {r['setting']} | {r['error']:.2e} | {r['time']:.4f} | {r['integration']:.4f} | "
              f"{r['nfev']} |")

    print("\n| target error | scipy DOP853 [s] | gyrolab auto, Scene.run() [s] | ratio | auto, integration [s] | ratio |"
          " goal | best gyrolab run [s] | ratio |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for target, goal in zip(TARGETS, (250, 300)):
        base = cheapest(rows, "scipy DOP853", target)
        auto = next(r for r in rows if r["setting"] == f"accuracy={target:.0e}")
        best = min((r for r in rows if r["method"].startswith("gyrolab") and r["error"] <= target),
                   key=lambda r: r["time"], default=None)
        if base is None:
            print(f"| {target:.0e} | not reached | | | | | |")
            continue
        auto_ok = auto["error"] <= target
        print(f"| {target:.0e} | {base['time']:.4f} | {auto['time']:.4f}{'' if auto_ok else ' (missed)'} | "
              f"{base['time'] / auto['time']:.0f}× | {auto['integration']:.4f} | "
              f"{base['time'] / auto['integration']:.0f}× | {goal}× | {best['time']:.4f} ({best['method']}, "
              f"{best['setting']}) | {base['time'] / best['time']:.0f}× |")
    same = [(s, g) for s in rows for g in rows if s["method"] == "scipy DOP853" and g["method"] == "gyrolab dop853_numba"
            and s["setting"] == g["setting"]]
    ratios = [s["time"] / g["time"] for s, g in same]
    # same steps ⇔ same evaluation counts (within the 3 of solve_ivp interpolating t0 itself)
    same_steps = [s["setting"] for s, g in same if abs(s["nfev"] - g["nfev"]) <= 3]
    print(f"\ncompiled DOP853 vs scipy DOP853 at equal tolerance: {min(ratios):.0f}×–{max(ratios):.0f}× faster; "
          f"same steps at {', '.join(same_steps) or 'no tolerance'} (near round-off, rounding flips accept/reject)")
    print(f"batch: 1000 trajectories, fixed-step RK4 (rk4_numba): {batch_throughput(repeats):.3g} trajectory-steps/s "
          f"(goal 1.5e7)")
    cold = cold_default_run()
    print(f"cold `gyrolab` default run, end to end: {cold[1]:.2f} s with warm kernel cache "
          f"(first process {cold[0]:.2f} s; goal 3 s)")


if __name__ == "__main__":
    main()
