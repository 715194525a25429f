"""The gyrolab command: default scene, figures, multirun; subcommands, help, batch's sweep, the logging convention."""

import argparse
import sys

import pytest
import xarray as xr
import yaml

from tests.helpers import REPO


FIGURES = ["body_axis_sphere.png", "euler_angles.png", "invariant_drift.png", "state.png"]


def test_default_run_writes_dataset_and_figures(cli, tmp_path):
    done = cli("hydra.run.dir=out", "time.end=5", "time.n_output=101")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        assert ds.sizes["time"] == 101
        assert "hydra_overrides" in ds.attrs and "time.end=5" in ds.attrs["hydra_overrides"]
    figures = sorted(p.name for p in (tmp_path / "out" / "figures").iterdir())
    assert figures == FIGURES


def test_a_run_refused_while_integrating_leaves_no_run_folder(cli, tmp_path):
    """auto's pilot finds the docs' chaotic top beyond double-double at 1e-12 over t = 3000 (λ ≈ 0.11): one sentence,
    a non-zero exit and no folder of a run that never was; a folder the user gave, with files of their own, stays."""
    chaotic = ["integrator=auto", "accuracy=1e-12", "initial.p0=0.3", "initial.q0=-0.2", "initial.r0=2",
               "time.end=3000", "output.figures=false"]
    done = cli(*chaotic, "hydra.run.dir=out")
    assert done.returncode != 0 and "double-double" in done.stderr, done.stderr
    assert done.stderr.count("gyrolab: error:") == 1
    assert not (tmp_path / "out").exists()
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("kept")
    done = cli(*chaotic, "hydra.run.dir=mine")
    assert done.returncode != 0
    assert (tmp_path / "mine" / "notes.txt").read_text() == "kept" and not (tmp_path / "mine" / "run.nc").exists()


def test_multirun_writes_one_dataset_per_job(cli, tmp_path):
    done = cli("-m", "integrator=rk4,dop853", "time.end=1", "time.n_output=11", "output.figures=false",
               "hydra.sweep.dir=sweep")
    assert done.returncode == 0, done.stderr
    names = []
    for job in ("0", "1"):
        with xr.open_dataset(tmp_path / "sweep" / job / "run.nc") as ds:
            names.append(ds.attrs["integrator"])
    assert names == ["rk4", "dop853"]



@pytest.mark.slow
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


# ---- the command line's grammar: subcommands, old spellings, options anywhere ------------------------------------

from gyrolab.app.parser import (ALIASES, COMMANDS, build_parsers, parse_command_line, run_parser,  # noqa: E402
                                 split_command, value_options)
from gyrolab.errors import ConfigError  # noqa: E402

#: the options that take a value, read from every subcommand's parser
OPTIONS = value_options({"run": run_parser(), **build_parsers()})


@pytest.mark.parametrize("argv, command, rest", [
    ([], "run", []),
    (["-m", "integrator=rk4,dop853"], "run", ["-m", "integrator=rk4,dop853"]),
    (["experiment=x"], "run", ["experiment=x"]),
    (["run", "time.end=1"], "run", ["time.end=1"]),
    (["--config-dir", "run", "run"], "run", ["--config-dir", "run"]),         # a folder named like a subcommand
    (["batch", "a=1,2"], "batch", ["a=1,2"]),
    (["--batch", "--config-dir", "usercfg", "experiment=r0_scan"], "batch",
     ["--config-dir", "usercfg", "experiment=r0_scan"]),
    (["--config-dir", "usercfg", "--batch", "experiment=r0_scan"], "batch",
     ["--config-dir", "usercfg", "experiment=r0_scan"]),
    (["experiment=r0_scan", "--batch", "-cd", "usercfg"], "batch", ["experiment=r0_scan", "-cd", "usercfg"]),
    (["-cd", "usercfg", "batch", "x=1"], "batch", ["-cd", "usercfg", "x=1"]),
    (["--plot=out", "output.dpi=50"], "plot", ["out", "output.dpi=50"]),
    (["--new-force=drag"], "new-force", ["drag"]),
    (["--reproduce", "run.nc"], "reproduce", ["run.nc"]),
    (["aggregate", "sweep"], "aggregate", ["sweep"]),
    (["time.end=1", "plot"], "run", ["time.end=1", "plot"]),                  # after an override, a word is a value
])
def test_the_subcommand_is_found_wherever_it_is_spelled(argv, command, rest):
    assert split_command(argv, OPTIONS) == (command, rest)


def test_an_unknown_subcommand_is_one_sentence_with_the_choices():
    with pytest.raises(ConfigError, match="unknown subcommand 'bach'.*did you mean gyrolab batch\\?.*aggregate"):
        split_command(["bach", "initial.r0=1,2"], OPTIONS)


def test_the_options_that_take_a_value_are_read_from_the_parsers():
    # typed here, not read from the parsers under test: each takes the next word as its value
    for option in ("--config-dir", "-cd", "--config-path", "-cp", "--config-name", "-cn", "--cfg", "-c", "--package",
                   "--scheduler", "--animate", "--format", "--frames", "--fps", "-o", "--output", "--points",
                   "--experimental-rerun", "--info"):
        assert option in OPTIONS, option
    assert not {"-m", "--multirun", "--help", "--resolve", "--version", "-V"} & OPTIONS
    assert split_command(["--points", "plot", "reproduce", "sweep.nc"], OPTIONS) == (
        "reproduce", ["--points", "plot", "sweep.nc"])


@pytest.mark.parametrize("argv, command, expected", [
    (["time.end=1", "-m", "--config-dir", "conf", "initial.r0=1,2"], "run",
     {"multirun": True, "config_dir": "conf", "overrides": ["time.end=1", "initial.r0=1,2"], "scheduler": None}),
    (["--scheduler", "local", "experiment=x", "-V"], "run",
     {"scheduler": "local", "version": True, "overrides": ["experiment=x"]}),
    (["reproduce", "sweep.nc", "--points", "0-3"], "reproduce", {"paths": ["sweep.nc"], "points": "0-3"}),
    (["--batch", "a=1,2", "-cd", "conf"], "batch", {"overrides": ["a=1,2"], "config_dir": "conf"}),
])
def test_one_parser_per_subcommand_reads_options_in_any_position(argv, command, expected):
    found, args = parse_command_line(argv)
    assert found == command
    assert {key: getattr(args, key) for key in expected} == expected


def test_a_run_leaves_sys_argv_as_it_was(monkeypatch, tmp_path):
    from gyrolab import app

    argv = ["gyrolab", "--config-dir", str(tmp_path), "time.end=1", "time.n_output=11", "output.figures=false",
            f"hydra.run.dir={tmp_path}/run"]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", list(argv))
    app.main()
    assert sys.argv == argv and (tmp_path / "run" / "run.nc").is_file()


def test_every_old_spelling_names_a_subcommand():
    assert set(ALIASES.values()) <= set(COMMANDS)


#: options each subcommand's --help must list (typed here, not read from the parser under test)
HELP_OPTIONS = {
    "batch": ["--scheduler", "--config-dir", "-cd", "--config-name", "-m", "--multirun", "KEY=VALUE"],
    "plot": ["--animate", "--format", "--frames", "--fps", "--output", "--config-dir", "output.dpi"],
    "reproduce": ["PATH"],
    "aggregate": ["SWEEP_DIR"],
    "new-force": ["NAME"],
    "completion": ["bash", "zsh"],
}


@pytest.mark.parametrize("command", HELP_OPTIONS)
def test_each_subcommands_help_lists_its_options(command, monkeypatch, capsys):
    from gyrolab import app

    monkeypatch.setattr(sys, "argv", ["gyrolab", command, "--help"])
    with pytest.raises(SystemExit) as done:
        app.main()
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: gyrolab {command}")
    for option in [*HELP_OPTIONS[command], "--help"]:
        assert option in out, option
    if command != "completion":
        assert "stderr" in out and "stdout" in out  # the logging convention is stated


def test_every_subcommand_has_a_parser_and_a_runner():
    from gyrolab.app.commands import RUNNERS

    assert set(build_parsers()) == set(RUNNERS) == set(COMMANDS) - {"run"}


def test_gyrolab_help_lists_subcommands_and_hydras_options(cli):
    done = cli("--help")
    assert done.returncode == 0, done.stderr
    for word in [*COMMANDS, "--config-dir", "--multirun", "--cfg", "--info", "--shell-completion", "--version",
                 "integrator: ", "stderr"]:
        assert word in done.stdout, word
    assert cli("run", "--help").stdout == done.stdout


def test_an_unknown_option_of_a_subcommand_is_one_sentence(cli):
    done = cli("batch", "--bogus", "initial.r0=1,2")
    assert done.returncode != 0
    assert done.stderr.strip().splitlines() == [
        "gyrolab: error: unrecognized arguments: --bogus; see gyrolab batch --help"]


# ---- batch: the sweep from the same place as -m, options anywhere ------------------------------------------------

SWEEP_IN_YAML = """# @package _global_
time:
  end: 1
  n_output: 11
output:
  figures: false
hydra:
  sweeper:
    params:
      initial.r0: 1,2,3
"""


@pytest.fixture
def usercfg(tmp_path):
    (tmp_path / "usercfg" / "experiment").mkdir(parents=True)
    (tmp_path / "usercfg" / "experiment" / "r0_scan.yaml").write_text(SWEEP_IN_YAML)
    return tmp_path / "usercfg"


@pytest.mark.parametrize("argv", [
    ["--batch", "--config-dir", "usercfg", "experiment=r0_scan"],         # the command, refused before
    ["batch", "experiment=r0_scan", "hydra.sweep.dir=grid", "-cd", "usercfg"],
])
def test_batch_reads_the_sweep_declared_in_yaml(argv, usercfg, cli, tmp_path):
    if "hydra.sweep.dir=grid" not in argv:
        argv = [*argv, "hydra.sweep.dir=grid"]
    done = cli(*argv)
    assert done.returncode == 0, done.stderr[-2000:]
    with xr.open_dataset(tmp_path / "grid" / "sweep.nc") as ds:
        assert list(ds["r0"].values) == [1.0, 2.0, 3.0]
    assert done.stdout.splitlines() == ["wrote grid/sweep.nc"]            # results on stdout, the log on stderr
    assert "[gyrolab.batch][INFO]" in done.stderr


def test_the_command_line_overrides_the_yaml_sweep_of_the_same_key(usercfg, cli, tmp_path):
    done = cli("batch", "-cd", "usercfg", "experiment=r0_scan", "initial.r0=5,6", "hydra.sweep.dir=grid")
    assert done.returncode == 0, done.stderr[-2000:]
    with xr.open_dataset(tmp_path / "grid" / "sweep.nc") as ds:
        assert list(ds["r0"].values) == [5.0, 6.0]


def test_batch_runs_the_default_integrator(cli, tmp_path):
    """The default config's integrator (dop853 today: no batch kernel) runs, one integrate() per point."""
    done = cli("batch", "initial.r0=1,2", "time.end=1", "time.n_output=11", "hydra.sweep.dir=grid")
    assert done.returncode == 0, done.stderr[-2000:]
    with xr.open_dataset(tmp_path / "grid" / "sweep.nc") as ds:
        assert ds.sizes["r0"] == 2 and int(ds.attrs["n_finished"]) == 2
        integrator = yaml.safe_load(ds.attrs["config"])["integrator"]["_target_"]
    defaults = yaml.safe_load((REPO / "conf" / "config.yaml").read_text())["defaults"]
    default = next(entry["integrator"] for entry in defaults if isinstance(entry, dict) and "integrator" in entry)
    assert integrator == yaml.safe_load((REPO / "conf" / "integrator" / f"{default}.yaml").read_text())["_target_"]


def test_batch_scheduler_option_reaches_the_batch(cli, tmp_path):
    done = cli("batch", "initial.r0=1,2", "--scheduler", "process", "time.end=1", "time.n_output=11",
               "hydra.sweep.dir=grid")
    assert done.returncode == 0, done.stderr[-2000:]
    refused = cli("batch", "initial.r0=1,2", "--scheduler", "nonsense", "hydra.sweep.dir=other")
    assert refused.returncode != 0
    last = refused.stderr.strip().splitlines()[-1]
    assert last.startswith("gyrolab: error: ") and "nonsense" in last and "Traceback" not in refused.stderr
    assert not (tmp_path / "other" / "sweep.nc").exists()


# ---- one logging convention: logs and progress on stderr, results on stdout ---------------------------------------

@pytest.mark.slow
def test_logs_go_to_stderr_and_results_to_stdout(cli, tmp_path):
    run = cli("run", "hydra.run.dir=out", "time.end=1", "time.n_output=11")
    assert run.returncode == 0, run.stderr
    written = run.stdout.splitlines()
    assert written[0] == f"wrote {tmp_path / 'out' / 'run.nc'}"
    assert all(line.startswith("wrote ") for line in written) and len(written) == 5   # run.nc and 4 figures
    assert "[gyrolab.engine.scene][INFO]" in run.stderr and "[INFO]" not in run.stdout

    plot = cli("plot", "out", "output.dpi=40")
    assert plot.returncode == 0, plot.stderr
    assert sorted(plot.stdout.splitlines()) == [f"wrote out/figures/{name}" for name in FIGURES]
    reproduce = cli("reproduce", "out/run.nc")
    assert reproduce.returncode == 0, reproduce.stderr
    assert reproduce.stdout.startswith("reproducing out/run.nc") and "identical" in reproduce.stdout
    assert "[INFO]" not in reproduce.stdout

    sweep = cli("-m", "initial.r0=1,2", "time.end=1", "time.n_output=11", "output.figures=false",
                "hydra.sweep.dir=sweep")
    assert sweep.returncode == 0, sweep.stderr
    assert {f"wrote {tmp_path / 'sweep' / job / 'run.nc'}" for job in "01"} <= set(sweep.stdout.splitlines())
    assert "wrote sweep/sweep.nc" in sweep.stdout.splitlines() or \
        f"wrote {tmp_path / 'sweep' / 'sweep.nc'}" in sweep.stdout.splitlines()
    assert "[INFO]" not in sweep.stdout and "[INFO]" in sweep.stderr
    aggregate = cli("aggregate", "sweep")
    assert aggregate.returncode == 0, aggregate.stderr
    assert aggregate.stdout.splitlines() == ["wrote sweep/sweep.nc"]
    assert "[INFO]" in aggregate.stderr


# ---- one run, one scene -------------------------------------------------------------------------------------------

def test_a_plain_run_builds_one_scene_and_checks_its_config_once(monkeypatch, tmp_path):
    """The preflight's scene is the one the run integrates: one composition's config checked once against the
    schema, one question whether the integrator reads ``accuracy``, one ``Scene``."""
    from gyrolab import app
    from gyrolab.engine.scene import Scene

    calls = {"scene": 0, "check": 0, "accuracy": 0}

    def counting(name, function):
        def counted(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)
        return counted

    built = Scene.from_config.__func__
    monkeypatch.setattr(Scene, "from_config", classmethod(counting("scene", built)))
    monkeypatch.setattr(app, "check_scene_config", counting("check", app.check_scene_config))
    monkeypatch.setattr(app, "ignored_accuracy", counting("accuracy", app.ignored_accuracy))
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", ["gyrolab", "time.end=1", "time.n_output=11", "output.figures=false",
                                      f"hydra.run.dir={tmp_path}/run"])
    app.main()
    assert calls == {"scene": 1, "check": 1, "accuracy": 1}
    with xr.open_dataset(tmp_path / "run" / "run.nc") as ds:
        assert ds.sizes["time"] == 11


def test_the_run_builds_its_own_scene_when_its_config_is_not_the_preflights(monkeypatch):
    from gyrolab import app
    from omegaconf import OmegaConf

    cfg = OmegaConf.create({"time": {"end": 1}})
    app._prepared[:] = [app.Prepared({"time": {"end": 2}}, object(), None)]
    assert app.take_prepared(cfg) is None and not app._prepared
    app._prepared[:] = [app.Prepared({"time": {"end": "${now:%H}"}}, object(), None)]  # may resolve otherwise
    assert app.take_prepared(OmegaConf.create({"time": {"end": "${now:%H}"}})) is None
    prepared = app.Prepared({"time": {"end": 1}}, object(), "note")
    app._prepared[:] = [prepared]
    assert app.take_prepared(cfg) is prepared


@pytest.mark.parametrize("argv", [
    ["-m", "time.end=1", "--config-dir", "conf", "initial.r0=1,2", "--info", "config"],
    ["--cfg", "job", "--resolve", "-p", "time", "-cn", "config", "body.a=2"],
    ["--help", "--scheduler", "local", "-V"],
])
def test_the_command_line_rebuilt_for_hydra_reads_as_the_parsed_one(argv):
    from gyrolab.compat import get_args_parser, hydra_argv

    ours = vars(run_parser().parse_intermixed_args(argv))
    hydras = vars(get_args_parser().parse_args(hydra_argv(argparse.Namespace(**ours))))
    assert hydras == {key: ours[key] for key in hydras} and len(hydras) == len(ours) - 2  # not --version, --scheduler


def test_under_a_hydra_it_was_not_written_for_the_run_is_hydra_mains(monkeypatch, tmp_path):
    # outside Hydra 1.3.x: no composition memo, and hydra.main reads the command line from sys.argv (restored after)
    import hydra

    from gyrolab import app, compat

    argv = ["gyrolab", "time.end=1", "time.n_output=11", "output.figures=false", f"hydra.run.dir={tmp_path}/run"]
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", list(argv))
    monkeypatch.setattr(hydra, "__version__", "1.4.0")
    seen = []
    main = hydra.main

    def watched(*args, **kwargs):
        seen.append((list(sys.argv), compat.active))
        return main(*args, **kwargs)

    monkeypatch.setattr(hydra, "main", watched)
    app.main()
    assert seen == [(["gyrolab", *argv[1:]], None)]
    assert sys.argv == argv
    with xr.open_dataset(tmp_path / "run" / "run.nc") as ds:
        assert ds.sizes["time"] == 11
