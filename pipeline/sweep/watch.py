"""Progress of a running sweep, watched from the process that launched it: the records that appeared (or were
rewritten) in the sweep directory since it started, wherever the jobs run. On a terminal one bar for the sweep;
elsewhere a log line every ``log_every`` seconds.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import time
from pathlib import Path
from typing import Any

from gyrolab.engine.progress import LinesAboveBar, on_terminal
from gyrolab.sweep.record import record_paths

log = logging.getLogger("gyrolab.sweep")


class SweepWatcher:
    def __init__(self, sweep_dir: Path, total: int, *, interval: float = 1.0, log_every: float = 60.0) -> None:
        self.sweep_dir, self.total = Path(sweep_dir), total
        self.interval, self.log_every = interval, log_every
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._bar: Any = None
        self._streams: tuple[Any, Any] | None = None
        self._before: dict[Path, int] = {}
        self._began = time.monotonic()

    def start(self) -> None:
        self._before = self._snapshot()
        self._began = time.monotonic()
        if on_terminal(sys.stderr):
            from tqdm import tqdm  # start-up: tqdm only for a bar on a terminal

            self._streams = (sys.stdout, sys.stderr)
            self._bar = tqdm(total=self.total, desc="sweep", unit="job", file=sys.stderr, dynamic_ncols=True)
            sys.stderr = LinesAboveBar(self._streams[1], self._bar)
            if on_terminal(self._streams[0]):
                sys.stdout = LinesAboveBar(self._streams[0], self._bar)
        self._thread = threading.Thread(target=self._watch, name="gyrolab-sweep-progress", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self._bar is not None:
            self._bar.update(self.done() - self._bar.n)
            self._bar.close()
            sys.stdout, sys.stderr = self._streams

    def done(self) -> int:
        """Jobs that ended (finished, failed or skipped) since ``start``."""
        now = self._snapshot()
        return sum(1 for path, mtime in now.items() if self._before.get(path) != mtime)

    def _snapshot(self) -> dict[Path, int]:
        out = {}
        for path in record_paths(self.sweep_dir):
            with contextlib.suppress(OSError):
                out[path] = path.stat().st_mtime_ns
        return out

    def _watch(self) -> None:
        last_log = time.monotonic()
        first_done: tuple[float, int] | None = None   # when jobs started ending (after Hydra's preparations)
        pause = self.interval
        while not self._stop.wait(pause):
            tic = time.monotonic()
            done = self.done()
            pause = max(self.interval, 20 * (time.monotonic() - tic))  # watching costs at most ~5% of a core
            if done and first_done is None:
                first_done = (tic, done)
            if self._bar is not None:
                self._bar.update(done - self._bar.n)
            elif time.monotonic() - last_log >= self.log_every:
                last_log = time.monotonic()
                elapsed = last_log - self._began
                if first_done is not None and done > first_done[1]:
                    rate = (done - first_done[1]) / (last_log - first_done[0])
                    log.info("sweep: %d of %d jobs done, %.0f s elapsed, ~%.0f s to go", done, self.total, elapsed,
                             (self.total - done) / rate)
                elif done:
                    log.info("sweep: %d of %d jobs done, %.0f s elapsed", done, self.total, elapsed)
                else:
                    log.info("sweep: 0 of %d jobs done, %.0f s elapsed (Hydra composes every job's config "
                             "before launching)", self.total, elapsed)
