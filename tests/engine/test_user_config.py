"""A user's own config directory works everywhere the packaged one does (docs/configs.md "Your own configs").

Everything runs from a temporary directory outside the source tree, on a copy of
examples/myconf (the README's example), in this process (a handful of steps keeps it fast).
"""

import shutil

import pytest
import xarray as xr

from gyrolab.sweep.aggregate import FINISHED, STATUS_FLAGS
from tests.helpers import REPO, run_main

SMALL = ["time.end=1", "time.n_output=11"]


@pytest.fixture
def myconf(tmp_path, monkeypatch):
    shutil.copytree(REPO / "examples" / "myconf", tmp_path / "myconf")
    monkeypatch.chdir(tmp_path)
    return tmp_path / "myconf"


def stored(path):
    with xr.open_dataset(path) as ds:
        return ds.attrs["config"], ds.attrs["integrator"], ds.sizes["time"]


def test_user_experiment_runs_as_written(myconf, tmp_path, monkeypatch, capsys):
    code, err = run_main(["--config-dir=myconf", "+experiment=lopsided_top", "time.end=1", "hydra.run.dir=out"],
                         monkeypatch, capsys)
    assert code == 0, err
    config, integrator, n = stored(tmp_path / "out" / "run.nc")
    # lopsided_top.yaml: its own body option (a = 1.8, b = 1.2), rk45, r0 = 2, 201 samples
    assert (integrator, n) == ("rk45", 201)
    assert "a: 1.8" in config and "b: 1.2" in config and "r0: 2.0" in config and "rtol: 1.0e-09" in config


def test_user_primary_config_runs(myconf, tmp_path, monkeypatch, capsys):
    # a relative --config-path is read from the working directory
    code, err = run_main(["-cp", "myconf", "-cn", "mine", "hydra.run.dir=out"], monkeypatch, capsys)
    assert code == 0, err
    config, integrator, n = stored(tmp_path / "out" / "run.nc")
    assert (integrator, n) == ("dop853", 101) and "a: 1.8" in config and not (tmp_path / "out" / "figures").exists()


@pytest.mark.parametrize("argv, expected", [
    (["hydra.searchpath=[file://{conf}]", "experiment=lopsided_top"], ("RK45", 1.8, 201)),
    (["--config-dir", "myconf", "--config-name", "mine"], ("DOP853", 1.8, 101)),
    (["--config-path", "myconf", "--config-name", "mine", "body=asymmetric_top"], ("DOP853", 2.0, 101)),
])
def test_the_preflight_composes_the_users_config(argv, expected, myconf, monkeypatch):
    """Each form passes the preflight, which composes from the user's folder (the runs above: Hydra agrees)."""
    from gyrolab import app
    from gyrolab.app.parser import parse_command_line
    from gyrolab.engine.config import ConfigSource, compose_config, use_source

    args = app.absolute_config_path(parse_command_line([a.format(conf=myconf) for a in argv])[1])
    try:
        app.preflight(parse_command_line([*[a.format(conf=myconf) for a in argv], "hydra.run.dir=out"])[1])
        overrides = args.overrides
        cfg = compose_config(overrides)  # composes from the source the preflight set
    finally:
        use_source(ConfigSource())
    assert (cfg.integrator._target_.rsplit(".", 1)[1], cfg.body.a, cfg.time.n_output) == expected
def test_user_configs_in_a_multirun_a_batch_and_a_reproduction(myconf, tmp_path, monkeypatch, capsys):
    code, err = run_main(["-m", "--config-dir", "myconf", "experiment=lopsided_top", "initial.r0=1,2", *SMALL,
                          "hydra.sweep.dir=sweep"], monkeypatch, capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "sweep" / "sweep.nc") as ds:
        assert list(ds["job_status"].values) == [STATUS_FLAGS[FINISHED]] * 2
    assert "a: 1.8" in stored(tmp_path / "sweep" / "1" / "run.nc")[0]
    code, err = run_main(["--config-dir", "myconf", "--batch", "body=lopsided", "integrator=rk4",
                          "initial.r0=1,2", *SMALL, "hydra.sweep.dir=batch"], monkeypatch, capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "batch" / "sweep.nc") as ds:
        assert ds.attrs["sweep_launcher"] == "batch" and ds.sizes["r0"] == 2 and ds.attrs["body_a"] == 1.8
    code, err = run_main(["--reproduce", "sweep/1/run.nc"], monkeypatch, capsys)
    assert code == 0, err


def test_the_preflight_validates_the_users_config(myconf, tmp_path, monkeypatch, capsys):
    """A typo or a bad value in the user's own file is refused like one on the command line."""
    (myconf / "experiment" / "typo.yaml").write_text("# @package _global_\ntime:\n  ennd: 5.0\n")
    (myconf / "experiment" / "task.yaml").write_text("# @package _global_\ntask: work_precison\n")
    (myconf / "experiment" / "large.yaml").write_text("# @package _global_\ntime:\n  n_output: 1000000000\n")
    for name, phrase in (("typo", "`time.ennd` is not a key of `time`; did you mean `time.end`?"),
                         ("task", "did you mean task=work_precision?"), ("large", "67.1 GiB"),
                         ("lopsided_topp", "did you mean experiment=lopsided_top?")):
        code, err = run_main(["--config-dir", "myconf", f"experiment={name}", "hydra.run.dir=out"],
                             monkeypatch, capsys)
        assert code == 2 and phrase in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out").exists()


def test_run_dir_may_use_hydra_resolvers(tmp_path, monkeypatch):
    # ${hydra:...} in the run directory is Hydra's own idiom: the preflight resolves it as the run will
    from gyrolab import app
    from gyrolab.app.parser import parse_command_line

    monkeypatch.chdir(tmp_path)
    args = app.preflight(parse_command_line(["hydra.run.dir=${hydra:runtime.cwd}/by_cwd", "time.end=1"])[1])
    assert "hydra.run.dir=${hydra:runtime.cwd}/by_cwd" in args.overrides


def test_a_user_file_that_a_packaged_one_shadows_is_one_warning_line(myconf, tmp_path, monkeypatch, capsys):
    from gyrolab.engine import config

    # gyrolab's own body/lagrange_top.yaml is found first (--config-dir goes after it on Hydra's search path)
    (myconf / "body" / "lagrange_top.yaml").write_text((REPO / "conf" / "body" / "lagrange_top.yaml").read_text()
                                                       .replace("a: 0.8", "a: 1.7"))
    config.warn_shadowed.cache_clear()
    code, err = run_main(["--config-dir=myconf", "body=lagrange_top", *SMALL, "output.figures=false",
                          "hydra.run.dir=out"], monkeypatch, capsys)
    assert code == 0, err
    warned = [line for line in err.splitlines() if line.startswith("gyrolab: warning:")]
    assert warned == ["gyrolab: warning: myconf/body/lagrange_top.yaml is not read: gyrolab's own body option "
                      "'lagrange_top' has the same name and is found first (--config-dir is searched after gyrolab's "
                      "configs); give yours another name and choose it by that name (body=lagrange_top_mine)"]
    assert "a: 0.8" in stored(tmp_path / "out" / "run.nc")[0]   # what the warning says: gyrolab's file ran
    config.warn_shadowed.cache_clear()
