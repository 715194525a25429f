"""One job of a sweep: skip it if its result is already there, otherwise run it, its directory locked, and record how
it ended; a failing job is recorded, not fatal, and a write failure is retried when the sweep is run again.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from pathlib import Path

from omegaconf import DictConfig

from gyrolab.errors import GyrolabError, OutputError
from gyrolab.output.lock import clear_temporaries, owner_of, try_lock, unlock
from gyrolab.sweep.identity import code_version, job_code, job_identity
from gyrolab.sweep.orphans import guard_worker
from gyrolab.sweep.record import ELSEWHERE, FAILED, FINISHED, RECORD_NAME, JobRecord, read_record, write_record

log = logging.getLogger("gyrolab.sweep")


def run_sweep_job(cfg: DictConfig, job_dir: Path, overrides: Sequence[str], job_num: int | None,
                  work: Callable[[str], Path]) -> JobRecord:
    """Run ``work(job_id)`` (which writes the job's dataset and returns its path) unless already done; never raises
    for a failing scene. A GyrolabError is recorded as a deterministic failure (not retried) except a write failure
    (``OutputError``: the disk may have room next time); any other exception is recorded, with its traceback in the
    job's log, and retried. A job another live process runs is left to it (``ELSEWHERE``, nothing written)."""
    job_dir = Path(job_dir)
    guard_worker()  # in a launcher's worker process: die with the launching process
    try:
        if not try_lock(job_dir):
            owner = owner_of(job_dir)
            log.warning("job %s is being run by another gyrolab process%s; left to it", job_num,
                        f" ({owner})" if owner else "")
            return JobRecord(job_id="", status=ELSEWHERE, overrides=list(overrides), code_version="",
                             job_num=job_num, skipped=True)
    except OutputError as error:  # the job directory cannot even hold a lock file: nothing can be written
        log.error("job %s failed: %s", job_num, error)
        return _failed(JobRecord("", FAILED, list(overrides), "", job_num), error, error.exit_code,
                       deterministic=False)
    try:
        clear_temporaries(job_dir)
        return _run_locked(cfg, job_dir, overrides, job_num, work)
    finally:
        unlock(job_dir)


def _run_locked(cfg: DictConfig, job_dir: Path, overrides: Sequence[str], job_num: int | None,
                work: Callable[[str], Path]) -> JobRecord:
    code = code_version()
    try:
        job_id = job_identity(cfg, code)
        code = job_code(cfg, code)  # what the identity covers: gyrolab's code and the plugins the job names
    except Exception as error:  # noqa: BLE001 - e.g. an interpolation that does not resolve: the job fails
        record = _failed(JobRecord(job_id="", status=FAILED, overrides=list(overrides), code_version=code,
                                   job_num=job_num), error, 2, deterministic=False)
        log.error("job %s failed: its config does not resolve: %s", job_num, record.error)
        return _recorded(job_dir, record)
    previous = read_record(job_dir)
    if previous is not None and previous.reusable_for(job_id, job_dir):
        log.info("job %s: %s earlier (job id %s); skipped", job_num, previous.status, job_id)
        return mark_skipped(job_dir, previous, job_num, overrides)
    (job_dir / RECORD_NAME).unlink(missing_ok=True)  # no stale record (other config or code) outlives this try
    base = JobRecord(job_id=job_id, status=FAILED, overrides=list(overrides), code_version=code, job_num=job_num)
    try:
        path = work(job_id)
    except GyrolabError as error:   # a failed write (OutputError) may succeed next time: not deterministic
        log.error("job %s failed: %s", job_num, error)
        record = _failed(base, error, error.exit_code, deterministic=not isinstance(error, OutputError))
    except Exception as error:  # noqa: BLE001 - a bug in one job must not take the sweep down
        log.exception("job %s crashed", job_num)
        record = _failed(base, error, 1, deterministic=False)
    else:
        base.status, base.run = FINISHED, Path(path).name
        record = base
    if record.status == FAILED:
        (job_dir / "run.nc").unlink(missing_ok=True)  # no partial or stale output next to a failure
    return _recorded(job_dir, record)


def mark_skipped(job_dir: Path, record: JobRecord, job_num: int | None, overrides: Sequence[str]) -> JobRecord:
    """Record that this session found the job settled (``record``) and did not run it again."""
    if record.skipped and record.job_num == job_num and record.overrides == list(overrides):
        return record  # already says so: nothing to write
    record.skipped, record.job_num, record.overrides = True, job_num, list(overrides)
    return _recorded(job_dir, record)


def _recorded(job_dir: Path, record: JobRecord) -> JobRecord:
    """Write the job's record; if even that fails (a full disk), say so: the job reruns next time."""
    try:
        write_record(job_dir, record)
    except OutputError as error:
        log.error("job %s: %s; it will run again when the sweep is resumed", record.job_num, error)
    return record


def _failed(base: JobRecord, error: Exception, exit_code: int, *, deterministic: bool) -> JobRecord:
    message = " ".join(str(error).split()) or type(error).__name__
    base.status, base.error, base.error_type = FAILED, message, type(error).__name__
    base.exit_code, base.deterministic = int(exit_code), deterministic
    return base
