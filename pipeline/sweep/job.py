"""One job of a sweep: skip it if its result is already there, otherwise run it and record how it ended.

A failing job is recorded, not fatal: the error goes into the job's record
(and, through the aggregator, into ``sweep.nc``'s table of failed jobs) and
the sweep goes on.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from pathlib import Path

from omegaconf import DictConfig

from gyrolab.errors import GyrolabError
from gyrolab.sweep.identity import code_version, job_identity
from gyrolab.sweep.record import FAILED, FINISHED, JobRecord, read_record, remove_record, write_record

log = logging.getLogger("gyrolab.sweep")


def run_sweep_job(cfg: DictConfig, job_dir: Path, overrides: Sequence[str], job_num: int | None,
                  work: Callable[[str], Path]) -> JobRecord:
    """Run ``work(job_id)`` (which writes the job's dataset and returns its path) unless already done.

    Never raises for a failing scene: a GyrolabError is recorded as a
    deterministic failure (the same config and code fail the same way, so it
    is not retried); any other exception is recorded too, with its traceback
    in the job's log, and retried when the sweep is run again.
    """
    job_dir = Path(job_dir)
    code = code_version()
    try:
        job_id = job_identity(cfg, code)
    except Exception as error:  # noqa: BLE001 - e.g. an interpolation that does not resolve: the job fails
        record = _failed(JobRecord(job_id="", status=FAILED, overrides=list(overrides), code_version=code,
                                   job_num=job_num), error, 2, deterministic=False)
        log.error("job %s failed: its config does not resolve: %s", job_num, record.error)
        write_record(job_dir, record)
        return record
    previous = read_record(job_dir)
    if previous is not None and previous.reusable_for(job_id, job_dir):
        log.info("job %s: %s earlier (job id %s); skipped", job_num, previous.status, job_id)
        previous.skipped, previous.job_num, previous.overrides = True, job_num, list(overrides)
        write_record(job_dir, previous)
        return previous
    remove_record(job_dir)  # a stale record (other config or code) must not outlive this attempt
    for leftover in job_dir.glob(".*.tmp"):  # temporary files of a job killed while writing
        leftover.unlink(missing_ok=True)
    base = JobRecord(job_id=job_id, status=FAILED, overrides=list(overrides), code_version=code, job_num=job_num)
    try:
        path = work(job_id)
    except GyrolabError as error:
        log.error("job %s failed: %s", job_num, error)
        record = _failed(base, error, error.exit_code, deterministic=True)
    except Exception as error:  # noqa: BLE001 - a bug in one job must not take the sweep down
        log.exception("job %s crashed", job_num)
        record = _failed(base, error, 1, deterministic=False)
    else:
        base.status, base.run = FINISHED, Path(path).name
        record = base
    if record.status == FAILED:
        (job_dir / "run.nc").unlink(missing_ok=True)  # no partial or stale output next to a failure
    write_record(job_dir, record)
    return record


def _failed(base: JobRecord, error: Exception, exit_code: int, *, deterministic: bool) -> JobRecord:
    message = " ".join(str(error).split()) or type(error).__name__
    base.status, base.error, base.error_type = FAILED, message, type(error).__name__
    base.exit_code, base.deterministic = int(exit_code), deterministic
    return base
