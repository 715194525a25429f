"""One composition per command (gyrolab.compat.composing_once) gives every job the config Hydra composes for it.

The reference is Hydra's own ``ConfigLoaderImpl`` outside ``composing_once``: the master config of a
multirun, then each job's config as Hydra's basic launcher builds it (``load_sweep_config``, then
``hydra.job.id`` and ``num``), compared key by key, unresolved (as ``.hydra/*.yaml`` store them) and
resolved (the job's directory, ``override_dirname``), with the struct and read-only flags. The
configs cover value and group sweeps, additions, deletions, a mapping given for a group, Hydra
settings, a user's config directory, a missing default (``???``) chosen by the sweep, and a job whose
override Hydra refuses (the same error).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hydra.core.global_hydra import GlobalHydra
from hydra.core.hydra_config import HydraConfig
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.errors import ConfigCompositionException
from hydra.types import RunMode
from omegaconf import OmegaConf, open_dict

from gyrolab import compat as composition
from gyrolab.engine.config import ConfigSource, hydra_for, register_plugin_configs
from gyrolab.compat import BasicSweeper, ConfigLoaderImpl
from tests.helpers import gyrolab_in_process


def jobs_of(arguments):
    parsed = OverridesParser.create().parse_overrides(arguments)
    return [list(job) for batch in BasicSweeper.split_arguments(parsed, None) for job in batch]


def launch_configs(config_name, arguments):
    """(the master config, every job's config) as Hydra's multirun and basic launcher compose them."""
    loader = GlobalHydra.instance().config_loader()
    master = loader.load_configuration(config_name=config_name, overrides=list(arguments),
                                       run_mode=RunMode.MULTIRUN)
    task = OmegaConf.to_container(master.hydra.overrides.task, resolve=False)
    configs = []
    for num, job in enumerate(jobs_of(task)):
        cfg = loader.load_sweep_config(master, job)
        with open_dict(cfg):  # as Hydra's basic launcher
            cfg.hydra.job.id = num
            cfg.hydra.job.num = num
        configs.append(cfg)
    return master, configs


def described(cfg, job_dir=True):
    """Everything a job sees of its config: stored form, resolved values, directory, flags."""
    HydraConfig.instance().set_config(cfg)
    job = OmegaConf.masked_copy(cfg, [k for k in cfg if k != "hydra"])
    seen = {
        "stored": OmegaConf.to_yaml(cfg),
        "resolved job": OmegaConf.to_container(job, resolve=True),
        "override_dirname": cfg.hydra.job.override_dirname,
        "num id": (OmegaConf.select(cfg, "hydra.job.num"), OmegaConf.select(cfg, "hydra.job.id")),
        "task overrides": list(cfg.hydra.overrides.task),
        "choices": OmegaConf.to_container(cfg.hydra.runtime.choices),
        "flags": (OmegaConf.is_struct(cfg), OmegaConf.is_readonly(cfg), OmegaConf.is_readonly(cfg.hydra),
                  OmegaConf.is_struct(cfg.hydra)),
    }
    if job_dir:  # where Hydra's run_job puts the job (the master has no job number)
        seen["job dir"] = f"{OmegaConf.select(cfg, 'hydra.sweep.dir')}/{OmegaConf.select(cfg, 'hydra.sweep.subdir')}"
    return seen


def both_ways(source, arguments):
    register_plugin_configs()
    with hydra_for(source):
        reference = launch_configs(source.config_name, arguments)
        assert ConfigLoaderImpl._load_configuration_impl is composition._ORIGINAL
        with composition.composing_once() as memo:
            served = launch_configs(source.config_name, arguments)
            served_twice = launch_configs(source.config_name, arguments)   # from the memo only
    assert memo.requests == 2 * (1 + len(reference[1]))
    return reference, served, served_twice, memo


def assert_same(source, arguments):
    (master, jobs), (master2, jobs2), (master3, jobs3), memo = both_ways(source, arguments)
    assert described(master2, False) == described(master, False) == described(master3, False)
    assert len(jobs2) == len(jobs) == len(jobs3) > 1
    for num, (a, b, c) in enumerate(zip(jobs, jobs2, jobs3)):
        assert described(b) == described(a), f"job {num}"
        assert described(c) == described(a), f"job {num}"
    return memo


PACKAGED = ConfigSource()


@pytest.mark.parametrize("arguments, skeletons", [
    # a value sweep: one composition serves the master and every job
    (["time.end=1", "initial.r0=1,2,3", "hydra.sweep.dir=/tmp/sweep"], 1),
    # Hydra settings, a sweep dir per override_dirname with a key excluded, an environment copy
    (["initial.r0=1,2", "body.a=1.5,1.2", "hydra.sweep.dir=/tmp/s/${hydra.job.name}",
      "hydra.sweep.subdir=${hydra.job.override_dirname}", "hydra.job.config.override_dirname.exclude_keys=[body.a]",
      "hydra.job.env_copy=[HOME]"], 1),
    # a group sweep: one skeleton per choice and one for the master (which ignores the sweep)
    (["integrator=rk4,dop853", "time.end=2", "hydra.sweep.dir=/tmp/sweep"], 3),
    # a list group, an added key, a deleted key, a mapping for a group (merged, a value override)
    (["force=[uniform_gravity],[uniform_gravity,newtonian]", "+time.extra=1,2", "~output.dpi",
      "initial={r0: 3.0}", "hydra.sweep.dir=/tmp/sweep"], 3),
    # an experiment and a launcher
    (["experiment=perf_reference", "hydra/launcher=basic", "time.end=1,2", "hydra.sweep.dir=/tmp/sweep"], 1),
])
def test_every_job_gets_the_config_hydra_composes(arguments, skeletons):
    memo = assert_same(PACKAGED, arguments)
    assert memo.compositions == skeletons


def test_a_user_config_dir_an_added_group_and_a_missing_default_chosen_by_the_sweep(tmp_path):
    (tmp_path / "mine.yaml").write_text(
        "defaults:\n  - config\n  - override integrator: ???\n  - _self_\ntime:\n  end: 3.0\n")
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "lab.yaml").write_text("who: me\n")
    (tmp_path / "body").mkdir()
    (tmp_path / "body" / "tiny.yaml").write_text("a: 1.1\nb: 1.2\nc: 1.0\nunits: nondimensional\n"
                                                   "com_direction: [0, 0, 1]\n")
    source = ConfigSource.from_args(None, "mine", str(tmp_path))
    # the master skips the missing integrator (a multirun composition); the jobs, run compositions, may not
    memo = assert_same(source, ["integrator=rk4,dop853", "body=tiny", "initial.r0=1,2", "+notes=lab",
                                "hydra.sweep.dir=/tmp/s"])
    assert memo.compositions == 3


def test_a_job_hydra_refuses_fails_the_same_way():
    register_plugin_configs()
    errors = []
    with hydra_for(PACKAGED):
        loader = GlobalHydra.instance().config_loader()
        master = loader.load_configuration(config_name="config", overrides=["time.end=1"], run_mode=RunMode.MULTIRUN)
        for memo in (None, composition.composing_once()):
            if memo is not None:
                memo.__enter__()
            try:
                with pytest.raises(ConfigCompositionException) as error:
                    loader.load_sweep_config(master, ["time.ennd=2"])
                errors.append((str(error.value), str(error.value.__cause__)))
            finally:
                if memo is not None:
                    memo.__exit__(None, None, None)
    assert errors[0] == errors[1]


def counted_compositions(monkeypatch):
    calls = []
    compose = ConfigLoaderImpl._compose_config_from_defaults_list

    def counting(self, *args, **kwargs):
        calls.append(1)
        return compose(self, *args, **kwargs)

    monkeypatch.setattr(ConfigLoaderImpl, "_compose_config_from_defaults_list", counting)
    return calls


def test_a_run_composes_its_config_once(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    calls = counted_compositions(monkeypatch)
    code = gyrolab_in_process(monkeypatch, "time.end=1", "time.n_output=11", "output.figures=false",
                              f"hydra.run.dir={tmp_path / 'run'}")
    assert code in (0, None)
    assert (tmp_path / "run" / "run.nc").is_file()
    assert len(calls) == 1   # the preflight's; Hydra's get_mode and run are served from it
    stored = OmegaConf.load(tmp_path / "run" / ".hydra" / "hydra.yaml")
    assert stored.hydra.runtime.cwd == os.getcwd() and list(stored.hydra.overrides.task) == [
        "time.end=1", "time.n_output=11", "output.figures=false"]


def test_a_value_sweep_composes_once(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    calls = counted_compositions(monkeypatch)
    sweep = tmp_path / "sweep"
    code = gyrolab_in_process(monkeypatch, "-m", "time.end=1", "time.n_output=11", "initial.r0=1,2,3",
                              "output.figures=false", f"hydra.sweep.dir={sweep}")
    assert code in (0, None)
    assert len(calls) == 1
    for num, r0 in enumerate((1, 2, 3)):
        job = OmegaConf.load(sweep / str(num) / ".hydra" / "hydra.yaml").hydra
        assert (job.job.num, str(job.job.id)) == (num, str(num))
        # (Hydra's sweeper spells the job's values as Python does: False)
        assert job.job.override_dirname == f"initial.r0={r0},output.figures=False,time.end=1,time.n_output=11"
        assert OmegaConf.load(sweep / str(num) / ".hydra" / "config.yaml").initial.r0 == r0
    assert Path(sweep / "sweep.nc").is_file()


def test_the_sweep_figures_take_the_sweeps_formats_from_its_config(tmp_path, monkeypatch):
    # the callback hands the sweep's output section to the figures (multirun.yaml is not read again)
    monkeypatch.chdir(tmp_path)
    sweep = tmp_path / "sweep"
    code = gyrolab_in_process(monkeypatch, "-m", "time.end=1", "time.n_output=11", "initial.r0=1,2",
                              "output.figure_formats=[svg]", "output.dpi=50", f"hydra.sweep.dir={sweep}")
    assert code in (0, None)
    drawn = sorted(p.name for p in (sweep / "figures").iterdir())
    assert drawn and all(name.endswith(".svg") for name in drawn), drawn
    assert OmegaConf.load(sweep / "multirun.yaml").output.figure_formats == ["svg"]


def test_a_first_composition_that_hydra_splits_otherwise_is_hydras(monkeypatch):
    # a Hydra whose defaults list takes another override as a value than the memo's rule: that request is
    # composed by Hydra itself, and no skeleton is kept from it
    register_plugin_configs()
    overrides = ["integrator=rk4", "time.end=1", "hydra.run.dir=/tmp/run"]
    with hydra_for(PACKAGED):
        loader = GlobalHydra.instance().config_loader()
        reference = loader.load_configuration(config_name="config", overrides=overrides, run_mode=RunMode.RUN)
        monkeypatch.setattr(composition, "_classify",
                            lambda parsed, repo: ((), [o for o in parsed if not o.is_sweep_override()]))
        with composition.composing_once() as memo:
            served = loader.load_configuration(config_name="config", overrides=overrides, run_mode=RunMode.RUN)
    assert memo.compositions == 0 and not memo.skeletons
    assert OmegaConf.to_yaml(served) == OmegaConf.to_yaml(reference)
    assert served.hydra.runtime.choices.integrator == "rk4"


@pytest.mark.parametrize("version, served", [("1.3.0", True), ("1.3.8", True), ("1.2.0", False), ("1.4.0", False),
                                             ("2.0.0.dev1", False)])
def test_only_the_hydra_it_was_written_for_is_served_from_the_memo(monkeypatch, version, served):
    # a Hydra outside 1.3.x: nothing is replaced, every composition is Hydra's own, and the configs are the same
    import hydra

    arguments = ["time.end=1", "initial.r0=1,2", "hydra.sweep.dir=/tmp/sweep"]
    register_plugin_configs()
    with hydra_for(PACKAGED):
        reference = launch_configs("config", arguments)
        monkeypatch.setattr(hydra, "__version__", version)
        with composition.composing_once() as memo:
            monkeypatch.undo()  # the version is checked on entry; the configs record the real one
            replaced = ConfigLoaderImpl._load_configuration_impl is not composition._ORIGINAL
            configs = launch_configs("config", arguments)
    assert replaced is served and (memo.requests > 0) is served
    assert ConfigLoaderImpl._load_configuration_impl is composition._ORIGINAL
    assert described(configs[0], False) == described(reference[0], False)
    assert [described(c) for c in configs[1]] == [described(c) for c in reference[1]]
