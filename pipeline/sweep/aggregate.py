"""One dataset per sweep: every job's ``run.nc`` on the sweep's grid, plus a table of failed jobs (the layout:
docs/datasets.md, "sweep.nc — a multirun").
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from omegaconf import DictConfig, OmegaConf

from gyrolab.contracts.integrator import IntegratorStats
from gyrolab.errors import ConfigError, shorten
from gyrolab.figures.options import figure_options
from gyrolab.output.cf import conform
from gyrolab.output.dataset import write_dataset
from gyrolab.output.foreign import FOREIGN_ERRORS, load_dataset
from gyrolab.output.lock import LOCK_NAME, clear_temporaries, owner_of, try_lock, unlock, wait_for
from gyrolab.output.trust import check_tree
from gyrolab.output.units import quantity_units
from gyrolab.output.user_yaml import stored_yaml_file
from gyrolab.output.written import announce_written
from gyrolab.sweep.grid import Grid, dim_names
from gyrolab.sweep.record import FAILED, FINISHED, JobRecord, read_record, record_paths

log = logging.getLogger("gyrolab.sweep")

SWEEP_NAME = "sweep.nc"
MISSING = "missing"
STATUS_FLAGS = {MISSING: 0, FINISHED: 1, FAILED: 2}
#: the CF flag attributes of ``job_status`` (a batch's sweep.nc has the same codes)
STATUS_ATTRS = {"units": "1", "flag_values": np.array(list(STATUS_FLAGS.values()), dtype=np.int8),
                "flag_meanings": " ".join(STATUS_FLAGS)}
#: run attributes that are per-job quantities, always variables over the swept dims
PER_JOB_ATTRS = ("config", "hydra_overrides") + tuple(f"integrator_{f.name}" for f in fields(IntegratorStats))
#: variable attributes that are per-job quantities
PER_JOB_VARIABLE_ATTRS = ("max_abs_drift",)
#: run attributes left in the jobs' own run.nc: the sweep has its own (set by ``gyrolab.output.cf.conform``)
JOB_ONLY_ATTRS = ("job_id", "date_created", "history", "Conventions")
#: CF units and long_name of the per-job variables a run's attributes become (others: "run attribute NAME")
PER_JOB_METADATA = {
    "config": (None, "the job's resolved config (YAML)"),
    "hydra_overrides": (None, "the job's command-line overrides"),
    "integrator_nfev": ("1", "right-hand-side evaluations of the integrator"),
    "integrator_n_steps": ("1", "integrator steps accepted"),
    "integrator_n_rejected": ("1", "integrator steps rejected"),
    "integrator_wall_time": ("s", "integrator wall time"),
    "integrator_njev": ("1", "Jacobian evaluations of the integrator"),
    "integrator_nlu": ("1", "LU decompositions of the integrator"),
    "sampling_fastest_rate": (None, "upper estimate of the fastest angular frequency"),
    "sampling_samples_per_period": ("1", "stored samples per period of the fastest motion"),
    "sampling_n_output_requested": (None, "time.n_output as the config gave it"),
    "sampling_warning": (None, "warning when the output times undersample the motion"),
}


@dataclass
class JobResult:
    """How one grid point ended: its dataset if finished, its error if failed, nothing if missing."""

    status: str = MISSING
    dataset: xr.Dataset | None = None
    job_id: str = ""
    job_dir: str = ""
    error: str = ""
    error_type: str = ""
    exit_code: int = 0
    skipped: bool = False


@dataclass
class SweepSummary:
    path: Path
    n_jobs: int
    finished: int
    failed: int
    missing: int
    skipped: int
    failures: list[tuple[str, str]] = field(default_factory=list)   # (overrides, error)
    #: failed jobs whose result could not be written (a full disk: OutputError), retried on resume
    write_failures: int = 0
    figures: list[Path] = field(default_factory=list)


def assemble(grid: Grid, results: Sequence[JobResult]) -> xr.Dataset:
    """The sweep dataset of ``grid`` from ``results[n]``, the outcome of job ``n`` (one per job)."""
    done = [(grid.index[n], r.dataset) for n, r in enumerate(results) if r.status == FINISHED]
    reserved = {"time", "sample", "axis", "failed_job"}.union(*(set(ds.variables) | set(ds.dims) for _, ds in done))
    grid_dims = dim_names(grid.dims, reserved)
    shape = grid.shape
    systems = {ds.attrs.get("body_units") for _, ds in done}   # si or nondimensional, None when they differ
    body_units = systems.pop() if len(systems) == 1 else None
    coords: dict[str, Any] = {
        name: (name, values, {"long_name": f"swept parameter {dim.key}", "override_key": dim.key,
                              **_units(values, quantity_units(dim.key, body_units))})
        for name, dim in zip(grid_dims, grid.dims) for values in [dim.coordinate()]
    }
    times = [ds["time"].values for _, ds in done]   # sample: the jobs' output times differ
    sample = "time" if all(np.array_equal(t, times[0]) for t in times[1:]) else "sample"
    data_vars = _stacked_variables(done, coords, shape, grid_dims, sample, body_units) if done else {}
    common = _run_attributes(done, coords, data_vars, shape, grid_dims, body_units)
    data_vars.update(_job_table(grid, results, grid_dims))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update({**common, **_sweep_attributes(grid, results, grid_dims, sample)})
    return conform(ds, source=f"sweep of {len(results)} jobs over {' × '.join(grid_dims) or 'no parameter'}")


def _sweep_attributes(grid: Grid, results: Sequence[JobResult], grid_dims: tuple[str, ...],
                      sample: str) -> dict[str, Any]:
    """What the sweep was (its title, dimensions, keys) and how its jobs ended."""
    counts = {f"n_{status}": sum(r.status == status for r in results) for status in STATUS_FLAGS}
    return {
        "failed_job_description": "dimension failed_job: one entry per failed job, in job order (the failed_job_* "
                                  "variables are its table)",
        **({"sample_description": "dimension sample: each job's output times in order (the jobs' output times "
                                  "differ: the variable time holds each job's own)"} if sample == "sample" else {}),
        "title": f"gyrolab sweep over {' × '.join(grid_dims) or 'no parameter'} ({len(results)} jobs)",
        "sweep_dims": " ".join(grid_dims),
        "sweep_keys": " ".join(d.key for d in grid.dims),
        "n_jobs": len(results),
        "n_finished": counts["n_finished"], "n_failed": counts["n_failed"], "n_missing": counts["n_missing"],
    }


def _stacked_variables(done: list[tuple[tuple, xr.Dataset]], coords: dict[str, Any], shape: tuple[int, ...],
                       grid_dims: tuple[str, ...], sample: str, body_units: str) -> dict[str, Any]:
    """The finished jobs' variables stacked over the grid, with their per-job attributes; the jobs' shared
    coordinates go into ``coords`` (ConfigError if the jobs disagree on one)."""
    data_vars: dict[str, Any] = {}
    first = done[0][1]
    for name, coord in first.coords.items():
        if name == "time" and sample == "sample":
            continue
        for _, ds in done[1:]:
            if name not in ds.coords or not np.array_equal(ds[name].values, coord.values):
                raise ConfigError(f"jobs of this sweep disagree on coordinate {name!r}; they cannot share "
                                  "one sweep.nc")
        coords[name] = (coord.dims, coord.values, _common_attrs([ds[name] for _, ds in done]))
        _add_per_job_attrs(data_vars, coords, done, name, shape, grid_dims, body_units)
    if sample == "sample":
        data_vars["time"] = _stack(done, "time", shape, grid_dims, sample)
        data_vars["time"][2].pop("axis", None)   # a variable over the jobs now, not the T coordinate (CF §4)
    for name in _union([list(ds.data_vars) for _, ds in done]):
        data_vars[name] = _stack(done, name, shape, grid_dims, sample)
        _add_per_job_attrs(data_vars, coords, done, name, shape, grid_dims, body_units)
    return data_vars


def _add_per_job_attrs(data_vars: dict[str, Any], coords: dict[str, Any], done: list, name: str,
                       shape: tuple[int, ...], grid_dims: tuple[str, ...], body_units: str | None) -> None:
    """The attributes of ``name`` that are per job by nature or differ between jobs, as variables over the grid."""
    having = [(index, ds[name]) for index, ds in done if name in ds.variables]
    for attr in _union([list(da.attrs) for _, da in having]):
        values = {index: da.attrs[attr] for index, da in having if attr in da.attrs}
        if attr not in PER_JOB_VARIABLE_ATTRS and len(values) == len(having) and _all_same(list(values.values())):
            continue
        variable = _cell_variable(values, shape, grid_dims, f"{name}_{attr}")
        if attr == "max_abs_drift":
            variable[2].update({"long_name": f"max |{name}(t) − {name}(0)|",
                                "units": having[0][1].attrs.get("units", "1")})
        else:
            units = (having[0][1].attrs.get("units") if attr == "invariant_allowed_drift"
                     else quantity_units(attr, body_units))
            variable[2].update({"long_name": f"attribute {attr} of {name}, per job", **_units(variable[1], units)})
        data_vars[f"{name}_{attr}"] = variable
        _index_coordinate(coords, variable, f"{name}_{attr}")


def _run_attributes(done: list[tuple[tuple, xr.Dataset]], coords: dict[str, Any], data_vars: dict[str, Any],
                    shape: tuple[int, ...], grid_dims: tuple[str, ...], body_units: str) -> dict[str, Any]:
    """The run attributes every finished job shares (returned); the others become per-job variables."""
    taken = set(coords) | set(data_vars) | set(grid_dims) | {"sample", "failed_job", "job_status", "job_dir",
                                                              "job_id", "title", "Conventions"}
    common: dict[str, Any] = {}
    for key in _union([list(ds.attrs) for _, ds in done]):
        if key in JOB_ONLY_ATTRS:
            continue
        values = {index: ds.attrs[key] for index, ds in done if key in ds.attrs}
        if key not in PER_JOB_ATTRS and len(values) == len(done) and _all_same(list(values.values())):
            common[key] = next(iter(values.values()))
            continue
        name = key if key not in taken else f"run_{key}"
        data_vars[name] = _cell_variable(values, shape, grid_dims, name)
        units, long_name = PER_JOB_METADATA.get(key, (None, f"run attribute {key}, per job"))
        data_vars[name][2].update({"long_name": long_name, **_units(data_vars[name][1],
                                                                    units or quantity_units(key, body_units))})
        taken.add(name)
        _index_coordinate(coords, data_vars[name], key)
    return common


def _job_table(grid: Grid, results: Sequence[JobResult], grid_dims: tuple[str, ...]) -> dict[str, Any]:
    """Every job's status, id and directory over the grid, and the failed jobs' table."""
    statuses = np.zeros(grid.shape, dtype=np.int8)
    job_ids, job_dirs = np.full(grid.shape, "", dtype=object), np.full(grid.shape, "", dtype=object)
    for index, result in zip(grid.index, results):
        statuses[index], job_ids[index], job_dirs[index] = STATUS_FLAGS[result.status], result.job_id, result.job_dir
    return {"job_status": (grid_dims, statuses, {"long_name": "how the job ended", **STATUS_ATTRS}),
            "job_id": (grid_dims, job_ids, {"long_name": "hash of the job's resolved config and code version"}),
            "job_dir": (grid_dims, job_dirs, {"long_name": "job directory, relative to the sweep directory"}),
            **_failure_table(grid, results)}


def _union(lists: Sequence[Sequence[str]]) -> list[str]:
    return list(dict.fromkeys(item for items in lists for item in items))


def _blank(shape: tuple[int, ...], dtype: np.dtype) -> np.ndarray:
    if dtype.kind in "fc":
        return np.full(shape, np.nan, dtype=dtype)
    if dtype.kind in "iub":
        return np.full(shape, np.nan, dtype=np.float64)   # NaN marks failed jobs: integers become floats
    return np.full(shape, "", dtype=object)


def _stack(done: Sequence[tuple[tuple[int, ...], xr.Dataset]], name: str, shape: tuple[int, ...],
           grid_dims: tuple[str, ...], sample: str) -> tuple:
    having = [(index, ds[name]) for index, ds in done if name in ds.variables]
    template = having[0][1]
    dims = tuple(sample if d == "time" else d for d in template.dims)
    for _, da in having:
        if da.dims != template.dims:
            raise ConfigError(f"variable {name!r} has dimensions {da.dims} in one job and {template.dims} in "
                              "another; they cannot share one sweep.nc")
    sizes = [max(da.shape[i] for _, da in having) for i in range(template.ndim)]
    out = _blank(shape + tuple(sizes), template.dtype)
    for index, da in having:
        out[index + tuple(slice(0, n) for n in da.shape)] = da.values
    return grid_dims + dims, out, _common_attrs([da for _, da in having])


def _common_attrs(arrays: Sequence[xr.DataArray]) -> dict[str, Any]:
    """Attributes equal in every job (the others become per-job variables, see ``_add_per_job_attrs``)."""
    return {k: v for k, v in arrays[0].attrs.items() if k not in PER_JOB_VARIABLE_ATTRS
            and all(k in da.attrs and _same(v, da.attrs[k]) for da in arrays)}


def _units(values: Any, units: str | None) -> dict[str, str]:
    """``{"units": units}`` for numeric values whose units are known; text has none."""
    numeric = np.asarray(values).dtype.kind in "iufb"
    return {"units": units} if numeric and units else {}


def _index_coordinate(coords: dict[str, Any], variable: tuple, key: str) -> None:
    """A per-job vector attribute (``initial_omega``) lies along ``<name>_index``: give that dimension a coordinate
    (component 0, 1, 2, ...) that says what it counts."""
    for dim, size in zip(variable[0], np.shape(variable[1])):
        if dim.endswith("_index") and dim not in coords:
            coords[dim] = (dim, np.arange(size, dtype=np.int32), {
                "long_name": f"component of run attribute {key} (as stored in each job's run.nc, from 0)",
                "units": "1"})


def _cell_variable(values: dict[tuple[int, ...], Any], shape: tuple[int, ...], grid_dims: tuple[str, ...],
                   name: str) -> tuple:
    """A variable over the swept dims from one value per grid point (missing points: NaN or '')."""
    items = list(values.values())
    arrays = [np.asarray(v) for v in items]
    if items and all(_is_number(v) for v in items):
        dims, out = grid_dims, np.full(shape, np.nan)
    elif items and all(a.ndim == 1 and a.dtype.kind in "iuf" and a.shape == arrays[0].shape for a in arrays):
        dims, out = grid_dims + (f"{name}_index",), np.full(shape + arrays[0].shape, np.nan)
    else:
        dims, out = grid_dims, np.full(shape, "", dtype=object)
        values = {index: value if isinstance(value, str) else np.array2string(np.asarray(value), separator=", ")
                  for index, value in values.items()}
    for index, value in values.items():
        out[index] = value
    return dims, out, {}


def _failure_table(grid: Grid, results: Sequence[JobResult]) -> dict[str, tuple]:
    failed = [(n, r) for n, r in enumerate(results) if r.status == FAILED]
    columns = {"dir": ([r.job_dir for _, r in failed], "failed job's directory, relative to the sweep directory"),
               "overrides": ([" ".join(grid.jobs[n]) for n, _ in failed], "failed job's overrides"),
               "error": ([r.error for _, r in failed], "error message"),
               "error_type": ([r.error_type for _, r in failed], "error class")}
    table = {f"failed_job_{name}": (("failed_job",), np.array(values, dtype=object), {"long_name": long_name})
             for name, (values, long_name) in columns.items()}
    table["failed_job_exit_code"] = (("failed_job",), np.array([r.exit_code for _, r in failed], dtype=np.int32),
                                     {"long_name": "exit code the single-run command would give", "units": "1"})
    return table


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))


def _same(a: Any, b: Any) -> bool:
    """Equal attribute values (arrays element by element; NaN equals NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return (a.shape == b.shape and a.dtype.kind == b.dtype.kind
                and bool(np.array_equal(a, b, equal_nan=a.dtype.kind == "f")))
    if _is_number(a) and _is_number(b):
        return bool(a == b or (np.isnan(a) and np.isnan(b)))
    return type(a) is type(b) and a == b


def _all_same(values: Sequence[Any]) -> bool:
    return all(_same(v, values[0]) for v in values[1:])


def collect(sweep_dir: Path, grid: Grid) -> list[JobResult]:
    """Each grid job's outcome, from the job records under ``sweep_dir`` (matched by their overrides)."""
    sweep_dir = Path(sweep_dir)
    found: dict[tuple[str, ...], tuple[float, Path, JobRecord]] = {}
    for path in record_paths(sweep_dir):
        record = read_record(path.parent)
        if record is None:
            log.warning("%s is not a job record gyrolab wrote (too large, too deep, or edited); that job counts as "
                        "missing and runs again when the sweep is resumed", path)
            continue
        key, mtime = tuple(record.overrides), path.stat().st_mtime
        if key not in found or found[key][0] < mtime:  # a stale copy elsewhere: the newest record wins
            found[key] = (mtime, path.parent, record)
    return [_result(sweep_dir, *found[job][1:]) if job in found else JobResult() for job in grid.jobs]


def _result(sweep_dir: Path, job_dir: Path, record: JobRecord) -> JobResult:
    """How the job of ``record`` ended: failed, finished with its dataset, or missing (a dataset that is not its)."""
    where = job_dir.relative_to(sweep_dir).as_posix()
    common = {"job_id": record.job_id, "job_dir": where, "skipped": record.skipped}
    if record.status == FAILED:
        return JobResult(FAILED, error=record.error, error_type=record.error_type, exit_code=record.exit_code,
                         **common)
    try:
        ds = load_dataset(job_dir / str(record.run), "a run.nc that gyrolab wrote", decode_times=False,
                          decode_timedelta=False)
    except ConfigError as error:
        log.warning("job %s: %s; counted as missing", where, error)
        return JobResult()
    if ds.attrs.get("job_id") != record.job_id:
        log.warning("job %s: its dataset belongs to another job (id %s, record %s); counted as missing",
                    where, ds.attrs.get("job_id"), record.job_id)
        return JobResult()
    return JobResult(FINISHED, dataset=ds, **common)


def aggregate_sweep(sweep_dir: Path, *, hydra_cfg: Any | None = None, figures: bool | None = None,
                    launcher: str = "", output: Any | None = None) -> SweepSummary:
    """Write ``sweep_dir/sweep.nc`` (and summary figures) from the sweep's job directories. ``hydra_cfg``, ``output``:
    the multirun's ``hydra`` node and ``output`` section, else read from ``sweep_dir/multirun.yaml``;
    ``figures=None``: as the sweep's callback was configured."""
    sweep_dir = Path(sweep_dir)
    check_tree(sweep_dir, sweep=True)
    if hydra_cfg is None:
        hydra_cfg = stored_hydra(sweep_dir)
        launcher = launcher or str(hydra_cfg.get("launcher", {}).get("_target_", "")).rsplit(".", 1)[-1]
    if figures is None:
        figures = bool(OmegaConf.select(hydra_cfg, "callbacks.sweep.figures", default=True))
    grid = Grid.from_hydra(hydra_cfg)
    wait_for_jobs(sweep_dir)
    # Two processes resuming one sweep aggregate one after the other; the later one sees every job.
    try_lock(sweep_dir, blocking=True)
    try:
        clear_temporaries(sweep_dir)
        results = collect(sweep_dir, grid)
        try:
            ds = assemble(grid, results)
        except FOREIGN_ERRORS as error:  # jobs' datasets that gyrolab did not write as they are
            raise ConfigError(f"the jobs' datasets in {shorten(str(sweep_dir))!r} do not fit one sweep.nc "
                              f"({type(error).__name__}); a job's run.nc was edited: remove that job's directory "
                              "and resume the sweep") from None
        ds.attrs["sweep_launcher"] = launcher
        path = write_dataset(ds, sweep_dir / SWEEP_NAME)
    finally:
        unlock(sweep_dir)
    summary = SweepSummary(
        path=path, n_jobs=len(results), finished=int(ds.attrs["n_finished"]), failed=int(ds.attrs["n_failed"]),
        missing=int(ds.attrs["n_missing"]), skipped=sum(r.skipped for r in results),
        failures=[(" ".join(grid.jobs[n]), r.error) for n, r in enumerate(results) if r.status == FAILED],
        write_failures=sum(r.status == FAILED and r.error_type == "OutputError" for r in results))
    if figures and grid.dims and summary.finished:
        from gyrolab.figures.sweep import save_figures  # matplotlib only when figures are drawn

        if output is None:  # the sweep's figure formats and dpi, as multirun.yaml stores them (else the defaults)
            saved = sweep_dir / "multirun.yaml"
            output = stored_yaml_file(saved).get("output") if saved.is_file() else None
        summary.figures = save_figures(ds, sweep_dir / "figures", *figure_options(output))
    return summary


def stored_hydra(sweep_dir: Path) -> DictConfig:
    """The ``hydra`` node of the sweep stored in ``sweep_dir/multirun.yaml``, read as untrusted input
    (``gyrolab.output.user_yaml.stored_yaml_file``); ConfigError when there is none."""
    saved = Path(sweep_dir) / "multirun.yaml"
    if not saved.is_file():
        raise ConfigError(f"{str(sweep_dir)!r} is not a sweep directory (no multirun.yaml); give the "
                          "directory a 'gyrolab -m ...' run wrote (its hydra.sweep.dir)")
    hydra_cfg = OmegaConf.create(stored_yaml_file(saved)).get("hydra")
    if not isinstance(hydra_cfg, DictConfig) or "overrides" not in hydra_cfg:
        raise ConfigError(f"{str(saved)!r} has no hydra.overrides section; give the directory a 'gyrolab -m ...' "
                          "run wrote (its hydra.sweep.dir)")
    return hydra_cfg


def wait_for_jobs(sweep_dir: Path) -> None:
    """Wait for the jobs of this sweep that another process is running (a concurrent resume)."""
    for job_dir in (path.parent for path in record_paths(sweep_dir, LOCK_NAME) if path.parent != Path(sweep_dir)):
        owner = owner_of(job_dir)
        if owner:
            log.info("waiting for job %s, run by another gyrolab process (%s)", job_dir.relative_to(sweep_dir).as_posix(),
                     owner)
        wait_for(job_dir)


def log_summary(summary: SweepSummary) -> None:
    log.info("sweep: %d jobs: %d finished, %d failed, %d missing; skipped %d finished jobs (done earlier)",
             summary.n_jobs, summary.finished, summary.failed, summary.missing, summary.skipped)
    for overrides, error in summary.failures:
        log.warning("failed job (%s): %s", overrides, error)
    announce_written(summary.path)  # results to stdout (gyrolab.output.written)
    for figure in summary.figures:
        announce_written(figure)
