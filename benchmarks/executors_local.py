"""Where should a batch's chunks run on one machine: in this process (numba's threads over every core) or on
a local Dask cluster (one single-threaded worker process per core)?

    python benchmarks/executors_local.py                 # 40,000 trajectories in 16 chunks
    python benchmarks/executors_local.py --points 200000 --chunks 40

The chunk function is ``gyrolab.batch.executors.integrate_chunk``: the default heavy top (fixed point,
uniform gravity), rk4_numba with step 0.01 over t ∈ [0, 10] (1,000 steps per trajectory), final state
only, ω0 perturbed per trajectory. Each executor runs the same chunks; the results are checked equal
bit for bit. The local cluster's time includes starting it (that is what a user waits for); its start
alone is printed too. Times are wall-clock on whatever else the machine is doing.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from omegaconf import OmegaConf

from gyrolab.batch.executors import IntegrationChunk, integrate_chunk, map_chunks
from gyrolab.engine.config import compose_config
from gyrolab.engine.scene import Scene

OVERRIDES = ["integrator=rk4_numba", "integrator.step=0.01", "time.end=10", "time.n_output=2",
             "output.euler_angles=false", "output.figures=false"]


def make_chunks(points: int, n_chunks: int) -> list[IntegrationChunk]:
    config = OmegaConf.to_container(compose_config(OVERRIDES), resolve=True)
    y0 = Scene.from_config(OmegaConf.create(config)).system.initial_state()
    rng = np.random.default_rng(0)
    states = np.tile(y0, (points, 1))
    states[:, :3] += rng.normal(scale=0.05, size=(points, 3))
    return [IntegrationChunk(config=config, initial_states=part) for part in np.array_split(states, n_chunks)]


def timed(chunks: list[IntegrationChunk], scheduler: str | None) -> tuple[float, np.ndarray]:
    out: dict[int, np.ndarray] = {}
    start = time.perf_counter()
    map_chunks(integrate_chunk, chunks, lambda i, r: out.__setitem__(i, r.y[:, -1]), scheduler=scheduler)
    return time.perf_counter() - start, np.concatenate([out[i] for i in range(len(chunks))])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=40_000)
    parser.add_argument("--chunks", type=int, default=16)
    args = parser.parse_args()
    chunks = make_chunks(args.points, args.chunks)
    integrate_chunk(IntegrationChunk(chunks[0].config, chunks[0].initial_states[:2]))  # compile/load kernels
    here, expected = timed(chunks, None)
    print(f"{args.points} trajectories, {args.chunks} chunks, {os.cpu_count()} cores")
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
