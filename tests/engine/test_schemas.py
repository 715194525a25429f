"""The config's schemas (gyrolab.engine.schemas) and the tables derived from them and from the tasks' declarations."""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
import subprocess
import sys
import typing
from importlib.resources import files
from pathlib import Path

import pytest
from omegaconf import OmegaConf

import gyrolab.experiments as experiments
from gyrolab.contracts import registry
from gyrolab.engine import budget, schemas, unread
from gyrolab.engine.config import check_scene_config, compose_config
from gyrolab.errors import ConfigError


@pytest.mark.parametrize("group, name", [(g, n) for g, names in registry.BUILTINS.items() for n in names])
def test_a_builtin_schema_has_the_keys_and_defaults_of_its_plugin(group, name):
    cls = registry.load(group, name)
    schema = {f.name: f for f in dataclasses.fields(schemas.BUILTIN[group][cls.__name__])}
    params = registry.default_params(cls)
    assert set(schema) == {"_target_", *params}, (group, name)
    for key, default in params.items():
        field = schema[key]
        value = field.default_factory() if field.default_factory is not dataclasses.MISSING else field.default
        assert value == (list(default) if isinstance(default, tuple) else default), (group, name, key)


def _hydra_composes(overrides):
    """The config as Hydra composes it (compose_config hands on a plain copy)."""
    from hydra.core.global_hydra import GlobalHydra
    from hydra.types import RunMode

    from gyrolab.engine.config import hydra_for

    with hydra_for():
        return GlobalHydra.instance().hydra.compose_config(config_name="config", overrides=overrides,
                                                           run_mode=RunMode.RUN)


# initial's options name no schema: a batch sweeps initial.r0=abc,5 and reports the bad point in its own sentence
# (tests/batch/test_sweep.py); validate types them after composing
@pytest.mark.parametrize("group", ["system", "body", "force", "integrator", "regime"])
def test_every_packaged_option_extends_a_schema(group):
    for option in sorted(p.name[:-5] for p in (files("gyrolab.conf") / group).iterdir() if p.name.endswith(".yaml")):
        cfg = _hydra_composes([f"{group}=[{option}]" if group == "force" else f"{group}={option}"])
        nodes = cfg.force.values() if group == "force" else [cfg[group]]
        for node in nodes:
            assert dataclasses.is_dataclass(OmegaConf.get_type(node)), (group, option)
    assert OmegaConf.get_type(_hydra_composes([])).__name__ == "GyrolabWhileComposing"


@pytest.mark.parametrize("overrides, sentence", [
    (["output.error_estimate=maybe"], "output.error_estimate='maybe' must be true, false or null"),
    (["output.dpi=high"], "output.dpi='high' must be an integer"),
    (["batch.zip=sometimes"], "batch.zip='sometimes' must be true or false"),
    (["experiment=stability_map", "stability_map.n_r0=many"], "stability_map.n_r0='many' must be an integer"),
    (["experiment=yehia2021_precessions", "yehia2021.orbits=[1]"], "yehia2021.orbits=[1] must be a number"),
    (["integrator=rk4", "integrator.step=fast"], "integrator.step='fast' must be a number"),
    (["regime=small_parameter", "regime.periods=1.5"], "regime.periods=1.5 must be an integer"),
    (["force.newtonian.k=strong"], "force.newtonian.k='strong' must be a number or null"),
    (["integrator=rk4", "integrator.rtol=1e-3"], "`integrator.rtol` is not a key of `integrator`"),
    (["experiment=gyrostat", "+body.a=2"], "`body.a` is not a key of `body`"),
])
def test_a_schema_refusal_is_one_sentence_naming_key_value_and_what_is_expected(overrides, sentence):
    with pytest.raises(ConfigError) as error:
        check_scene_config(compose_config(overrides))
    assert sentence in str(error.value) and "\n" not in str(error.value)


def test_a_config_that_names_no_schema_is_checked_against_them():
    """A user's primary config (or a dataset's stored config) is a plain mapping: the schemas apply all the same."""
    plain = OmegaConf.to_container(compose_config([]), resolve=False)
    check_scene_config(OmegaConf.create(plain))
    for key, value, sentence in (("output.error_estimate", "maybe", "must be true, false or null"),
                                 ("integrator.atoll", 1e-9, "did you mean `integrator.atol`?"),
                                 ("body.mass_kg", 1.0, "`body.mass_kg` is not a key of `body`")):
        cfg = OmegaConf.create(plain)
        OmegaConf.update(cfg, key, value, force_add=True)
        with pytest.raises(ConfigError, match=sentence.replace("?", r"\?")):
            check_scene_config(cfg)
    cfg = OmegaConf.create({k: v for k, v in plain.items() if k != "initial"})
    with pytest.raises(ConfigError, match="no `initial` section"):
        check_scene_config(cfg)


def test_a_bad_value_on_the_command_line_exits_non_zero_in_one_sentence_and_writes_nothing(tmp_path):
    gyrolab = Path(sys.executable).with_name("gyrolab")
    done = subprocess.run([str(gyrolab), "output.error_estimate=maybe", "hydra.run.dir=out"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode != 0
    assert done.stderr.strip().splitlines() == [
        "gyrolab: error: output.error_estimate='maybe' must be true, false or null"]
    assert not (tmp_path / "out").exists() and done.stdout == ""


def test_a_plugins_schema_is_its_declared_dataclass_or_made_from_its_signature():
    @dataclasses.dataclass
    class DragConfig:
        _target_: str = "x:Drag"
        coefficient: float = 0.1

    class Declared:
        schema = DragConfig

        def __init__(self, body, *, coefficient: float = 0.1) -> None: ...

    class Derived:
        def __init__(self, body, *, coefficient: float = 0.1, axis: typing.Sequence[float] = (0, 0, 1)) -> None: ...

    assert schemas.plugin_schema(Declared) is DragConfig
    node = OmegaConf.structured(schemas.plugin_schema(Derived))
    assert set(node) == {"_target_", "coefficient", "axis"}
    with pytest.raises(Exception, match="could not be converted"):
        OmegaConf.merge(node, {"coefficient": "abc"})
    OmegaConf.merge(node, {"axis": [1, 0, 0]})  # an annotation OmegaConf cannot check: any value


def test_the_scaffold_declares_a_schema():
    from gyrolab.scaffold import render

    text = render("my_drag")["gyrolab_my_drag/__init__.py"]
    assert "class MyDragConfig:" in text and "schema = MyDragConfig" in text
    namespace: dict = {}
    schema = text[text.index("@dataclass"):text.index("class MyDrag(Force)")]
    exec(compile("from dataclasses import dataclass\n" + schema, "scaffold", "exec"), namespace)  # the dataclass
    assert OmegaConf.structured(namespace["MyDragConfig"]).coefficient == 0.1


# ---- tasks' declarations and the tables derived from them -------------------------------------------------------

def _experiment_modules() -> list[str]:
    return [m.name for m in pkgutil.iter_modules(experiments.__path__)]


def test_every_experiment_declares_its_task_and_the_index_is_derived_from_the_declarations():
    declared = {}
    for name in _experiment_modules():
        module = importlib.import_module(f"gyrolab.experiments.{name}")
        task = getattr(module, "TASK", None)
        assert isinstance(task, schemas.Task), f"gyrolab.experiments.{name} has no TASK declaration"
        assert callable(module.run)
        declared[task.name] = module.__name__
    assert experiments.TASKS == declared
    for option in (files("gyrolab.conf") / "experiment").iterdir():
        task = OmegaConf.load(str(option)).get("task") if option.name.endswith(".yaml") else None
        assert task is None or task in experiments.TASKS, option.name


def test_a_declaration_names_real_keys_and_its_settings_schema():
    top = {f.name: f for f in dataclasses.fields(schemas.Gyrolab)}
    hints = typing.get_type_hints(schemas.Gyrolab)
    for name in experiments.TASKS:
        task = experiments.declaration(f"task {name}")
        for key in task.reads:
            assert key in schemas.only_declared_keys(), (name, key)
        for key in task.sets:
            assert key.split(".")[0] in top, (name, key)
        if task.section is not None:
            assert task.section in top, (name, task.section)
            if task.settings is not None:
                assert task.settings in typing.get_args(hints[task.section]), (name, task.section)
    for key, readers in experiments.read_by().items():
        assert readers, f"{key} is read only by declaring runs, and no run declares it"


def test_the_tables_follow_the_declarations(monkeypatch):
    """A new task's declaration is enough: the unread-key refusal reads it (no table to edit)."""
    fake = schemas.Task("fake", reads=("batch",), sets={"time.end": "it sets its own span"})
    monkeypatch.setattr(experiments, "TASKS", {**experiments.TASKS, "fake": "fake_module"})
    monkeypatch.setitem(sys.modules, "fake_module", type(sys)("fake_module"))
    sys.modules["fake_module"].TASK = fake
    experiments.read_by.cache_clear()
    try:
        assert "task fake" in experiments.read_by()["batch"]
        experiments.refuse_unread("task fake", ["batch.output=final"])
        with pytest.raises(ConfigError, match=r"time.end=5 is not read by task fake \(it sets its own span\)"):
            experiments.refuse_unread("task fake", ["time.end=5"])
        with pytest.raises(ConfigError, match="read only by task stability_map, task fake or gyrolab batch"):
            experiments.refuse_unread("task scene", ["batch.output=final"])
    finally:
        experiments.read_by.cache_clear()


def test_the_hand_kept_tables_are_gone():
    from gyrolab.app import REQUIRED_SECTIONS
    from gyrolab.app import completion

    assert budget.TOLERANCES == schemas.keys_with("tolerance") and "rtol" in budget.TOLERANCES
    assert unread.OWN_SETTINGS == schemas.keys_with("own") and "step" in unread.OWN_SETTINGS
    assert REQUIRED_SECTIONS is schemas.REQUIRED_SECTIONS and REQUIRED_SECTIONS["time"] == "end"
    assert not hasattr(unread, "_PROBES")
    for name in ("READ_BY", "NOT_READ_BY"):
        assert not hasattr(experiments, name)
    for name in ("RUN_OPTIONS", "HYDRA_KEYS"):
        assert not hasattr(completion, name)
    from gyrolab.app import parser

    assert not hasattr(parser, "VALUE_OPTIONS")  # read from the parsers (parser.value_options)
    assert {"--multirun", "--config-dir", "--batch", "-V"} <= set(completion.run_options())
    assert "hydra.run.dir" in completion.hydra_keys()


@pytest.mark.parametrize("overrides, reads", [
    (["integrator=auto"], True),
    (["integrator=auto", "integrator.accuracy=1e-6"], False),
    (["integrator=taylor", "integrator.tol=${..accuracy}", "accuracy=1e-9"], True),
    (["integrator=taylor", "integrator.tol=${time.end}", "time.end=${accuracy}", "accuracy=1e-9"], True),
    (["integrator=taylor", "integrator.tol=${time.end}"], False),
    (["integrator=taylor", "integrator.tol=${oc.select:accuracy,1e-9}"], True),
])
def test_whether_the_integrator_reads_accuracy_is_read_off_its_references(overrides, reads):
    assert unread.reads_accuracy(compose_config(overrides, refuse_unread=False)) is reads
