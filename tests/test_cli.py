"""The gyrolab command: default scene, figures, multirun."""

import xarray as xr


def test_default_run_writes_dataset_and_figures(cli, tmp_path):
    done = cli("hydra.run.dir=out", "time.end=5", "time.n_output=101")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        assert ds.sizes["time"] == 101
        assert "hydra_overrides" in ds.attrs and "time.end=5" in ds.attrs["hydra_overrides"]
    figures = sorted(p.name for p in (tmp_path / "out" / "figures").iterdir())
    assert figures == ["body_axis_sphere.png", "euler_angles.png", "invariant_drift.png", "state.png"]


def test_multirun_writes_one_dataset_per_job(cli, tmp_path):
    done = cli("-m", "integrator=rk4,dop853", "time.end=1", "time.n_output=11", "output.figures=false",
               "hydra.sweep.dir=sweep")
    assert done.returncode == 0, done.stderr
    names = []
    for job in ("0", "1"):
        with xr.open_dataset(tmp_path / "sweep" / job / "run.nc") as ds:
            names.append(ds.attrs["integrator"])
    assert names == ["rk4", "dop853"]



def test_multirun_jobs_draw_no_figures_unless_asked(cli, tmp_path):
    """Issue 24 item 3: a sweep's jobs skip their own figures by default (the sweep's figures stay);
    ``output.job_figures=true`` draws them, and ``gyrolab --plot`` draws them later from the datasets."""
    done = cli("-m", "initial.r0=1,2", "time.end=1", "time.n_output=11", "hydra.sweep.dir=sweep")
    assert done.returncode == 0, done.stderr
    for job in ("0", "1"):
        assert (tmp_path / "sweep" / job / "run.nc").is_file()
        assert not (tmp_path / "sweep" / job / "figures").exists()
    assert any((tmp_path / "sweep" / "figures").iterdir())          # the sweep's own figures
    later = cli("--plot", "sweep")
    assert later.returncode == 0, later.stderr
    assert (tmp_path / "sweep" / "0" / "figures" / "state.png").is_file()

    asked = cli("-m", "initial.r0=1", "time.end=1", "time.n_output=11", "output.job_figures=true",
                "hydra.sweep.dir=asked")
    assert asked.returncode == 0, asked.stderr
    assert (tmp_path / "asked" / "0" / "figures" / "state.png").is_file()


import pytest  # noqa: E402

EXPERIMENTS = {
    # experiment (or regime) -> (extra overrides keeping it small, files it must write)
    "regime=small_parameter": ([], ["regime.nc", "figures/regime_comparison.png"]),
    "experiment=ismail2021_tables": ([], ["table1.csv", "table2.csv"]),
    "experiment=shaker_omega3": ([], []),
    # the experiments' results are tested in-process elsewhere: here one regime, three points, one orbit
    "experiment=regime_validity": (["regime_validity.regimes=[small_parameter]", "regime_validity.evidence=[]",
                                    "regime_validity.small_parameter.values=[0.25,0.125,0.0625]",
                                    "regime_validity.small_parameter.fit_below=0.3",
                                    "~regime_validity.resonance_sweep"], ["regime_validity.nc"]),
    "experiment=yehia2021_precessions": (["yehia2021.orbits=1"], ["precession_cases.csv"]),
    "experiment=work_precision": (["time.end=5", "work_precision.repeats=1", "~work_precision.methods",
                                   "+work_precision.methods={taylor: {tol: [1e-10]}, rk4_numba: {step: [0.01]}}"],
                                  ["work_precision.nc", "figures/error_vs_wall_time.png"]),
}


@pytest.mark.slow
@pytest.mark.parametrize("selector", EXPERIMENTS)
def test_every_experiment_runs_from_the_command_line(selector, cli, tmp_path):
    extra, expected = EXPERIMENTS[selector]
    done = cli(selector, *extra, "hydra.run.dir=out")
    assert done.returncode == 0, done.stderr[-2000:]
    written = [p for p in (tmp_path / "out").rglob("*") if p.is_file() and ".hydra" not in p.parts]
    assert any(p.suffix in (".nc", ".csv") for p in written), written
    for name in expected:
        assert (tmp_path / "out" / name).exists(), name
