"""gyrolab's sweeper: Hydra's basic sweeper that leaves finished jobs out before launching anything
(docs/cluster.md, "Resuming a multirun": how identities are predicted without composing every job).

A job whose overrides do not apply to its composed group choices is composed in full, so that Hydra reports it.
A wrong prediction can only cost a launch, never skip a job.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import os
import re
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override, OverrideType
from hydra.core.plugins import Plugins
from hydra.plugins.launcher import Launcher
from hydra.plugins.sweeper import Sweeper
from hydra.types import HydraContext, TaskFunction
from omegaconf import DictConfig, OmegaConf

from gyrolab.compat import BasicSweeper, ConfigLoaderImpl
from gyrolab.errors import ConfigError, GyrolabError, shorten
from gyrolab.output.atomic import atomic_open
from gyrolab.output.lock import try_lock, unlock
from gyrolab.output.trust import check_tree, private_dir
from gyrolab.output.written import fail
from gyrolab.sweep.aggregate import SWEEP_NAME, stored_hydra
from gyrolab.sweep.grid import Grid
from gyrolab.sweep.identity import code_version, job_identity
from gyrolab.sweep.job import mark_skipped
from gyrolab.sweep.record import JobRecord, read_record

log = logging.getLogger("gyrolab.sweep")

#: finished jobs between two runs of remaining jobs that are launched anyway (they skip themselves) rather
#: than splitting the launch: a launcher with parallel workers keeps them busy across small gaps
MERGE_GAP = 8
#: an interpolation that calls a resolver (``${name:...}``): its value may differ inside the job
_RESOLVER = re.compile(r"\$\{\s*[\w.]+\s*:")


class ResumingSweeper(Sweeper):
    """Hydra's basic sweeper (same jobs, numbers, ``max_batch_size`` and ``params``) that does not launch the jobs
    a previous run of the same sweep settled. It calls the basic sweeper's functions rather than subclassing it:
    Hydra re-imports its plugin modules when it scans them, which would leave a subclass with a stale base."""

    def __init__(self, max_batch_size: int | None = None, params: dict[str, str] | None = None) -> None:
        super().__init__()
        self.max_batch_size = max_batch_size
        self.params = dict(params or {})
        self.hydra_context: HydraContext | None = None
        self.config: DictConfig | None = None
        self.launcher: Launcher | None = None

    def setup(self, *, hydra_context: HydraContext, task_function: TaskFunction, config: DictConfig) -> None:
        self.hydra_context, self.config = hydra_context, config
        self.launcher = Plugins.instance().instantiate_launcher(hydra_context=hydra_context,
                                                                task_function=task_function, config=config)

    def sweep(self, arguments: list[str]) -> Any:
        assert self.config is not None and self.launcher is not None and self.hydra_context is not None
        parser = OverridesParser.create(config_loader=self.hydra_context.config_loader)
        params = [f"{key}={value}" for key, value in self.params.items()]  # as the basic sweeper: params first
        overrides = parser.parse_overrides([*params, *arguments])
        jobs = [job for batch in BasicSweeper.split_arguments(overrides, None) for job in batch]
        sweep_dir = Path(self.config.hydra.sweep.dir)
        try:
            claim(sweep_dir, self.config)
        except GyrolabError as error:  # as the sweep callback refuses a directory in use: one sentence
            fail(error)

        tic = time.perf_counter()
        settled, unsure = check_jobs(self.config, self.hydra_context.config_loader, jobs)
        remaining = [num for num in range(len(jobs)) if num not in settled]
        if settled:
            log.info("sweep resumed: %d of %d jobs already settled, not launched (checked in %.1f s)",
                     len(settled), len(jobs), time.perf_counter() - tic)
        # As the basic sweeper, refuse a sweep with a job Hydra cannot compose before launching any job: every
        # job's overrides were applied above; the jobs where that failed are composed in full (Hydra's error).
        self.validate_batch_is_legal([jobs[num] for num in unsure if num not in settled])
        returns, launched = self._launch(jobs, remaining)
        for num, (job_dir, record) in settled.items():  # as a job that skips itself records it
            if num not in launched:
                mark_skipped(job_dir, record, num, jobs[num])
        return returns

    def _launch(self, jobs: list, remaining: list[int]) -> tuple[list, set[int]]:
        """Launch the ``remaining`` jobs in batches: (the launcher's results, the job numbers launched)."""
        # A sequential launcher gains nothing from launching settled jobs between remaining ones.
        gap = 0 if type(self.launcher).__name__ == "BasicLauncher" else MERGE_GAP
        returns, launched = [], set()
        for start, batch in launch_runs(remaining, jobs, self.max_batch_size, gap):
            launched.update(range(start, start + len(batch)))
            results = self.launcher.launch(batch, initial_job_idx=start)
            for r in results:
                _ = r.return_value  # re-raises a job's exception, as the basic sweeper does
            returns.append(results)
        return returns, launched


def claim(sweep_dir: Path, config: DictConfig) -> None:
    """Make ``sweep_dir`` this sweep's (its ``multirun.yaml``), or refuse it in one sentence (ConfigError): another
    sweep or a batch there is refused, the same sweep again resumes; under the directory's lock, so two sweeps
    started at once cannot interleave. Nothing there is followed (``check_tree``), and submitit's folder, whose
    pickles the jobs load, is the user's alone (``private_dir``)."""
    check_tree(sweep_dir, sweep=True)
    try_lock(sweep_dir, blocking=True)
    try:
        saved = sweep_dir / "multirun.yaml"
        if saved.exists() or (sweep_dir / SWEEP_NAME).exists():
            where = shorten(str(sweep_dir))
            if not saved.exists():
                raise ConfigError(f"{where!r} holds a {SWEEP_NAME} of a batch or another sweep and no multirun.yaml; "
                                  "choose another hydra.sweep.dir or remove it")
            theirs = Grid.from_hydra(stored_hydra(sweep_dir)).jobs
            if theirs != Grid.from_hydra(config.hydra).jobs:
                raise ConfigError(f"{where!r} holds another sweep ({len(theirs)} jobs, its command line in "
                                  f"{shorten(str(saved))}); choose another hydra.sweep.dir, or run that sweep's "
                                  "command again to resume it")
        folder = OmegaConf.select(config, "hydra.launcher.submitit_folder", default=None)
        if folder is not None:
            inside = Path(os.path.relpath(os.path.abspath(str(folder)), os.path.abspath(sweep_dir))).parts
            if inside and inside[0] not in ("..", "."):
                private_dir(sweep_dir / inside[0], "submitit's folder")
        with atomic_open(saved, "w") as stream:
            stream.write(OmegaConf.to_yaml(config))
    finally:
        unlock(sweep_dir)


def launch_runs(remaining: Sequence[int], jobs: Sequence[Sequence[str]], max_batch_size: int | None,
                merge_gap: int = MERGE_GAP) -> list[tuple[int, list[list[str]]]]:
    """(first job number, overrides of consecutive jobs) to launch: runs of remaining jobs joined across gaps
    of at most ``merge_gap`` settled jobs, each cut into batches of at most ``max_batch_size`` jobs."""
    runs: list[list[int]] = []
    for num in remaining:
        if runs and num - runs[-1][-1] - 1 <= merge_gap:
            runs[-1].extend(range(runs[-1][-1] + 1, num + 1))
        else:
            runs.append([num])
    size = max_batch_size if max_batch_size and max_batch_size > 0 else None
    return [(run[i], [list(jobs[n]) for n in run[i:i + step]])
            for run in runs for step in [size or len(run)] for i in range(0, len(run), step)]


class OverridesDoNotApply(Exception):
    """A job's value overrides could not be applied to the config of its group choices."""


def check_jobs(master: DictConfig, loader: ConfigLoaderImpl,
               jobs: Sequence[Sequence[str]]) -> tuple[dict[int, tuple[Path, JobRecord]], list[int]]:
    """(the jobs whose directory holds a record that settles their identity, by job number; the jobs whose
    overrides did not apply). A job whose identity is not predictable here is launched and checks itself."""
    sweep_dir = Path(master.hydra.sweep.dir)
    predictor = IdentityPredictor(master, loader)
    settled, unsure = {}, []
    for num, overrides in enumerate(jobs):
        try:
            job_id = predictor.identity(overrides)  # None: not predictable here
        except OverridesDoNotApply:
            unsure.append(num)
            continue
        job_dir = _job_dir(master, num, sweep_dir)  # None: the jobs find their own directories
        record = read_record(job_dir) if job_id is not None and job_dir is not None else None
        if record is not None and record.reusable_for(job_id, job_dir):
            settled[num] = (job_dir, record)
    return settled, unsure


def _job_dir(master: DictConfig, num: int, sweep_dir: Path) -> Path | None:
    """Job ``num``'s directory; None when ``hydra.sweep.subdir`` depends on more than the job number
    (e.g. ``${hydra.job.override_dirname}``: only Hydra knows it before the job runs)."""
    subdir = OmegaConf.to_container(master.hydra.sweep, resolve=False).get("subdir")
    if subdir == "${hydra.job.num}":  # gyrolab's default
        return sweep_dir / str(num)
    if "${" in str(subdir):
        return None
    return sweep_dir / str(subdir)


@dataclass
class _Base:
    """The config (without ``hydra``) of one composed job, and its value overrides by key."""

    scene: DictConfig
    applied: dict[str, Override]
    #: the scene as plain data, when it has no interpolation (a job's differs only where its overrides say)
    plain: dict[str, Any] | None = None


class IdentityPredictor:
    """Job identities of a sweep's jobs as the jobs themselves will compute them (None: not predictable), each
    from a composed job's config with the job's differing value overrides applied, then put back."""

    def __init__(self, master: DictConfig, loader: ConfigLoaderImpl) -> None:
        self.master, self.loader = master, loader
        self.groups = set((master.hydra.runtime.get("choices") or {}).keys())
        self.parser = OverridesParser.create(config_loader=loader)
        self.code = code_version()
        self._parse = functools.cache(self.parser.parse_override)   # each distinct override parsed once
        #: group choices -> the composed job with those choices (None: its config calls a resolver)
        self._bases: dict[tuple[str, ...], _Base | None] = {}

    def identity(self, overrides: Sequence[str]) -> str | None:
        parsed = [self._parse(text) for text in overrides]
        # Hydra's own settings are the same for every job of a sweep and are not part of an identity
        values = [o for o in parsed if not self._is_group(o) and not o.key_or_group.startswith("hydra.")]
        base = self._base(tuple(o.input_line for o in parsed if self._is_group(o)), overrides, values)
        if base is None or not all(o.key_or_group in base.applied for o in values):
            return None
        changed = [o for o in values if base.applied[o.key_or_group].input_line != o.input_line]
        if any(o.is_delete() for o in changed):
            return None
        plain = self._resolved_with(base, changed)
        return None if plain is None else job_identity(plain, self.code)

    def _base(self, choices: tuple[str, ...], overrides: Sequence[str], values: list) -> _Base | None:
        """The composed config of the jobs choosing ``choices`` (composed once), or None where a resolver could
        give each job its own value."""
        if choices not in self._bases:
            composed = self.loader.load_sweep_config(self.master, list(overrides))
            scene = OmegaConf.masked_copy(composed, [k for k in composed if k != "hydra"])
            unresolved = OmegaConf.to_container(scene, resolve=False)
            self._bases[choices] = None if _RESOLVER.search(repr(unresolved)) else _Base(
                scene, {o.key_or_group: o for o in values}, None if "${" in repr(unresolved) else unresolved)
        return self._bases[choices]

    @staticmethod
    def _resolved_with(base: _Base, changed: list) -> dict | None:
        """The base config with the ``changed`` overrides applied, resolved (None: it does not resolve); the base
        is left as it was."""
        try:
            try:
                for o in changed:
                    ConfigLoaderImpl._apply_overrides_to_config([_as_change(o)], base.scene)
            except Exception as error:  # noqa: BLE001 - Hydra's composition will say what is wrong
                raise OverridesDoNotApply(str(error)) from error
            try:
                plain = _patched(base, changed)
                return plain if plain is not None else OmegaConf.to_container(base.scene, resolve=True)
            except Exception:  # noqa: BLE001 - e.g. an interpolation that does not resolve: the job records it
                return None
        finally:
            for o in changed:  # back to the composed job's values
                ConfigLoaderImpl._apply_overrides_to_config([_as_change(base.applied[o.key_or_group])], base.scene)

    def _is_group(self, o: Override) -> bool:
        return o.key_or_group in self.groups or o.key_or_group.startswith("hydra/")


def _as_change(o: Override) -> Override:
    """``+key=value`` as ``key=value``: the key is there already (the composed job added it)."""
    return dataclasses.replace(o, type=OverrideType.CHANGE) if o.is_add() else o


def _patched(base: _Base, changed: Sequence[Override]) -> dict[str, Any] | None:
    """The job's config as plain data: the composed job's with the changed values read back where they were applied
    (typed as Hydra types them); None when the config or a new value interpolates, or a key goes through a list."""
    if base.plain is None or any("${" in o.input_line for o in changed):
        return None
    plain = dict(base.plain)
    for o in changed:
        *parents, leaf = o.key_or_group.split(".")
        node, where = plain, base.scene
        for key in parents:  # copy the dictionaries on the way: the composed job's stay as they are
            if not isinstance(node.get(key), dict):
                return None
            node[key] = dict(node[key])
            node, where = node[key], where[key]
        value = where[leaf]
        node[leaf] = OmegaConf.to_container(value, resolve=True) if OmegaConf.is_config(value) else value
    return plain


def register_plugin() -> None:
    """Make sure Hydra knows gyrolab's sweeper (``hydra_plugins.gyrolab_sweeper``) in this process: in an editable
    install setuptools' finder serves the package on import but cannot list it, so Hydra's scan misses it."""
    plugins = Plugins.instance()  # scans first: a scan re-executes the plugin modules it finds
    from hydra_plugins.gyrolab_sweeper import GyrolabSweeper  # after the scan above, which re-executes it

    if f"{GyrolabSweeper.__module__}.{GyrolabSweeper.__name__}" not in plugins.class_name_to_class:
        plugins.register(GyrolabSweeper)
