"""Large sweeps in one process: every grid point integrated by one batch call, the same ``sweep.nc``.

``gyrolab --batch body.a=range(1.5,2.5,0.01) initial.r0=1,2,5 ...`` composes the config once,
applies each grid point's overrides to the resolved config (no per-point Hydra composition,
which dominates small jobs), builds and validates each point's scene (an invalid point is a
failed job, as in a multirun), integrates all valid points together
(``gyrolab.engine.batch.integrate_batch``: the compiled, vectorised RK4 path for fixed-step RK4, one
run per point otherwise) and assembles ``sweep.nc`` with ``gyrolab.sweep.aggregate.assemble``.
Only parameters of the body, the initial state and the forces may vary: the system, the forces'
list, the integrator and the output times are one for the whole batch.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from omegaconf import DictConfig, OmegaConf

from gyrolab.engine.batch import integrate_batch
from gyrolab.engine.config import compose_config
from gyrolab.contracts.integrator import IntegratorStats, Solution
from gyrolab.output.dataset import build_dataset, write_dataset
from gyrolab.output.lock import writing_in
from gyrolab.errors import ConfigError, GyrolabError
from gyrolab.engine.scene import Scene
from gyrolab.sweep.aggregate import FAILED, FINISHED, JobResult, assemble
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import job_identity

log = logging.getLogger(__name__)
VARIABLE_SECTIONS = ("body.", "initial.", "force.")


def run_batch_sweep(overrides: Sequence[str], out_dir: Path) -> Path:
    """Run the grid of ``overrides`` as one batch; write and return ``out_dir/sweep.nc``.

    ``out_dir`` is locked meanwhile (a second batch into it is refused in one sentence) and cleared
    of the temporary files that killed writes left there.
    """
    grid = Grid.from_overrides(overrides)
    for dim in grid.dims:
        if not dim.key.lstrip("+~").startswith(VARIABLE_SECTIONS):
            raise ConfigError(f"a batch sweep varies body, initial and force parameters only, not {dim.key!r}; "
                              "sweep it with gyrolab -m instead")
    base = compose_config(list(grid.jobs[0]))
    with writing_in(out_dir, "sweep directory"):  # after the cheap checks: a bad grid leaves no directory
        return _integrate_and_write(grid, base, Path(out_dir))


def _integrate_and_write(grid: Grid, base: DictConfig, out_dir: Path) -> Path:
    plain = OmegaConf.to_container(base, resolve=True)
    start = time.perf_counter()
    scenes: list[Scene | None] = []
    results = [JobResult() for _ in grid.jobs]
    swept = {dim.key: dim for dim in grid.dims}
    for n, job in enumerate(grid.jobs):
        cfg = OmegaConf.create(plain)  # the fixed overrides are in it already; apply the swept ones
        for override in job:
            key, _, label = override.partition("=")
            if key in swept:
                value = swept[key].values[swept[key].labels.index(label)]
                OmegaConf.update(cfg, key.lstrip("+~"), value, merge=False, force_add=key.startswith("+"))
        try:
            scenes.append(Scene.from_config(cfg))
        except GyrolabError as error:
            scenes.append(None)
            results[n] = JobResult(status=FAILED, error=str(error), error_type=type(error).__name__,
                                   exit_code=error.exit_code, job_id=job_identity(cfg))
    valid = [n for n, scene in enumerate(scenes) if scene is not None]
    log.info("batch sweep: %d points, %d valid, scenes built in %.1f s", len(scenes), len(valid),
             time.perf_counter() - start)
    if valid:
        _share_output_times([scenes[n] for n in valid])
        first = scenes[valid[0]]
        params = None
        if first.system.compiled_model() is not None:
            params = np.stack([scenes[n].system.compiled_model().params for n in valid])
        y0s = np.stack([scenes[n].system.initial_state() for n in valid])
        batch = integrate_batch(first, y0s, params)
        log.info("batch sweep: integrated %d trajectories in %.2f s (%.3g trajectory-steps/s)", len(valid),
                 batch.wall_time, batch.trajectory_steps_per_second)
        share = batch.wall_time / len(valid)
        for row, n in enumerate(valid):
            stats = IntegratorStats(nfev=4 * batch.n_steps, n_steps=batch.n_steps, n_rejected=0, wall_time=share) \
                if first.integrator.name in ("rk4", "rk4_numba") else IntegratorStats(0, batch.n_steps, None, share)
            ds = build_dataset(scenes[n], Solution(batch.t, batch.y[row], stats))
            ds.attrs["hydra_overrides"] = " ".join(grid.jobs[n])
            ds.attrs["batch"] = 1
            results[n] = JobResult(status=FINISHED, dataset=ds, job_id=job_identity(scenes[n].config))
    sweep = assemble(grid, results)
    sweep.attrs["sweep_launcher"] = "batch"
    return write_dataset(sweep, Path(out_dir) / "sweep.nc")


def _share_output_times(scenes: Sequence[Scene]) -> None:
    """One output grid for the batch: with ``time.n_output: auto`` the points' own grids may differ (a faster
    spin needs more samples), so every point gets the densest of them (the same span, so no point undersamples)."""
    densest = max(scenes, key=lambda scene: len(scene.times)).times
    for scene in scenes:
        scene.times = densest

