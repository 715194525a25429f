"""Progress of long integrations and sweeps: a tqdm bar on a terminal (after ``BAR_DELAY`` seconds), a log line
every ``every`` seconds elsewhere (docs/faults.md, "Progress of long runs"); sweep jobs draw no bar of their own
(``allow_bars(False)``): the sweep shows one for all its jobs.
"""

from __future__ import annotations

import contextlib
import logging
import math
import sys
import threading
import time
from collections.abc import Iterator
from typing import Any, TextIO

log = logging.getLogger("gyrolab.progress")

BAR_DELAY = 2.0
_bars_allowed = True


#: loggers whose INFO notes say that something is being compiled ("compiling force NAME, once")
COMPILE_LOGGERS = ("gyrolab.kernels.expression",)


@contextlib.contextmanager
def compile_notes_on_console(stream: TextIO | None = None) -> Iterator[None]:
    """Show the compile notes of ``COMPILE_LOGGERS`` on ``stream`` (stderr) while logging is not configured yet:
    the preflight builds the scene (compiling a plugin torque, once) before Hydra configures logging, and Python
    drops an INFO record without a handler."""
    if logging.getLogger().handlers:
        yield
        return
    handler = logging.StreamHandler(sys.stderr if stream is None else stream)
    handler.setFormatter(logging.Formatter("gyrolab: %(message)s"))
    loggers = [logging.getLogger(name) for name in COMPILE_LOGGERS]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.addHandler(handler)
        if logger.getEffectiveLevel() > logging.INFO:
            logger.setLevel(logging.INFO)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels):
            logger.removeHandler(handler)
            logger.setLevel(level)


def allow_bars(allowed: bool) -> None:
    """Whether ``Progress`` may draw bars in this process (sweep jobs say no)."""
    global _bars_allowed
    _bars_allowed = allowed


def on_terminal(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or not a real stream
        return False


def duration(seconds: float) -> str:
    """A wall-clock duration for people: '42 s', '7.5 min', '3.1 h', '12 days', '290 years', '9.5e+06 years'."""
    if not math.isfinite(seconds):
        return "? s"
    for unit, size, limit in (("s", 1, 120), ("min", 60, 120), ("h", 3600, 48), ("days", 86400, 730),
                              ("years", 365.25 * 86400, 1e4)):
        value = seconds / size
        if value < limit:
            return f"{value:.0f} {unit}" if value >= 10 or unit == "s" else f"{value:.1f} {unit}"
    return f"{seconds / (365.25 * 86400):.2g} years"


class Progress:
    """Callable ``progress(t)`` that integrators call every few steps with the model time reached."""

    def __init__(self, label: str, t_start: float, t_end: float, every: float = 5.0,
                 stream: TextIO | None = None) -> None:
        self.label = label
        self.t_start, self.t_end = t_start, t_end
        self.every = every
        self._began = self._last = time.perf_counter()
        self._t_last: float | None = None
        stream = sys.stderr if stream is None else stream
        self._bar = self._make_bar(stream) if _bars_allowed and on_terminal(stream) else None

    def _make_bar(self, stream: TextIO) -> Any:
        from tqdm import tqdm  # start-up: tqdm only for a bar on a terminal

        return tqdm(total=self.t_end - self.t_start, desc=self.label, file=stream, delay=BAR_DELAY, leave=False,
                    mininterval=0.25, bar_format="{desc}: {percentage:3.0f}%|{bar}| t={n:.4g} of {total:.4g} "
                                                 "[{elapsed}<{remaining}]")

    def __call__(self, t: float) -> None:
        if self._bar is not None:
            self._bar.update(min(t, self.t_end) - self.t_start - self._bar.n)
            if t >= self.t_end:
                self.close()
            return
        now = time.perf_counter()
        if now - self._last < self.every:
            return
        fraction = (t - self.t_start) / (self.t_end - self.t_start)
        elapsed = now - self._began
        first = self._t_last is None
        since, t_since = self._last, self._t_last
        self._last, self._t_last = now, t
        if first:  # its time includes a compiled method's compilation: no pace until a stretch has been measured
            log.info("%s: %3.0f%% (t=%.6g of %.6g), %s elapsed (compilation included), measuring the pace",
                     self.label, 100 * fraction, t, self.t_end, duration(elapsed))
            return
        pace = (t - t_since) / (now - since) if now > since else 0.0
        remaining = (self.t_end - t) / pace if pace > 0 else float("nan")
        log.info("%s: %3.0f%% (t=%.6g of %.6g), %s elapsed, ~%s to go",
                 self.label, 100 * fraction, t, self.t_end, duration(elapsed), duration(remaining))

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __del__(self) -> None:
        self.close()


class LinesAboveBar:
    """A stream wrapper that prints whole lines above a tqdm bar (clears it, writes, redraws): installed as
    ``sys.stdout``/``sys.stderr`` while a sweep bar is shown, so that log lines do not run into the bar."""

    def __init__(self, stream: TextIO, bar: Any) -> None:
        self._stream, self._bar = stream, bar
        self._pending = ""
        self._lock = threading.RLock()

    def write(self, text: str) -> int:
        with self._lock:
            self._pending += text
            if "\n" in self._pending:
                lines, _, self._pending = self._pending.rpartition("\n")
                with self._bar.get_lock():
                    self._bar.clear(nolock=True)
                    self._stream.write(lines + "\n")
                    self._stream.flush()
                    self._bar.refresh(nolock=True)
        return len(text)

    def flush(self) -> None:
        self._stream.flush()  # a partial line waits for its end, so that it never lands inside the bar

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)
