"""The ``gyrolab`` command: a Hydra app that runs one scene (or a multirun sweep) per invocation.

Before Hydra starts, a preflight turns the usual mistakes — an unknown plugin
name, a malformed override, an invalid scene, an unwritable output
directory — into one sentence and a non-zero exit, so that no run directory
with a partial ``run.nc`` is left behind.
"""

from __future__ import annotations

import logging
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path

import hydra
from hydra._internal.utils import get_args_parser
from hydra.core.hydra_config import HydraConfig
from hydra import initialize_config_module
from hydra.core.override_parser.overrides_parser import OverridesParser
from hydra.core.override_parser.types import Override
from hydra.errors import OverrideParseException
from omegaconf import DictConfig, open_dict

from pipeline.config import (
    CONFIG_MODULE,
    SELECTABLE_GROUPS,
    compose_config,
    group_options,
    register_plugin_configs,
)
from pipeline.errors import ConfigError, GyrolabError, choices
from pipeline.scene import Scene

log = logging.getLogger("gyrolab")


def fail(error: GyrolabError) -> None:
    print(f"gyrolab: error: {error}", file=sys.stderr)
    sys.exit(error.exit_code)


def preflight(argv: Sequence[str]) -> None:
    """Validate the command line before Hydra creates any output directory."""
    args, _ = get_args_parser().parse_known_args(list(argv))
    if args.help or args.hydra_help or args.info or args.shell_completion or args.cfg:
        return  # Hydra's own informational commands
    parser = OverridesParser.create()
    overrides = []
    for text in args.overrides:
        try:
            overrides.extend(parser.parse_overrides([text]))
        except OverrideParseException as error:
            reason = str(error).strip().splitlines()[0].split(" See https://")[0]
            raise ConfigError(f"malformed override {text!r}: {reason}") from None
    sweeping = args.multirun or any(o.is_sweep_override() for o in overrides)
    check_plugin_names(overrides)
    # One job composed and validated: the first value of every sweep.
    first = [f"{o.get_key_element()}={next(iter(o.sweep_string_iterator()))}" if o.is_sweep_override()
             else o.input_line for o in overrides]
    cfg = compose_config(first, return_hydra_config=True)
    Scene.from_config(_without_hydra(cfg))
    run_dir = cfg.hydra.sweep.dir if sweeping else cfg.hydra.run.dir
    check_writable(Path(str(run_dir)))


def check_plugin_names(overrides: Sequence[Override]) -> None:
    """Every option named for a config group (swept or not, in lists too) must exist."""
    selected = [o for o in overrides if o.key_or_group in SELECTABLE_GROUPS and o.package is None
                and not o.is_delete()]
    if not selected:
        return
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        for o in selected:
            valid = group_options(o.key_or_group)
            values = list(o.sweep_string_iterator()) if o.is_sweep_override() else [o.value()]
            for value in values:
                items = value if isinstance(value, list) else str(value).strip("[]").split(",")
                for name in (str(item).strip() for item in items):
                    if name and name != "null" and name not in valid:
                        raise ConfigError(f"unknown {o.key_or_group} {name!r}; valid choices: {choices(valid)}")


def _without_hydra(cfg: DictConfig) -> DictConfig:
    cfg = cfg.copy()
    with open_dict(cfg):
        cfg.pop("hydra", None)
    return cfg


def check_writable(directory: Path) -> None:
    """ConfigError unless ``directory`` exists or can be created, and accepts new files."""
    existing = directory
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    try:
        if not existing.is_dir():
            raise NotADirectoryError(20, "a path component is a file, not a directory")
        probe = tempfile.mkdtemp(prefix=".gyrolab-write-check-", dir=existing)
        Path(probe).rmdir()
    except OSError as error:
        raise ConfigError(f"output directory {str(directory)!r} is not writable ({error.strerror or error}); "
                          "choose a writable hydra.run.dir (or hydra.sweep.dir)") from None


@hydra.main(config_path="pkg://conf", config_name="config", version_base="1.3")
def _task(cfg: DictConfig) -> None:
    from pipeline.dataset import write_dataset
    from pipeline.figures import save_figures  # matplotlib only when figures are drawn

    try:
        out_dir = Path(HydraConfig.get().runtime.output_dir)
        scene = Scene.from_config(cfg)
        ds = scene.run()
        ds.attrs["hydra_overrides"] = " ".join(HydraConfig.get().overrides.task)
        path = write_dataset(ds, out_dir / "run.nc")
        log.info("wrote %s", path)
        if cfg.output.get("figures", True):
            for figure in save_figures(ds, out_dir / "figures"):
                log.info("wrote %s", figure)
    except GyrolabError as error:
        fail(error)


def main() -> None:
    """Console entry point ``gyrolab`` (also ``python -m pipeline``)."""
    try:
        register_plugin_configs()
        preflight(sys.argv[1:])
    except GyrolabError as error:
        fail(error)
    _task()
