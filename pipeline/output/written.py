"""gyrolab's one logging convention: log lines and progress go to stderr, results go to stdout.

A result is what a command leaves behind for the user or a script: the paths it wrote (``wrote PATH``, one a
line) and reports (``gyrolab reproduce``'s comparison). So ``gyrolab ... > written.txt`` keeps the list of
files, and ``gyrolab ... 2> log.txt`` the log, the same for run, multirun, batch, plot, reproduce and
aggregate. (Hydra's console log handlers are pointed at stderr in conf/config.yaml for the same reason.)
"""

from __future__ import annotations

import logging
import sys
from os import PathLike
from typing import NoReturn

from gyrolab.errors import GyrolabError

log = logging.getLogger("gyrolab")


def announce_written(path: str | PathLike[str]) -> None:
    """Say on stdout that ``path`` was written (and in the log at debug level, for the log file)."""
    print(f"wrote {path}", file=sys.stdout, flush=True)
    log.debug("wrote %s", path)


def fail(error: GyrolabError) -> NoReturn:
    """End the command with ``error``'s one sentence on stderr and its exit status."""
    print(f"gyrolab: error: {error}", file=sys.stderr)
    sys.exit(error.exit_code)
