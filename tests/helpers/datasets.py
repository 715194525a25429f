"""Every dataset kind gyrolab writes, one small one each, built in this process and written with ``write_dataset``:
``KINDS`` maps a kind to a builder ``(tmp_path, monkeypatch) -> (dataset, path)`` (run.nc of both systems, multirun
and --batch sweep.nc, regime.nc, every experiment's dataset, the stability map). The experiments run their real
code up to the dataset write; their figures are not drawn."""

import importlib
from pathlib import Path

import pytest
import xarray as xr

from gyrolab import run
from gyrolab.batch.sweep import run_batch_sweep
from gyrolab.engine.config import compose_config
from gyrolab.experiments import TASKS, run_task
from gyrolab.figures import redraw
from gyrolab.output.cf import conform
from gyrolab.output.dataset import write_dataset
from gyrolab.sweep.aggregate import FINISHED, JobResult, assemble
from gyrolab.sweep.grid import Grid
from tests.helpers.regimes import overrides_000

TINY = ["time.end=1", "time.n_output=11", "output.figures=false"]


class _Written(Exception):
    """Raised after an experiment's dataset is written, so that its figures are not drawn."""


def _experiment(task: str, overrides: list[str], out_dir: Path, monkeypatch) -> tuple[xr.Dataset, Path]:
    module = importlib.import_module(TASKS[task])
    captured = []

    def write_and_stop(ds, path):
        captured.append((ds, write_dataset(ds, path)))
        raise _Written

    # experiments write through gyrolab.figures.redraw.write_and_draw; the stability map adds its sections itself
    monkeypatch.setattr(module if hasattr(module, "write_dataset") else redraw, "write_dataset", write_and_stop)
    with pytest.raises(_Written):
        run_task(task, compose_config(overrides), out_dir)
    return captured[0]


def assembled_sweep(overrides) -> xr.Dataset:
    """The sweep.nc a multirun of ``overrides`` assembles, its jobs run in this process."""
    grid = Grid.from_overrides(overrides)
    results = []
    for n, job in enumerate(grid.jobs):
        ds = run(list(job))
        ds.attrs.update(hydra_overrides=" ".join(job), job_id=f"job{n}")
        results.append(JobResult(FINISHED, ds, job_id=f"job{n}", job_dir=str(n)))
    return assemble(grid, results)


def _sweep(tmp_path, monkeypatch, overrides=("body.a=1.5,2",)):
    ds = assembled_sweep([*TINY, *overrides, "output.euler_angles=false"])
    return ds, write_dataset(ds, tmp_path / "sweep.nc")


def _batch(tmp_path, monkeypatch):
    path = run_batch_sweep(["integrator=rk4", "integrator.step=0.01", "body.a=1.5,2", "output.euler_angles=false",
                            *TINY], tmp_path)
    return xr.load_dataset(path, decode_times=False), path


def _batch_trajectory(tmp_path, monkeypatch):
    """A batch that stores whole trajectories: a time axis, as in a run."""
    path = run_batch_sweep(["integrator=rk4", "integrator.step=0.01", "batch.output=trajectory", "body.a=1.5,2",
                            "output.euler_angles=false", *TINY], tmp_path)
    ds = xr.load_dataset(path, decode_times=False)
    assert "time" in ds.dims
    return ds, path


def _batch_points(tmp_path, monkeypatch):
    """A list of points (``batch.zip``): one dimension ``point``, the swept keys coordinates along it."""
    path = run_batch_sweep(["integrator=rk4", "integrator.step=0.01", "batch.zip=true", "body.a=1.5,2",
                            "initial.r0=5,8", "output.euler_angles=false", *TINY], tmp_path)
    ds = xr.load_dataset(path, decode_times=False)
    assert ds.a.dims == ds.r0.dims == ("point",)
    return ds, path


def _yehia(tmp_path, monkeypatch):
    """One case of the Yehia table with its trace (the full table integrates every case for several orbits)."""
    from gyrolab.experiments import yehia2021_precessions as yehia
    from gyrolab.analysis.precession.cases import CASES
    from gyrolab.analysis.precession.closed_forms import check_closed_forms

    cfg = compose_config(["experiment=yehia2021_precessions", "yehia2021.orbits=0.1"])
    row, trace = yehia.evaluate(cfg, CASES[0], 0.1, 1e-10)
    traced = yehia.trace_variables([row], {row["label"]: trace})
    ds = yehia._dataset([row], check_closed_forms(), cfg).merge(traced, combine_attrs="override")
    ds.attrs.update(traced.attrs)
    ds = conform(ds, source="yehia2021_precessions experiment")
    return ds, write_dataset(ds, tmp_path / "precession_cases.nc")


def run_dataset(overrides):
    """A builder of the run.nc of ``overrides`` (a tiny scene)."""
    def build(tmp_path, monkeypatch):
        ds = run([*overrides, *TINY])
        return ds, write_dataset(ds, tmp_path / "run.nc")
    return build


def _task(task, overrides):
    return lambda tmp_path, monkeypatch: _experiment(task, overrides, tmp_path, monkeypatch)


KINDS = {
    "run_fixed_point": run_dataset([]),
    "run_orbiting_gyrostat": run_dataset(["body=gyrostat_symmetric", "force=[newtonian]", "force.newtonian.k=null"]),
    "sweep_multirun": _sweep,
    # jobs with different output times: time becomes a variable over (a, sample)
    "sweep_multirun_samples": lambda tmp_path, monkeypatch: _sweep(tmp_path, monkeypatch, ("time.end=1,2",)),
    "sweep_batch": _batch,
    "sweep_batch_points": _batch_points,
    "sweep_batch_trajectory": _batch_trajectory,
    "regime": _task("regime", [*overrides_000(20.0), "regime.periods=1", "regime.samples_per_period=50"]),
    "work_precision": _task("work_precision", [
        "experiment=work_precision", "time.end=1", "work_precision.repeats=1", "~work_precision.methods",
        "+work_precision.methods={dop853: {rtol: [1e-6]}}"]),
    "regime_validity": _task("regime_validity", [
        "experiment=regime_validity", "regime_validity.regimes=[small_parameter]", "regime_validity.evidence=[]",
        "regime_validity.small_parameter.values=[0.0625,0.03125]", "regime_validity.resonance_sweep=null"]),
    "ismail2021_tables": _task("ismail2021_tables", ["experiment=ismail2021_tables"]),
    "shaker_omega3": _task("shaker_omega3", ["experiment=shaker_omega3", "time.n_output=201"]),
    "yehia2021_precessions": _yehia,
    "orbit_family": _task("orbit_family", [
        "experiment=orbit_family", "~orbit_family.families",
        "+orbit_family.families={one: {label: default body, a: 2.0, b: 1.5, com_direction: [0.3, 0.2, "
        "0.9327379053088815], k: 0.5, theta0: 1.5, section: gamma_prime, r0_start: 100.0, r0_end: 60.0, "
        "max_points: 3, max_period: 40.0}}"]),
    "stability_map": _task("stability_map", [
        "experiment=stability_map", "batch.points=4", "time.end=0.5", "stability_map.sections=[[0.6,3.0]]",
        "stability_map.section_time=20", "output.figures=false"]),
}
