"""No config value a run silently ignores (gyrolab.engine.unread; docs/configs.md "Values a run does not read").

A value the user gives and the run does not read is refused in one sentence before anything is written; a value
a config file set (an experiment's default) lets the run proceed, says so once and is recorded in the dataset.
"""

import pytest
import xarray as xr

from gyrolab import compose_scene
from gyrolab.engine.unread import ACCURACY_IGNORED_ATTRIBUTE, given_overrides, reads_accuracy
from gyrolab.engine.config import compose_config
from gyrolab.errors import ConfigError

SHORT = ("time.end=1", "output.figures=false")


def _one_error_line(done):
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("gyrolab: error: ")
    return lines[0]


# -- accuracy given, not read: refused ----------------------------------------------------------------------------

def test_accuracy_given_to_an_integrator_that_does_not_read_it_is_refused_before_the_run_directory(cli, tmp_path):
    done = cli("integrator=taylor", "accuracy=1e-8", *SHORT, "hydra.run.dir=out")
    assert _one_error_line(done) == (
        "gyrolab: error: accuracy=1e-08 is the target of integrator=auto only; integrator=taylor does not read it and "
        "runs at its own settings (integrator.tol=1e-16): ask integrator=auto accuracy=1e-08 or set integrator.tol "
        "instead (and drop accuracy=1e-08)")
    assert not (tmp_path / "out").exists()
    assert not list(tmp_path.rglob("run.nc"))


@pytest.mark.parametrize("integrator, settings", [
    ("rk4", "integrator.step=0.01"),
    ("dop853", "integrator.rtol=1e-10, integrator.atol=1e-10"),
    ("lie_poisson", "integrator.step=0.01"),
])
def test_compose_scene_refuses_a_given_accuracy_naming_the_integrators_own_settings(integrator, settings):
    with pytest.raises(ConfigError) as refused:
        compose_scene([f"integrator={integrator}", "accuracy=1e-7", "time.end=1"])
    text = str(refused.value)
    assert f"accuracy=1e-07 is the target of integrator=auto only; integrator={integrator} does not read it" in text
    assert f"({settings})" in text and "ask integrator=auto accuracy=1e-07" in text


def test_an_accuracy_an_integrator_reads_is_accepted_whatever_its_name():
    # auto reads it through its packaged setting; any integrator reads it when a setting refers to it
    assert compose_scene(["integrator=auto", "accuracy=1e-8", "time.end=1"]).integrator.accuracy == 1e-8
    scene = compose_scene(["integrator=taylor", "integrator.tol=${accuracy}", "accuracy=1e-10", "time.end=1"])
    assert scene.integrator.tol == 1e-10


def test_an_accuracy_replaced_by_the_integrators_own_setting_is_refused():
    with pytest.raises(ConfigError, match=r"accuracy=1e-08 is not read: integrator=auto runs at its own settings "
                                          r"\(integrator.accuracy=1e-06\), which replace it"):
        compose_scene(["integrator=auto", "integrator.accuracy=1e-6", "accuracy=1e-8", "time.end=1"])


def test_a_sweep_whose_jobs_none_read_the_given_accuracy_is_refused(cli, tmp_path):
    done = cli("-m", "integrator=dop853,taylor", "accuracy=1e-6", *SHORT, "hydra.sweep.dir=sweep")
    assert "accuracy=1e-06 is the target of integrator=auto only; integrator=dop853" in _one_error_line(done)
    assert not (tmp_path / "sweep").exists()


def test_a_batch_given_an_accuracy_its_integrator_does_not_read_is_refused(cli, tmp_path):
    done = cli("batch", "integrator=rk4_numba", "accuracy=1e-8", "initial.r0=1,2", "time.end=1", "time.n_output=2",
               "hydra.sweep.dir=b")
    assert "integrator=rk4_numba does not read it" in _one_error_line(done)
    assert not (tmp_path / "b").exists()


def test_accuracy_null_and_deleting_it_are_not_values():
    assert set(given_overrides(["accuracy=1e-8", "+batch.output=final", "~time.n_output", "++x.y=1"])) == {
        "accuracy", "batch.output", "x.y"}
    compose_scene(["integrator=taylor", "accuracy=null", "time.end=1"])


def test_whether_accuracy_is_read_is_asked_of_the_config_not_the_name():
    assert reads_accuracy(compose_config(["integrator=auto"]))
    assert not reads_accuracy(compose_config(["integrator=auto", "integrator.accuracy=1e-6"]))
    assert not reads_accuracy(compose_config(["integrator=taylor"]))
    assert reads_accuracy(compose_config(["integrator=taylor", "integrator.tol=${accuracy}", "accuracy=1e-9"]))


# -- accuracy from a config file, not read: the run proceeds, says so once, records it ---------------------------

def test_an_experiments_accuracy_the_integrator_does_not_read_is_warned_once_and_recorded(cli, tmp_path):
    done = cli("experiment=perf_reference", "integrator=taylor", *SHORT, "hydra.run.dir=out")
    assert done.returncode == 0, done.stderr
    said = [line for line in done.stderr.splitlines() if "accuracy=1e-08" in line]
    assert len(said) == 1 and "WARNING" in said[0], done.stderr
    assert "integrator=taylor does not read it" in said[0] and "a config file set it" in said[0]
    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        recorded = ds.attrs[ACCURACY_IGNORED_ATTRIBUTE]
    assert recorded in said[0]


def test_the_python_api_says_and_records_an_experiments_accuracy_the_integrator_does_not_read(caplog):
    with caplog.at_level("WARNING", logger="gyrolab"):
        scene = compose_scene(["experiment=perf_reference", "integrator=taylor", "time.end=1"])
    said = [r.getMessage() for r in caplog.records if "accuracy=1e-08" in r.getMessage()]
    assert len(said) == 1 and "integrator=taylor does not read it" in said[0]
    assert scene.run().attrs[ACCURACY_IGNORED_ATTRIBUTE] == said[0]
    read = compose_scene(["experiment=perf_reference", "time.end=1"])  # auto reads it: nothing to say
    assert read.accuracy_ignored is None and ACCURACY_IGNORED_ATTRIBUTE not in read.run().attrs


def test_a_sweep_over_integrators_gives_the_accuracy_to_the_jobs_that_read_it_and_records_the_others(cli, tmp_path):
    done = cli("-m", "integrator=auto,taylor", "accuracy=1e-6", *SHORT, "hydra.sweep.dir=sweep")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "sweep" / "0" / "run.nc") as auto, \
            xr.open_dataset(tmp_path / "sweep" / "1" / "run.nc") as taylor:
        assert auto.attrs["integrator"] != taylor.attrs["integrator"]
        assert ACCURACY_IGNORED_ATTRIBUTE not in auto.attrs
        assert "integrator=taylor does not read it" in taylor.attrs[ACCURACY_IGNORED_ATTRIBUTE]
        assert "the sweep gives it to every job" in taylor.attrs[ACCURACY_IGNORED_ATTRIBUTE]


def test_a_batch_from_an_experiment_whose_accuracy_its_integrator_does_not_read_says_so_and_records_it(cli, tmp_path):
    done = cli("batch", "experiment=perf_reference", "integrator=taylor", "initial.r0=1,2", "time.end=1",
               "time.n_output=2", "hydra.sweep.dir=b")
    assert done.returncode == 0, done.stderr
    said = [line for line in done.stderr.splitlines() if "accuracy=1e-08" in line]
    assert len(said) == 1 and "WARNING" in said[0] and "integrator=taylor does not read it" in said[0], done.stderr
    with xr.open_dataset(tmp_path / "b" / "sweep.nc") as ds:
        assert ds.attrs[ACCURACY_IGNORED_ATTRIBUTE] in said[0]


# -- keys only some runs read, given to a run that does not read them: refused ------------------------------------

@pytest.mark.parametrize("argv, sentence", [
    (["batch.output=final"], "batch.output=final is read only by task stability_map or gyrolab batch; this run "
                             "(task scene) does not read it, so it would change nothing: run it with gyrolab batch, "
                             "or drop it"),
    (["-m", "batch.decimate=5", "initial.r0=1,2"], "batch.decimate=5 is read only by task stability_map or gyrolab "
                                                   "batch; this run (task scene in a sweep (gyrolab -m)) does not"),
    (["output.job_figures=true"], "output.job_figures=true is read only by a sweep (gyrolab -m); this run (task scene) "
                                  "does not read it"),
    (["experiment=stability_map", "regime=small_parameter"],
     "regime=small_parameter is read only by task regime or task shaker_omega3; this run (task stability_map)"),
    (["batch", "regime=small_parameter", "initial.r0=1,2"], "regime=small_parameter is read only by task regime or "
                                                            "task shaker_omega3; this run (gyrolab batch)"),
    (["regime=small_parameter", "output.error_estimate=true"],
     "output.error_estimate=true is read only by task scene, task work_precision or task yehia2021_precessions; this "
     "run (task regime) does not read it, so it would change nothing: drop it"),
    (["experiment=work_precision", "integrator=taylor"],
     "integrator=taylor is not read by task work_precision (it runs every method of work_precision.methods); "
     "drop it"),
    (["experiment=work_precision", "accuracy=1e-9"], "accuracy=1e-9 is not read by task work_precision"),
    (["experiment=work_precision", "time.n_output=50"], "time.n_output=50 is not read by task work_precision"),
    (["experiment=yehia2021_precessions", "initial.r0=3"], "initial.r0=3 is not read by task yehia2021_precessions "
                                                           "(each precession case sets its own body"),
    (["experiment=orbit_family", "body.a=3"], "body.a=3 is not read by task orbit_family (each family of "
                                              "orbit_family.families sets its own body"),
    (["experiment=ismail2021_tables", "integrator=rk4"], "integrator=rk4 is not read by task ismail2021_tables"),
    (["experiment=stability_map", "initial.r0=3"], "initial.r0=3 is not read by task stability_map (the map's grid "
                                                   "sets it"),
    (["batch", "output.error_estimate=true", "initial.r0=1,2"],
     "output.error_estimate=true is read only by task scene, task work_precision or task yehia2021_precessions; this "
     "run (gyrolab batch) does not read it"),
])
def test_a_value_given_to_a_run_that_does_not_read_it_is_one_sentence_and_writes_nothing(argv, sentence, cli, tmp_path):
    directories = ["hydra.sweep.dir=sweep"] if argv[0] == "batch" else ["hydra.run.dir=out", "hydra.sweep.dir=sweep"]
    done = cli(*argv, *SHORT, *directories)
    assert sentence in _one_error_line(done)
    assert not (tmp_path / "out").exists() and not (tmp_path / "sweep").exists()


def test_the_runs_that_read_those_keys_still_take_them():
    from gyrolab.experiments import refuse_unread

    refuse_unread("task scene", ["output.error_estimate=true"])
    refuse_unread("gyrolab batch", ["batch.output=final", "batch.decimate=5"])
    refuse_unread("task stability_map", ["batch.points=100"])
    refuse_unread("task work_precision", ["time.end=50", "output.error_estimate=false"])
    refuse_unread("task yehia2021_precessions", ["integrator=taylor", "yehia2021.orbits=2"])
    refuse_unread("task orbit_family", ["orbit_family.families.x.r0_end=1", "output.figures=false"])
    refuse_unread("task shaker_omega3", ["regime.periods=2"])
    refuse_unread("task scene", ["output.job_figures=true"], sweep=True)
    refuse_unread("task stability_map", ["regime=null"])   # null unsets: nothing to read
    # a config file's value is a default for the runs that read it: only overrides are checked
    refuse_unread("task scene", [])


def test_a_work_precision_method_given_an_accuracy_it_does_not_read_is_refused_before_the_run_directory(cli, tmp_path):
    done = cli("experiment=work_precision", "work_precision.repeats=1", "~work_precision.methods",
               "+work_precision.methods={taylor: {accuracy: [1e-8]}}", *SHORT, "hydra.run.dir=out")
    assert _one_error_line(done).startswith(
        "gyrolab: error: work_precision.methods.taylor.accuracy: accuracy=1e-08 is the target of integrator=auto only; "
        "integrator=taylor does not read it")
    assert not (tmp_path / "out").exists()


def test_a_regime_run_whose_integrator_does_not_read_the_configs_accuracy_records_it(tmp_path):
    from omegaconf import open_dict

    from gyrolab.experiments import run_task

    cfg = compose_config(["regime=small_parameter", "initial.r0=20", "initial.theta0=1.5", "regime.periods=1",
                          "regime.samples_per_period=40", "output.figures=false", "integrator=taylor"])
    with open_dict(cfg):
        cfg.accuracy = 1e-9   # as an experiment file would set it, for auto
    run_task("regime", cfg, tmp_path)
    with xr.open_dataset(tmp_path / "regime.nc") as ds:
        assert "accuracy=1e-09 is the target of integrator=auto only; integrator=taylor does not read it" in \
            ds.attrs[ACCURACY_IGNORED_ATTRIBUTE]
