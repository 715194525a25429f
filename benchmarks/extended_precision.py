"""Extended precision on a chaotic top: gyrolab's double-double Taylor against heyoka's quadruple precision.

    pip install -e ".[bench]"                         # heyoka (its rows are skipped when absent)
    python benchmarks/extended_precision.py           # about a minute
    python benchmarks/extended_precision.py --quick   # fewer settings and rounds, results not written

Scene (issue 22 item 3): the default body and forces, ``initial=slow_spin time.end=300``, state (ω, γ)
(``output.euler_angles=false``: heyoka integrates the same six equations), the scene's own output
times (``time.n_output=auto``: 2,001). Its largest Lyapunov exponent is ≈ 0.13, so an error grows like
e^{0.13 t} ≈ 10^17 over the run: double precision (ε ≈ 1e-16) cannot reach 1e-8 at t = 300.

Reference: heyoka's ``taylor_adaptive`` with ``fp_type=real128`` (IEEE quadruple, 113-bit significand,
ε ≈ 1.9e-34) at tol 1e-33, the equations written in heyoka's expression system with 1/I formed in
real128 (heyoka folds a division by a constant into a product by its reciprocal, rounded to double when
the constant is a double: that alone moves the final state by 5e-8). Cross-checked against gyrolab's
double-double kernel at tol 1e-32 (all 32 digits of its final state): their disagreement is printed.

Contestants integrate on the same 2,001 times (dense output): gyrolab ``Taylor(precision="double-double")``
(``Integrator.integrate``, outputs stored as double) over tolerances, heyoka real128 ``propagate_grid``
over tolerances (compact mode on and off), and, for where double precision ends, gyrolab's double Taylor
and heyoka in double. Error = max-norm of the final state's error against the reference. Time = CPU time
(``time.process_time``), every contestant once per round, rounds interleaved, the median over the rounds.
For a target ε each method's time is that of its cheapest setting reaching ε. Results go to
``benchmarks/results/extended_precision.json`` with the CPU, core count, load and library versions.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np

from gyrolab import compose_scene
from gyrolab.kernels import taylor_dd
from gyrolab.kernels.layout import INERTIA, N_Z, U_Z
from gyrolab.plugins.integrators.compiled_solvers import Taylor
from results_file import cpu_model  # noqa: E402  (benchmarks/ is not a package; run as a script)

SCENE = ["initial=slow_spin", "time.end=300", "output.euler_angles=false", "output.figures=false",
         "integrator=taylor", "integrator.precision=double-double"]
TARGETS = [1e-8, 1e-10, 1e-12, 1e-14]
RESULTS = Path(__file__).resolve().parent / "results" / "extended_precision.json"
HORIZON_TIMES = [0.0, 50.0, 100.0, 150.0, 200.0, 250.0, 300.0]


def heyoka_system(p: np.ndarray, fp_type):
    """The (ω, γ) equations of the packed parameters p in heyoka's expressions; 1/I in ``fp_type``."""
    import heyoka as hy

    A, B, C = (float(x) for x in p[INERTIA:INERTIA + 3])
    u0, u1, u2 = (float(x) for x in p[U_Z:U_Z + 3])
    k = float(p[N_Z])
    w0, w1, w2, g0, g1, g2 = hy.make_vars("w0", "w1", "w2", "g0", "g1", "g2")

    def inverse(x):
        return hy.expression(fp_type(1) / fp_type(x))

    return [(w0, ((B - C) * w1 * w2 + u1 * g2 - u2 * g1 + k * (C - B) * g1 * g2) * inverse(A)),
            (w1, ((C - A) * w2 * w0 + u2 * g0 - u0 * g2 + k * (A - C) * g2 * g0) * inverse(B)),
            (w2, ((A - B) * w0 * w1 + u0 * g1 - u1 * g0 + k * (B - A) * g0 * g1) * inverse(C)),
            (g0, g1 * w2 - g2 * w1), (g1, g2 * w0 - g0 * w2), (g2, g0 * w1 - g1 * w0)]


def heyoka_contestant(p, y0, grid, tol, fp_type, compact):
    """(callable returning the final state as float64 and, with ``exact=True``, as fp_type; order)."""
    import heyoka as hy

    ta = hy.taylor_adaptive(heyoka_system(p, fp_type), np.array(y0, dtype=fp_type), tol=fp_type(tol),
                            fp_type=fp_type, compact_mode=compact)
    start = np.array(y0, dtype=fp_type)
    times = np.array(grid, dtype=fp_type)

    def call(exact=False):
        ta.time = fp_type(grid[0])
        ta.state[:] = start
        out = ta.propagate_grid(times)[-1]
        final = out[-1]
        return final if exact else np.array([float(x) for x in final])
    return call, ta.order


def interleaved(contestants, rounds):
    """Median CPU time and the last result of each callable, every one once per round."""
    times = {key: [] for key in contestants}
    results = {}
    for _ in range(rounds):
        for key, fn in contestants.items():
            start = time.process_time()
            results[key] = fn()
            times[key].append(time.process_time() - start)
    return {key: (float(np.median(v)), results[key]) for key, v in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer settings and rounds")
    args = parser.parse_args()
    rounds = 3 if args.quick else 7
    load_start = os.getloadavg()
    print(f"# gyrolab extended-precision benchmark, {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, "
          f"{cpu_model()}, {os.cpu_count()} cores, load average {load_start[0]:.2f} at start")
    scene = compose_scene(SCENE)
    p, y0, grid = scene.compiled.params, scene.system.initial_state(), scene.times
    compiled = scene.compiled
    try:
        import heyoka as hy
    except ImportError:
        hy = None
    versions = {"python": platform.python_version(), "numpy": np.__version__, "numba": version("numba"),
                "gyrolab": version("gyrolab"), "heyoka": version("heyoka") if hy else None}

    # the reference, and its cross-check
    dd_hi, dd_lo = taylor_dd.propagate(p, 1e-32, grid[[0, -1]], y0)
    if hy is not None:
        start = time.process_time()
        ref_call, ref_order = heyoka_contestant(p, y0, grid, 1e-33, hy.real128, True)
        exact = ref_call(exact=True)
        reference = np.array([float(x) for x in exact])
        disagreement = max(abs(float(exact[i] - hy.real128(dd_hi[-1, i]) - hy.real128(dd_lo[-1, i]))) for i in range(6))
        reference_note = (f"heyoka real128 tol=1e-33 (order {ref_order}), {time.process_time() - start:.2f} s; "
                          f"gyrolab double-double tol=1e-32 differs from it by {disagreement:.1e} at t = 300")
    else:
        reference = dd_hi[-1]
        disagreement = None
        reference_note = "gyrolab double-double tol=1e-32 (heyoka not installed: no independent reference)"
    print(f"# reference: {reference_note}")

    contestants, settings = {}, {}
    dd_tols = [1e-18, 1e-22, 1e-26, 1e-30] if args.quick else [10.0 ** -k for k in range(16, 33)]
    for tol in dd_tols:
        method = Taylor(precision="double-double", tol=tol)
        key = ("gyrolab taylor double-double", tol)
        contestants[key] = lambda m=method: m.integrate(None, grid, y0, None, compiled).y[-1]
        settings[key] = f"tol={tol:.0e}, order {method.order}"
    double = Taylor(tol=1e-16)
    contestants[("gyrolab taylor double", 1e-16)] = lambda: double.integrate(None, grid, y0, None, compiled).y[-1]
    settings[("gyrolab taylor double", 1e-16)] = f"tol=1e-16, order {double.order}"
    if hy is not None:
        hy_tols = [1e-18, 1e-22, 1e-26, 1e-30] if args.quick else [10.0 ** -k for k in range(16, 34)]
        for tol in hy_tols:
            for compact in (True, False):
                key = (f"heyoka real128{' compact' if compact else ''}", tol)
                contestants[key], order = heyoka_contestant(p, y0, grid, tol, hy.real128, compact)
                settings[key] = f"tol={tol:.0e}, order {order}"
        for tol in (1e-16, float(np.finfo(float).eps)):
            key = ("heyoka double", tol)
            contestants[key], order = heyoka_contestant(p, y0, grid, tol, float, False)
            settings[key] = f"tol={tol:.1e}, order {order}"
    interleaved(contestants, 1)  # compile, load caches
    measured = interleaved(contestants, rounds)
    errors = {key: float(np.max(np.abs(np.asarray(result, dtype=float) - reference)))
              for key, (_, result) in measured.items()}

    print(f"\nEvery setting ({len(grid)} output times, t ∈ [0, 300]; CPU ms, median of {rounds} interleaved rounds):\n")
    print("| method | setting | final error | CPU time [ms] |\n| --- | --- | --- | --- |")
    rows = []
    for key in sorted(measured, key=lambda key: (key[0], -key[1])):
        print(f"| {key[0]} | {settings[key]} | {errors[key]:.1e} | {measured[key][0] * 1e3:.1f} |")
        rows.append({"method": key[0], "setting": settings[key], "tol": key[1], "final_error": errors[key],
                     "cpu_ms": measured[key][0] * 1e3})

    def cheapest(prefix, eps):
        """The fastest setting reaching eps of the methods named ``prefix`` (or ``prefix compact``)."""
        ok = [key for key in measured if key[0] in (prefix, f"{prefix} compact") and errors[key] <= eps]
        return min(ok, key=lambda key: measured[key][0]) if ok else None

    print("\nCPU time to reach a final error ≤ ε, ms (setting):\n")
    print("| ε | gyrolab double-double | heyoka real128 | gyrolab / heyoka | gyrolab double |\n"
          "| --- | --- | --- | --- | --- |")
    targets = []
    for eps in TARGETS:
        g, h, d = (cheapest(prefix, eps) for prefix in ("gyrolab taylor double-double", "heyoka real128",
                                                         "gyrolab taylor double"))

        def cell(key):
            if key is None:
                return "not reached"
            mode = "compact, " if key[0].endswith("compact") else ""
            return f"{measured[key][0] * 1e3:.1f} ({mode}{settings[key]}, error {errors[key]:.0e})"
        ratio = measured[g][0] / measured[h][0] if g and h else None
        print(f"| {eps:.0e} | {cell(g)} | {cell(h)} | {'' if ratio is None else f'{ratio:.3f}'} | {cell(d)} |")
        targets.append({"epsilon": eps, "gyrolab_dd": None if g is None else {"setting": settings[g],
                                                                               "cpu_ms": measured[g][0] * 1e3,
                                                                               "final_error": errors[g]},
                        "heyoka_real128": None if h is None else {"method": h[0], "setting": settings[h],
                                                                  "cpu_ms": measured[h][0] * 1e3,
                                                                  "final_error": errors[h]},
                        "ratio_gyrolab_over_heyoka": ratio})

    # where double precision ends: the error along the run, against the real128 reference on a coarse grid
    horizon = {}
    if hy is not None:
        ta_grid = np.array(HORIZON_TIMES)
        ta = hy.taylor_adaptive(heyoka_system(p, hy.real128), np.array(y0, dtype=hy.real128),
                                tol=hy.real128(1e-33), fp_type=hy.real128, compact_mode=True)
        exact_along = ta.propagate_grid(np.array(ta_grid, dtype=hy.real128))[-1]
        along = np.array([[float(x) for x in row] for row in exact_along])
        runs = {"gyrolab taylor double tol=1e-16": Taylor(tol=1e-16),
                "gyrolab taylor double-double tol=1e-26": Taylor(precision="double-double", tol=1e-26)}
        print("\nError along the run (max-norm against the real128 reference at tol 1e-33; outputs rounded to double "
              "unless all digits are said):\n")
        print(f"| method | {' | '.join(f't={t:g}' for t in HORIZON_TIMES[1:])} |\n| --- |{' --- |' * (len(HORIZON_TIMES) - 1)}")
        for name, method in runs.items():
            y = method.integrate(None, ta_grid, y0, None, compiled).y
            err = np.max(np.abs(y - along), axis=1)[1:]
            horizon[name] = dict(zip(map(str, HORIZON_TIMES[1:]), map(float, err)))
            print(f"| {name} | {' | '.join(f'{e:.1e}' for e in err)} |")
        for tol in (1e-26, 1e-32):  # every digit: the double-double state (high + low parts) against real128
            hi, lo = taylor_dd.propagate(p, tol, ta_grid, y0)
            err = [max(abs(float(exact_along[r][i] - hy.real128(hi[r, i]) - hy.real128(lo[r, i]))) for i in range(6))
                   for r in range(1, len(ta_grid))]
            name = f"gyrolab double-double tol={tol:.0e}, all 32 digits"
            horizon[name] = dict(zip(map(str, HORIZON_TIMES[1:]), err))
            print(f"| {name} | {' | '.join(f'{e:.1e}' for e in err)} |")
    load_end = os.getloadavg()
    print(f"\nload average {load_end[0]:.2f} at the end; versions: {versions}")
    if args.quick:
        print(f"(--quick: {RESULTS.name} not rewritten)")
        return
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps({
        "date_utc": f"{datetime.datetime.now(datetime.UTC):%Y-%m-%dT%H:%MZ}", "cpu_model": cpu_model(),
        "cores": os.cpu_count(), "load_average_start": load_start, "load_average_end": load_end,
        "versions": versions, "scene": SCENE, "n_output": len(grid), "rounds": rounds,
        "clock": "time.process_time, median of interleaved rounds", "reference": reference_note,
        "reference_cross_check": disagreement, "settings": rows, "targets": targets, "error_along_the_run": horizon,
    }, indent=2) + "\n")
    print(f"written {RESULTS.relative_to(Path.cwd()) if RESULTS.is_relative_to(Path.cwd()) else RESULTS}")


if __name__ == "__main__":
    main()
