"""How ``gyrolab --batch`` scales with the number of points (issue 14's targets).

    python benchmarks/batch_scaling.py                 # N = 1e3, 1e4, 1e5, 1e6 (a few minutes)
    python benchmarks/batch_scaling.py --sizes 1000 10000

Each N runs in a fresh process (its peak memory is its own): the default body and forces, a grid
initial.theta0 × initial.r0 of N points, t ∈ [0, 10], integrator rk4_numba with step 0.01, 101 output times
(10 steps between samples), ``batch.output=reductions`` (final state, invariant drifts, max |θ − θ0|),
written to ``sweep.nc`` in a temporary directory. The numba kernels are compiled (and cached) by a warm-up
run of N = 100 first, as a user's second run would find them.

What the columns measure (printed under the table too):
  process wall   the whole child process, as a user's command: Python start-up, imports, plan, chunks, file;
  start-up       the process wall before ``run_batch`` is called (interpreter, imports of gyrolab, numba, xarray,
                 parsing the swept values);
  plan           ``make_plan`` (one Hydra composition, parsing the swept values, initial states, checks);
  in kernels     inside ``integrate_arrays`` (the compiled RK4 kernel; its first call loads it from numba's cache,
                 which is included), summed over chunks;
  outputs        the chunks' other work: final-state variables, the compiled reductions;
  store + rest   writing, syncing and journaling the chunks, creating and closing the file, choosing chunks,
                 the interpreter's exit (its final garbage collection: 0.5 s or more);
  kernel share   in kernels / process wall (the issue's target: ≥ 50 % at N = 10⁵);
  peak memory    the child's ``ru_maxrss``.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FIXED = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=10", "time.n_output=101",
         "output.euler_angles=false", "output.figures=false", "batch.output=reductions"]


def grid(n: int) -> list[str]:
    """``initial.theta0`` × ``initial.r0`` with about n points (θ0 in (0, π), r0 in [0.5, 10])."""
    n_theta = max(1, int(round(math.sqrt(n))))
    n_r = max(1, n // n_theta)
    thetas = [0.05 + (3.0 - 0.05) * i / max(n_theta - 1, 1) for i in range(n_theta)]
    rates = [0.5 + (10.0 - 0.5) * j / max(n_r - 1, 1) for j in range(n_r)]
    return [f"initial.theta0={','.join(repr(t) for t in thetas)}", f"initial.r0={','.join(repr(r) for r in rates)}"]


def child(n: int, out: str, launched: float) -> None:
    from gyrolab.batch.plan import split_overrides
    from gyrolab.batch.sweep import run_batch

    fixed, dims = split_overrides(FIXED + grid(n))
    start = time.time()
    stats = run_batch(fixed, dims, Path(out) / "sweep.nc")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux -> MiB
    print(json.dumps({"n": math.prod(len(d.values) for d in dims), "startup_s": start - launched,
                      "batch_s": time.time() - start, "plan_s": stats.plan_time, "kernel_s": stats.kernel_time,
                      "outputs_s": stats.chunk_time - stats.kernel_time, "chunks": stats.chunks, "peak_mib": peak}))


def run(n: int) -> dict:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        launched = time.time()
        done = subprocess.run([sys.executable, __file__, "--child", str(n), out, repr(launched)], capture_output=True,
                              text=True)
        wall = time.perf_counter() - start
        if done.returncode:
            raise SystemExit(done.stderr[-3000:])
        row = json.loads(done.stdout.strip().splitlines()[-1])
    row["wall_s"] = wall
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sizes", type=int, nargs="*", default=[1000, 10_000, 100_000, 1_000_000])
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(int(args.child[0]), args.child[1], float(args.child[2]))
        return
    run(100)  # compiles and caches the kernels
    print("| N | process wall (s) | start-up (s) | plan (s) | in kernels (s) | outputs (s) | store + rest (s) | "
          "kernel share | µs per point | peak memory (MiB) |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in args.sizes:
        r = run(n)
        rest = r["wall_s"] - r["startup_s"] - r["plan_s"] - r["kernel_s"] - r["outputs_s"]
        print(f"| {r['n']:,} | {r['wall_s']:.1f} | {r['startup_s']:.1f} | {r['plan_s']:.1f} | {r['kernel_s']:.1f} | "
              f"{r['outputs_s']:.1f} | {rest:.1f} | {100 * r['kernel_s'] / r['wall_s']:.0f} % | "
              f"{1e6 * r['wall_s'] / r['n']:.0f} | {r['peak_mib']:.0f} |", flush=True)
    print("\nprocess wall: the whole child process (Python start-up, imports, plan, chunks, file, exit), as a "
          "user's command;\nstart-up: the process wall before run_batch is called (imports, parsing the swept values); "
          "in kernels: inside\nintegrate_arrays (its first call loads the cached kernel, included); outputs: the "
          "chunks' final variables and\nreductions; store + rest: the rest (writing, syncing, journaling, the file's "
          "creation and closing, the\ninterpreter's exit); kernel share = in kernels / process wall.")


if __name__ == "__main__":
    main()
