"""The Hydra callback that turns a multirun into one ``sweep.nc`` (configured in ``conf/config.yaml``):
``on_multirun_start`` starts the sweep's progress display, ``on_multirun_end`` (on the launching machine, once
every job has returned, whatever the launcher) aggregates the job directories into ``sweep.nc`` and the summary
figures. Nothing here runs in the jobs.
"""

from __future__ import annotations

import functools
import logging
from pathlib import Path
from typing import Any

from hydra.core import utils as hydra_utils
from hydra.experimental.callback import Callback
from omegaconf import DictConfig

from gyrolab.errors import GyrolabError, OutputError
from gyrolab.output.atomic import reason
from gyrolab.output.lock import lock, unlock
from gyrolab.output.trust import check_output_target, own_dir
from gyrolab.output.written import fail
from gyrolab.sweep.aggregate import SweepSummary, aggregate_sweep, log_summary
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.orphans import announce_launcher, forget_launcher
from gyrolab.sweep.sweeper import register_plugin
from gyrolab.sweep.watch import SweepWatcher

log = logging.getLogger("gyrolab.sweep")

#: outcome of the last sweep aggregated in this process (read by the command's exit status)
last_summary: SweepSummary | None = None
last_error: str | None = None
#: exit status of the command when ``last_error`` is set (3: sweep.nc could not be written)
last_exit_code: int = 1


def reset() -> None:
    """Forget the last sweep's outcome: each command starts clean (the app may run several in one process)."""
    global last_summary, last_error, last_exit_code
    last_summary, last_error, last_exit_code = None, None, 1


class SweepCallback(Callback):
    """Aggregate a multirun into ``<sweep dir>/sweep.nc``; ``figures``: also draw the summary figures. For a single
    run it locks the run directory before Hydra writes there (``on_run_start``): a second run into a directory in
    use is refused in one sentence (exit 2) without touching the first run's files."""

    def __init__(self, figures: bool = True, progress: bool = True) -> None:
        self.figures = bool(figures)
        self.progress = bool(progress)
        self._watcher: SweepWatcher | None = None

    def __getstate__(self) -> dict[str, Any]:  # launchers pickle callbacks to send them to the jobs
        return {"figures": self.figures, "progress": self.progress, "_watcher": None}  # no lock, no announcement

    def on_run_start(self, config: DictConfig, **kwargs: Any) -> None:
        try:  # the directory Hydra is about to create (the same config object: the same ${now:} values)
            run_dir = Path(str(config.hydra.run.dir))
        except Exception:  # noqa: BLE001 - not resolvable yet: the run locks it itself (gyrolab.app._run_one)
            return
        try:
            lock(run_dir)
        except GyrolabError as error:
            fail(error)
        self._locked = run_dir

    def on_run_end(self, config: DictConfig, **kwargs: Any) -> None:
        locked = self.__dict__.pop("_locked", None)
        if locked is not None:
            unlock(locked)

    def on_multirun_start(self, config: DictConfig, **kwargs: Any) -> None:
        register_plugin()  # Hydra instantiates the sweeper next (already done by the preflight; kept idempotent)
        reset()
        self._announced = announce_launcher()  # worker processes of this sweep die with this process
        if not self.progress or not _basic_sweeper(config):
            return
        try:
            total = len(Grid.from_hydra(config.hydra).jobs)
        except GyrolabError:
            return  # the sweeper will report the problem
        self._watcher = SweepWatcher(Path(config.hydra.sweep.dir), total)
        self._watcher.start()

    def on_multirun_end(self, config: DictConfig, **kwargs: Any) -> None:
        global last_summary, last_error, last_exit_code
        if self._watcher is not None:
            self._watcher.stop()
            self._watcher = None
        forget_launcher(self.__dict__.pop("_announced", None))
        if not _basic_sweeper(config):
            log.warning("sweep.nc is written for Hydra's basic sweeper only (this sweep used %s)",
                        config.hydra.sweeper.get("_target_"))
            return
        sweep_dir = Path(config.hydra.sweep.dir)
        try:
            summary = aggregate_sweep(sweep_dir, hydra_cfg=config.hydra, figures=self.figures,
                                      launcher=str(config.hydra.launcher.get("_target_", "")).rsplit(".", 1)[-1],
                                      output=config.get("output"))
        except OutputError as error:  # a full disk: one sentence, exit 3, the jobs' results intact
            last_error = f"{error}; the job results are intact: run 'gyrolab --aggregate {sweep_dir}' once " \
                         "the cause is fixed"
            last_exit_code = error.exit_code
            return
        except GyrolabError as error:  # e.g. a link planted in the sweep directory meanwhile: one sentence
            last_error, last_exit_code = str(error), error.exit_code
            return
        except Exception as error:  # noqa: BLE001 - the jobs' results are safe; say how to aggregate them later
            last_error = f"could not aggregate the sweep ({type(error).__name__}: {error}); the job results are " \
                         f"intact: run 'gyrolab --aggregate {sweep_dir}' once the cause is fixed"
            log.exception("aggregation failed")
            return
        last_summary = summary
        log_summary(summary)


def _tolerate_hydra_record_failures() -> None:
    """A full disk while Hydra saves a job's ``.hydra/*.yaml`` (before the job starts; an OSError there would abort
    the multirun with a traceback) is a warning: the config is also in the job's ``job.json`` and ``run.nc``, so
    the copy is dropped (no partial file left) and the job goes on, failing alone if it cannot write its results."""
    save = hydra_utils._save_config
    if getattr(save, "_gyrolab_tolerant", False):
        return

    @functools.wraps(save)
    def save_or_warn(cfg: Any, filename: str, output_dir: Path) -> None:
        try:  # Hydra opens the file following links: a link planted since the preflight's check is not written
            own_dir(output_dir)
            check_output_target(Path(output_dir) / filename)
        except GyrolabError as error:
            log.warning("%s; the job's config is also stored in its job.json and run.nc", error)
            return
        try:
            save(cfg, filename, output_dir)
        except OSError as error:
            target = Path(output_dir) / filename
            target.unlink(missing_ok=True)
            log.warning("cannot write %s (%s); the job's config is also stored in its job.json and run.nc",
                        target, reason(error))

    save_or_warn._gyrolab_tolerant = True  # type: ignore[attr-defined]
    hydra_utils._save_config = save_or_warn


_tolerate_hydra_record_failures()


def _basic_sweeper(config: DictConfig) -> bool:
    return str(config.hydra.sweeper.get("_target_", "")).endswith(("BasicSweeper", "GyrolabSweeper"))
