"""Per-job overhead of a sweep with Hydra's basic launcher (issue 24 item 3), CPU time.

    python benchmarks/sweep_overhead.py                 # the default sweep (no per-job figures)
    python benchmarks/sweep_overhead.py --job-figures   # also with output.job_figures=true, for comparison
    python benchmarks/sweep_overhead.py --repeats 5     # the sweep run 5 times (default 3), the median kept

Runs ``gyrolab -m time.end=1 time.n_output=101 initial.r0=1,2,...,20`` in a fresh process and takes its CPU
time (user + system, the process and its children). The jobs' own work is one ``Scene.run()`` each, measured
in this process on the same config (median of 20 after a warm-up); the overhead per job is
(sweep CPU − 20 × that) / 20, everything else: Python and gyrolab start-up, Hydra's composition of the jobs,
the records, writing ``run.nc``, the sweep's aggregation and figures. Target: ≤ 0.2 s per job.
CPU time, not wall time: the development machine is shared, and wall times there mean little. Each sweep
runs ``--repeats`` times in fresh processes; the verdict is on the median. The numbers go to
``benchmarks/results/sweep_overhead.json`` with the machine (``results_file.write_results``).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from results_file import write_results  # noqa: E402  (benchmarks/ is not a package)

JOBS = 20
SWEEP = ["time.end=1", "time.n_output=101", "initial.r0=" + ",".join(str(r) for r in range(1, JOBS + 1))]
TARGET = 0.2


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def sweep_cpu(extra: list[str]) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        before = children_cpu()
        subprocess.run([sys.executable, "-m", "gyrolab", "-m", *SWEEP, *extra, f"hydra.sweep.dir={tmp}/sweep"],
                       check=True, capture_output=True, cwd=tmp, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        return children_cpu() - before


def job_cpu() -> float:
    from gyrolab import compose_scene

    scene = compose_scene(["time.end=1", "time.n_output=101", "initial.r0=10"])
    scene.run()
    times = []
    for _ in range(20):
        start = time.process_time()
        scene.run()
        times.append(time.process_time() - start)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--job-figures", action="store_true", help="also measure with output.job_figures=true")
    parser.add_argument("--repeats", type=int, default=3, help="sweeps per variant (the median is kept)")
    args = parser.parse_args()
    print(f"# load average {os.getloadavg()[0]:.1f} at start, {os.cpu_count()} cores")
    run = job_cpu()
    print(f"one job's Scene.run(): {run * 1e3:.1f} ms CPU (median of 20)")
    variants = [("default", [])] + ([("output.job_figures=true", ["output.job_figures=true"])]
                                    if args.job_figures else [])
    rows, numbers = [], {"jobs": JOBS, "sweep": " ".join(SWEEP), "scene_run_s": run, "target_s": TARGET,
                         "repeats": args.repeats, "variants": {}}
    for name, extra in variants:
        totals = [sweep_cpu(extra) for _ in range(args.repeats)]
        total = float(np.median(totals))
        overhead = (total - JOBS * run) / JOBS
        print(f"{name}: sweep {total:.2f} s CPU (median of {args.repeats}: "
              f"{', '.join(f'{t:.2f}' for t in totals)}), overhead {overhead:.3f} s per job")
        numbers["variants"][name] = {"sweep_cpu_s": totals, "sweep_cpu_median_s": total, "overhead_per_job_s": overhead}
        rows.append([name, f"{total:.2f}", f"{overhead:.3f}"])
    verdict = numbers["variants"]["default"]["overhead_per_job_s"]
    numbers["verdict"] = "PASS" if verdict <= TARGET else "FAIL"
    print(f"{numbers['verdict']}: default sweep overhead {verdict:.3f} s per job (target ≤ {TARGET} s)")
    write_results("sweep_overhead", numbers, {"sweep_overhead": {
        "caption": f"`gyrolab -m {' '.join(SWEEP)}` with Hydra's basic launcher: CPU time of the whole sweep "
                   f"(median of {args.repeats} fresh processes) and its overhead per job beyond one `Scene.run()` "
                   f"({run * 1e3:.1f} ms); target ≤ {TARGET} s per job",
        "header": ["sweep", "sweep CPU (s)", "overhead per job (s)"], "rows": rows}},
        summary=[[f"a {JOBS}-job sweep's overhead per job, Hydra's basic launcher (CPU)", f"{verdict:.3f} s",
                  f"≤ {TARGET} s", numbers["verdict"]]])


if __name__ == "__main__":
    main()
