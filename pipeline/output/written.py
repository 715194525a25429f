"""gyrolab's one logging convention: log lines and progress go to stderr, results go to stdout: the paths a command
wrote (``wrote PATH``, one a line) and reports (``gyrolab reproduce``'s comparison), so ``gyrolab ... >
written.txt`` keeps the list of files and ``2> log.txt`` the log (Hydra's console handlers too: conf/config.yaml).
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
