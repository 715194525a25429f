"""``gyrolab reproduce PATH/run.nc``: rerun a dataset's stored config and compare bit for bit (docs/sweeps.md,
"Reproduce a result"); also a multirun's ``sweep.nc`` job by job (``reproduce_sweep``). Batches
(``gyrolab.batch.reproduce``) and experiments (``gyrolab.experiments.reproduce_task``) use ``compare`` of this module.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.engine.budget import check_budget
from gyrolab.engine.safety import check_stored_config
from gyrolab.errors import ConfigError, GyrolabError, shorten
from gyrolab.output.foreign import FOREIGN_ERRORS, RUN, load_dataset, load_run as load_run_only, not_gyrolabs
from gyrolab.output.provenance import provenance
from gyrolab.engine.scene import Scene

#: provenance attributes worth comparing (the wall time differs by nature)
PROVENANCE_KEYS = ("gyrolab_version", "git_commit", "git_dirty", "git_diff_sha256", "python_version", "platform",
                   "plugin_packages")


@dataclass
class Comparison:
    #: what ``same`` and ``differ`` count: a run's variables and coordinates, or a sweep's jobs
    unit: str = "variables and coordinates"
    same: list[str] = field(default_factory=list)
    differ: list[str] = field(default_factory=list)          # one sentence per differing variable
    provenance: list[str] = field(default_factory=list)      # stored vs now, where they differ

    @property
    def identical(self) -> bool:
        return not self.differ


def load_run(path: Path, *, sweeps: bool = False) -> xr.Dataset:
    """The dataset at ``path``: a run.nc or another dataset with a stored config (``sweeps``: a multirun's
    sweep.nc too); ConfigError, one sentence, for anything else."""
    if not sweeps:
        return load_run_only(path)
    ds = load_dataset(Path(path), RUN, decode_times=False, decode_timedelta=False)  # (the trust boundary's loader)
    return ds if is_multirun(ds) else load_run_only(path)


def is_multirun(ds: xr.Dataset) -> bool:
    """Whether a dataset is a multirun's sweep.nc (``gyrolab -m``): jobs with their directories, no config of its own."""
    return "config" not in ds.attrs and "job_status" in ds and "job_dir" in ds


def parse_points(text: str | None, n_points: int, what: str = "point") -> list[int] | None:
    """``--points 0,5,10-19`` as sorted numbers below ``n_points`` (None: all); ConfigError, one sentence, otherwise."""
    if text is None:
        return None
    chosen: set[int] = set()
    for part in (p.strip() for p in str(text).split(",")):
        low, dash, high = part.partition("-")
        try:
            first, last = int(low), int(high) if dash else int(low)
        except ValueError:
            raise ConfigError(f"--points {shorten(repr(text))}: {shorten(repr(part))} is not a {what} number or a "
                              f"range; give numbers and ranges from 0 to {n_points - 1}, e.g. --points 0,5,10-19") from None
        if not 0 <= first <= last < n_points:
            raise ConfigError(f"--points {shorten(repr(text))}: {part} is outside the {what}s 0 to {n_points - 1}; "
                              "e.g. --points 0,5,10-19")
        chosen.update(range(first, last + 1))
    return sorted(chosen)


def reproduce_sweep(path: Path, stored: xr.Dataset, points: str | None = None) -> tuple[Comparison, list[str]]:
    """(the comparison, the report's head) of reproducing the finished jobs of a multirun's sweep.nc (``points``: only
    these, flat C-order numbers), each from its own run.nc; a failed job left none: it is named, not rerun."""
    path = Path(path)
    status = np.asarray(stored["job_status"].values).ravel()
    dirs = [str(d) for d in np.asarray(stored["job_dir"].values).ravel()]
    chosen = parse_points(points, status.size, "job") if points is not None else list(range(status.size))
    result, head = Comparison(unit="jobs' datasets"), [f"reproducing {path} (a sweep of {status.size} jobs): "
                                  f"{'all ' if points is None else ''}{len(chosen)} of them"]
    top = path.parent.resolve()
    for n in chosen:
        if int(status[n]) != 1 or not dirs[n]:
            head.append(f"  job {n}: {'failed' if int(status[n]) == 2 else 'did not run'} in the sweep; no run.nc to rerun")
            continue
        run_path = (top / dirs[n] / "run.nc").resolve()
        if not run_path.is_relative_to(top):
            raise ConfigError(f"{path}: job_dir {shorten(repr(dirs[n]))} is outside the sweep directory; give a "
                              "sweep.nc that gyrolab wrote, in its sweep directory")
        comparison, _ = reproduce(run_path)
        head.append(f"  job {n} ({dirs[n]}/run.nc): " + ("identical" if comparison.identical else
                                                          f"{len(comparison.differ)} variables differ"))
        if comparison.identical:
            result.same.append(f"job {n}")
        else:
            result.differ.append(f"job {n}: " + "; ".join(comparison.differ))
        result.provenance = result.provenance or comparison.provenance
    return result, head


def stored_config(stored: xr.Dataset, where: str = "the dataset's config attribute") -> DictConfig:
    """The config a dataset stores, checked as any config is: a dataset may come from someone else (no YAML tags,
    no interpolation, registered plugins only: ``gyrolab.engine.safety``; within the budget)."""
    cfg = check_stored_config(stored.attrs["config"], where)
    plain = OmegaConf.to_container(cfg)
    time = plain.get("time")
    if isinstance(time, dict) and {"start", "end", "n_output"} <= set(time) and (
            isinstance(time["n_output"], int) or time["n_output"] == "auto"):
        probe = cfg.copy()
        probe.time.n_output = 2
        check_budget(plain, Scene.from_config(probe).system.initial_state().size)
    return cfg


def compare(stored: xr.Dataset, new: xr.Dataset) -> Comparison:
    result = Comparison()
    for kind, names_old, names_new in (("coordinate", stored.coords, new.coords),
                                       ("variable", stored.data_vars, new.data_vars)):
        for name in sorted(set(names_old) | set(names_new)):
            if name not in names_new:
                result.differ.append(f"{kind} {name}: in the dataset, not in the rerun")
            elif name not in names_old:
                result.differ.append(f"{kind} {name}: in the rerun, not in the dataset")
            else:
                message = _difference(stored[name], new[name])
                (result.differ.append(f"{kind} {name}: {message}") if message else result.same.append(name))
    now = provenance()
    for key in PROVENANCE_KEYS:
        then = stored.attrs.get(key)
        if then is not None and str(then) != str(now.get(key)):
            result.provenance.append(f"{key}: {then} then, {now.get(key)} now")
    for key, then in stored.attrs.items():
        if key.startswith("version_") and str(then) != str(now.get(key)):
            result.provenance.append(f"{key[len('version_'):]}: {then} then, {now.get(key, 'not installed')} now")
    return result


def _difference(old: xr.DataArray, new: xr.DataArray) -> str:
    """'' if bit-for-bit equal, else one phrase saying how they differ."""
    a, b = np.asarray(old.values), np.asarray(new.values)
    if old.dims != new.dims or a.shape != b.shape:
        return f"shape {dict(zip(old.dims, a.shape))} in the dataset, {dict(zip(new.dims, b.shape))} in the rerun"
    if a.dtype.kind in "fc" and b.dtype.kind in "fc":
        return _float_difference(old, a.astype(np.float64), b.astype(np.float64))
    if a.dtype == b.dtype and np.array_equal(a, b):
        return ""
    if a.dtype.kind in "iub" and b.dtype.kind in "iub":
        return f"max |Δ| = {int(np.max(np.abs(a.astype(np.int64) - b.astype(np.int64))))}"
    equal = np.asarray(a.astype(str) == b.astype(str))
    return "" if equal.all() else f"{int((~equal).sum())} of {equal.size} values differ"


def _float_difference(old: xr.DataArray, a: np.ndarray, b: np.ndarray) -> str:
    """'' if the floats ``a`` and ``b`` are bit-for-bit equal, else where NaNs differ or the largest difference."""
    if a.tobytes() == b.tobytes():  # the bits in C order, whatever either array's memory layout
        return ""
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    if (nan_a != nan_b).any():
        return f"NaN at {int((nan_a != nan_b).sum())} places where the other has a number"
    delta = np.abs(a - b)
    delta[nan_a] = 0.0
    scale = float(np.max(np.abs(a))) or 1.0
    worst = np.unravel_index(int(np.argmax(delta)), delta.shape)
    where = ", ".join(f"{d}={old[d].values[i]}" if d in old.coords else f"{d}[{i}]"
                      for d, i in zip(old.dims, worst))
    return (f"max |Δ| = {float(delta[worst]):.3g} (relative to max |value| {float(delta[worst]) / scale:.3g}) "
            f"at {where or 'the only value'}; {int((delta > 0).sum())} of {delta.size} values differ")


@contextmanager
def _gyrolabs_only(path: Path) -> Iterator[None]:
    """A stored config, or variables, without what gyrolab's runs always have: one sentence."""
    try:
        yield
    except GyrolabError:
        raise
    except FOREIGN_ERRORS as error:
        raise not_gyrolabs(path, error, RUN) from None


def checked_config(path: Path, stored: xr.Dataset) -> DictConfig:
    """``stored_config``, with what a foreign dataset lacks said in one sentence."""
    with _gyrolabs_only(path):
        return stored_config(stored)


def reproduce(path: Path, stored: xr.Dataset | None = None) -> tuple[Comparison, xr.Dataset]:
    """Rerun the run.nc at ``path`` (``stored``: its dataset, already loaded) and compare."""
    stored = load_run(path) if stored is None else stored
    with _gyrolabs_only(path):
        scene = Scene.from_config(stored_config(stored))
    new = scene.run()
    with _gyrolabs_only(path):
        return compare(stored, new), stored


def report(path: Path, comparison: Comparison, stored: xr.Dataset, head: list[str] | None = None) -> list[str]:
    """The report's lines: ``head`` (default: the run's title, integrator and output times), then the comparison."""
    lines = list(head) if head else [
        f"reproducing {path} ({stored.attrs.get('title', '?')}; {stored.attrs.get('integrator', '?')}, "
        f"{stored.sizes.get('time', '?')} output times)"]
    lines += [f"  provenance differs: {p}" for p in comparison.provenance]
    if comparison.identical:
        lines.append(f"identical: {len(comparison.same)} {comparison.unit} equal bit for bit "
                     f"({', '.join(comparison.same)})")
    else:
        lines += [f"  {d}" for d in comparison.differ]
        lines.append(f"NOT identical: {len(comparison.differ)} of {len(comparison.differ) + len(comparison.same)} "
                     f"{comparison.unit} differ")
    return lines
