"""Large sweeps in one command: ``gyrolab batch KEY=V1,V2 ...`` writes ``<dir>/sweep.nc`` (docs/batch.md): the plan,
run in chunks, streamed to one resumable dataset; only body, initial-state and force parameters may vary.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import netCDF4

from gyrolab.batch import executors
from gyrolab.batch.plan import Dim, Plan, make_plan, split_overrides
from gyrolab.batch.runner import RunStats, Settings, run_plan
from gyrolab.batch.scheduler import probe
from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import VARIATIONAL
from gyrolab.errors import ConfigError
from gyrolab.output.lock import writing_in

SWEEP_NAME = "sweep.nc"


def run_batch_sweep(overrides: Sequence[str], out_dir: Path) -> Path:
    """Run the grid of ``overrides`` as one batch; write (or resume) and return ``out_dir/sweep.nc``, the folder
    locked meanwhile (a second batch into it is refused in one sentence)."""
    fixed, dims = split_overrides(overrides)
    return run_batch(fixed, dims, Path(out_dir) / SWEEP_NAME).path


def failed_points(path: Path) -> str | None:
    """One sentence when points of the finished batch at ``path`` failed (the command then exits 1), else None."""

    with netCDF4.Dataset(path, "r") as nc:
        failed, total = int(getattr(nc, "n_failed", 0)), int(getattr(nc, "n_points", 0))
    if not failed:
        return None
    return (f"{failed} of {total} points failed; their errors are error_message[job_error] where job_status is 2 "
            f"in {path}")


def run_batch(fixed: Sequence[str], dims: Sequence[Dim], path: Path, *,
              plain: dict[str, Any] | None = None, lock: bool = True) -> RunStats:
    """The batch of grid ``dims`` over the config of ``fixed`` (or ``plain``), stored at ``path``; its
    directory is locked meanwhile unless ``lock`` is False (the caller holds the lock)."""
    start = time.perf_counter()
    plan = make_plan(fixed, dims, plain=plain)
    settings = Settings.from_config(plan.plain.get("batch"))
    check_integrator(plan, settings)
    if executors.scheduler_kind(settings.scheduler) == "address":   # a bad peer is refused before any directory
        probe(str(settings.scheduler), settings.scheduler_source, executors.CONNECT_TIMEOUT)
    plan_time = time.perf_counter() - start
    # locked after the cheap checks: a bad grid leaves no directory
    with writing_in(path.parent, "sweep directory") if lock else contextlib.nullcontext():
        stats = run_plan(plan, path, settings)
    stats.plan_time = plan_time
    return stats


def check_integrator(plan: Plan, settings: Settings) -> None:
    """Refuse, in one sentence, an integrator without VARIATIONAL for the chaos indicators (``batch.output=indicator``);
    any integrator runs the other outputs (one without a batch kernel: one ``integrate`` call per point)."""

    if settings.output == "indicator" and not plan.integrator_class.supports(VARIATIONAL):
        raise ConfigError(f"integrator {plan.integrator_class.name!r} has no variational equations (capability "
                          f"{VARIATIONAL}), which the chaos indicators of batch.output=indicator need; valid choices: "
                          f"{or_list(integrators_with(VARIATIONAL))}")
