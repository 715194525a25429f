"""A job's record, ``job.json`` next to its ``run.nc``: what ran, with which identity, and how it ended. Written
(atomically) after ``run.nc``; a job without a complete record is recomputed when the sweep is run again.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterator
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from gyrolab.errors import ConfigError
from gyrolab.output.atomic import atomic_open
from gyrolab.output.trust import open_own_file

#: a job's record is a few hundred bytes; a larger file is not gyrolab's
MAX_RECORD_BYTES = 1024 * 1024

RECORD_NAME = "job.json"
FINISHED, FAILED = "finished", "failed"
#: status of a job that another live process is running (returned, never written)
ELSEWHERE = "running elsewhere"


@dataclass
class JobRecord:
    job_id: str
    status: str                          # FINISHED or FAILED
    overrides: list[str]                 # the job's Hydra overrides, as the sweeper built them
    code_version: str
    job_num: int | None = None
    run: str | None = None               # dataset file name in the job directory (finished jobs)
    error: str = ""                      # one sentence (failed jobs)
    error_type: str = ""
    exit_code: int = 0                   # what the single-run command would have exited with
    deterministic: bool = True           # False: an unexpected error, retried when the sweep is run again
    skipped: bool = False                # True: this session found the job finished and did not rerun it

    def reusable_for(self, job_id: str, job_dir: Path) -> bool:
        """Whether this record settles a job of identity ``job_id``: same identity, and its result is still there."""
        if self.job_id != job_id:
            return False
        if self.status == FINISHED:
            return self.run is not None and (job_dir / self.run).is_file()
        return self.status == FAILED and self.deterministic


def write_record(job_dir: Path, record: JobRecord) -> Path:
    """Write ``job_dir/job.json`` atomically (OutputError, one sentence, if it cannot be written)."""
    path = Path(job_dir) / RECORD_NAME
    with atomic_open(path, "w") as stream:
        json.dump(asdict(record), stream, indent=1)
    return path


def read_record(job_dir: Path) -> JobRecord | None:
    """The record in ``job_dir``, or None when there is none or it is not what gyrolab writes (untrusted input: at
    most MAX_RECORD_BYTES, a JSON mapping whose ``run`` is a file name in the job directory); None is unfinished."""
    try:
        fd = open_own_file(Path(job_dir) / RECORD_NAME, os.O_RDONLY)
        with os.fdopen(fd, "rb") as handle:
            text = handle.read(MAX_RECORD_BYTES + 1)
        if len(text) > MAX_RECORD_BYTES:
            return None
        data = json.loads(text)
        known = {f.name for f in fields(JobRecord)}
        record = JobRecord(**{k: v for k, v in data.items() if k in known})
    except (OSError, ValueError, TypeError, AttributeError, RecursionError, ConfigError):
        return None
    run = record.run
    if run is not None and (not isinstance(run, str) or Path(run).name != run or run in (".", "..")):
        return None  # a path out of the job directory: not a record gyrolab wrote
    if not (isinstance(record.overrides, list) and all(isinstance(o, str) for o in record.overrides)
            and isinstance(record.job_id, str) and isinstance(record.status, str)):
        return None
    return record


def record_paths(sweep_dir: Path, name: str = RECORD_NAME) -> Iterator[Path]:
    """Every job record (or file ``name``) under ``sweep_dir``, skipping hidden folders (.hydra, .submitit)."""
    for root, dirs, files in os.walk(sweep_dir):
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        if name in files:
            yield Path(root) / name
