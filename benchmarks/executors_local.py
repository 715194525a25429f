"""Where should a batch's chunks run on one machine: in this process (numba's threads over every core) or on
a local Dask cluster (one single-threaded worker process per core)?

    python benchmarks/executors_local.py                 # 40,000 trajectories in 16 chunks
    python benchmarks/executors_local.py --points 200000 --chunks 40

The chunks are the batch runner's own (``gyrolab.batch.runner.plan_tasks``, run by ``run_chunk``): the
default heavy top (fixed point, uniform gravity), a grid initial.theta0 × initial.r0, rk4_numba with step
0.01 over t ∈ [0, 10] (1,000 steps per trajectory), final state stored. Each executor runs the same
chunks; the results are checked equal bit for bit. The local cluster's time includes starting it (that
is what a user waits for); its start alone is printed too. Times are wall-clock on whatever else the
machine is doing.
"""

from __future__ import annotations

import argparse
import math
import os
import time

import numpy as np

from gyrolab.batch.executors import map_chunks
from gyrolab.batch.plan import plan_from_overrides
from gyrolab.batch.runner import ChunkTask, Settings, plan_tasks, run_chunk

OVERRIDES = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=10", "time.n_output=2",
             "output.euler_angles=false", "output.figures=false"]


def make_chunks(points: int, n_chunks: int) -> list[ChunkTask]:
    n_theta = max(1, round(math.sqrt(points)))
    n_r = max(1, points // n_theta)
    theta0 = ",".join(repr(0.05 + 3.0 * i / n_theta) for i in range(n_theta))
    r0 = ",".join(repr(0.5 + 9.5 * j / n_r) for j in range(n_r))
    plan = plan_from_overrides([*OVERRIDES, f"initial.theta0={theta0}", f"initial.r0={r0}"])
    return plan_tasks(plan, Settings(output="final", chunk=max(1, plan.size // n_chunks)))


def timed(chunks: list[ChunkTask], scheduler: str | None) -> tuple[float, np.ndarray]:
    out: dict[int, np.ndarray] = {}
    start = time.perf_counter()
    map_chunks(run_chunk, chunks, lambda i, r: out.__setitem__(i, r.outputs["omega"].data), scheduler=scheduler)
    return time.perf_counter() - start, np.concatenate([out[i] for i in range(len(chunks))])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=40_000)
    parser.add_argument("--chunks", type=int, default=16)
    args = parser.parse_args()
    chunks = make_chunks(args.points, args.chunks)
    run_chunk(chunks[0])  # compile/load the kernels
    here, expected = timed(chunks, None)
    points = sum(len(task.rows) for task in chunks)
    print(f"{points} trajectories, {len(chunks)} chunks, {os.cpu_count()} cores")
    print(f"in this process (numba threads): {here:.2f} s")

    from distributed import Client, LocalCluster

    from gyrolab.batch.executors import WORKER_ENV

    start = time.perf_counter()
    with LocalCluster(n_workers=os.cpu_count(), threads_per_worker=1, dashboard_address=None, env=WORKER_ENV) as c, \
            Client(c):
        started = time.perf_counter() - start
    print(f"local cluster start and stop alone: {started:.2f} s")
    local, got = timed(chunks, "local")
    assert np.array_equal(got, expected), "the local cluster's results differ from this process's"
    print(f"local Dask cluster ({os.cpu_count()} single-threaded workers), start included: {local:.2f} s; "
          "results identical bit for bit")


if __name__ == "__main__":
    main()
