"""Progress of a long integration, reported on the log: silent for runs that finish quickly."""

from __future__ import annotations

import logging
import time

log = logging.getLogger("gyrolab.progress")


class Progress:
    """Callable ``progress(t)`` that logs how far model time has got, at most every ``every`` seconds."""

    def __init__(self, label: str, t_start: float, t_end: float, every: float = 5.0) -> None:
        self.label = label
        self.t_start, self.t_end = t_start, t_end
        self.every = every
        self._began = self._last = time.perf_counter()

    def __call__(self, t: float) -> None:
        now = time.perf_counter()
        if now - self._last < self.every:
            return
        self._last = now
        fraction = (t - self.t_start) / (self.t_end - self.t_start)
        elapsed = now - self._began
        remaining = elapsed * (1.0 - fraction) / fraction if fraction > 0 else float("nan")
        log.info("%s: %3.0f%% (t=%.6g of %.6g), %.0f s elapsed, ~%.0f s to go",
                 self.label, 100 * fraction, t, self.t_end, elapsed, remaining)
