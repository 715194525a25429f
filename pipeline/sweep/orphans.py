"""Sweep jobs in worker processes die with the process that launched the sweep (docs/faults.md, "Workers die with
the launching process"); the launcher announces itself to its workers in ``LAUNCHER_ENV`` ("host:pid").
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import logging
import os
import signal
import socket
import sys
import threading
from pathlib import Path

log = logging.getLogger("gyrolab.sweep")

LAUNCHER_ENV = "GYROLAB_SWEEP_LAUNCHER"
POLL = 0.5
PR_SET_PDEATHSIG = 1

_armed = False


def announce_launcher() -> str | None:
    """Mark this process as the sweep's launcher for the jobs it starts; returns the previous value."""
    previous = os.environ.get(LAUNCHER_ENV)
    os.environ[LAUNCHER_ENV] = f"{socket.gethostname()}:{os.getpid()}"
    return previous


def forget_launcher(previous: str | None) -> None:
    if previous is None:
        os.environ.pop(LAUNCHER_ENV, None)
    else:
        os.environ[LAUNCHER_ENV] = previous


def launcher_pid() -> int | None:
    """The pid of the process that launched this job's sweep, if it is another process on this host."""
    host, _, pid = os.environ.get(LAUNCHER_ENV, "").rpartition(":")
    if not pid.isdigit() or host != socket.gethostname() or int(pid) == os.getpid():
        return None
    return int(pid)


def guard_worker() -> bool:
    """In a worker process of a sweep, arm the guards (once per process); True if this is such a worker."""
    global _armed
    launcher = launcher_pid()
    if launcher is None:
        return False
    if _armed:
        return True
    _armed = True
    parent = os.getppid()
    if parent == launcher and sys.platform.startswith("linux"):
        _set_parent_death_signal()
    if not alive(launcher):  # it died before the guards were armed
        _end(launcher)
    thread = threading.Thread(target=_watch, args=(launcher, parent), name="gyrolab-orphan-watchdog",
                              daemon=True)
    thread.start()
    return True


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, killed but not yet reaped, counts as dead)."""
    stat = Path(f"/proc/{pid}/stat")
    if Path("/proc/self/stat").exists():
        try:
            state = stat.read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            return False
        return state not in ("Z", "X")
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _set_parent_death_signal() -> None:
    with contextlib.suppress(OSError, AttributeError):  # no prctl here: the watchdog alone guards this worker
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        if libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) != 0:
            log.debug("prctl(PR_SET_PDEATHSIG) failed: errno %d; the watchdog alone guards this worker",
                      ctypes.get_errno())


def _watch(launcher: int, parent: int) -> None:
    stop = threading.Event()
    while not stop.wait(POLL):
        if os.getppid() != parent or not alive(launcher):
            _end(launcher)


def _end(launcher: int) -> None:
    log.error("the sweep's launching process (pid %d) is gone; this worker (pid %d) stops its job, which "
              "reruns when the sweep is resumed", launcher, os.getpid())
    logging.shutdown()
    os._exit(1)
