"""The package installs under the one import name ``gyrolab`` (and its Hydra sweeper under ``hydra_plugins``) and
says its own version."""

import shutil
import subprocess
import sys
import tomllib
import zipfile
from importlib import metadata
from pathlib import Path

import pytest

from gyrolab.errors import ConfigError
from tests.helpers import REPO

PYPROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]


def _import_name(folder: Path) -> str:
    """The import name a source folder installs under, from pyproject's package-dir."""
    relative = folder.relative_to(REPO).as_posix()
    best = max((src for src in SETUPTOOLS["package-dir"].values() if relative == src or relative.startswith(src + "/")),
               key=len)
    name = next(k for k, v in SETUPTOOLS["package-dir"].items() if v == best)
    rest = relative[len(best):].strip("/")
    return ".".join([name, *rest.split("/")]) if rest else name


def test_every_source_package_is_installed_under_gyrolab():
    # hydra_plugins/ is the one top-level folder beside the client's: Hydra finds sweepers and launchers only in
    # the hydra_plugins namespace package (docs/layout.md), which therefore has no __init__.py of its own
    folders = [init.parent for top in ("pipeline", "plugins", "conf", "hydra_plugins")
               for init in (REPO / top).rglob("__init__.py") if "__pycache__" not in init.parts]
    expected = sorted(_import_name(folder) for folder in folders)
    assert sorted(SETUPTOOLS["packages"]) == expected
    assert all(name == "gyrolab" or name.startswith(("gyrolab.", "hydra_plugins.")) for name in expected)
    assert not (REPO / "hydra_plugins" / "__init__.py").exists()  # a namespace package, shared with Hydra's plugins


def test_the_sweeper_is_a_hydra_plugin_by_its_configured_name():
    from hydra.core.plugins import Plugins
    from hydra.plugins.sweeper import Sweeper
    from omegaconf import OmegaConf

    from gyrolab.sweep.sweeper import ResumingSweeper, register_plugin

    target = OmegaConf.load(REPO / "conf" / "hydra" / "sweeper" / "gyrolab.yaml")._target_
    register_plugin()
    register_plugin()  # idempotent
    found = {f"{c.__module__}.{c.__name__}": c for c in Plugins.instance().discover(Sweeper)}
    assert target == "hydra_plugins.gyrolab_sweeper.GyrolabSweeper"
    assert isinstance(found[target](max_batch_size=3).sweeper, ResumingSweeper)
    assert "gyrolab.sweep.sweeper.ResumingSweeper" not in found  # only the class Hydra is given by name
    module = sys.modules[found[target].__module__]
    assert Path(module.__file__).parent.name == "gyrolab_sweeper"  # a real module, not a stand-in


def test_the_sweeper_plugin_imports_no_gyrolab_until_it_is_used():
    # Hydra imports every hydra_plugins module whenever any Hydra app starts: an unrelated app must not pay for gyrolab
    code = "import sys, hydra_plugins.gyrolab_sweeper; print(sorted(m for m in sys.modules if m.startswith('gyrolab')))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=REPO.parent)
    assert done.returncode == 0 and done.stdout.strip() == "[]", done.stderr[-2000:]


def test_version_flag_prints_gyrolab_version():
    done = subprocess.run([sys.executable, "-m", "gyrolab", "--version"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0
    assert done.stdout.strip() == f"gyrolab {metadata.version('gyrolab')}"


def test_a_launcher_of_the_cluster_extra_missing_is_one_sentence(monkeypatch):
    from hydra.core.override_parser.overrides_parser import OverridesParser

    from gyrolab import app

    overrides = OverridesParser.create().parse_overrides(["hydra/launcher=joblib"])
    # the launcher's module missing, and its parent package missing too (find_spec raises then)
    for module in ("hydra_plugins.not_installed_launcher", "not_installed_namespace.launcher"):
        monkeypatch.setitem(app.EXTRA_LAUNCHERS, "joblib", module)
        with pytest.raises(ConfigError, match=r'pip install "gyrolab\[cluster\]"') as refused:
            app.check_launcher_installed(overrides)
        assert "\n" not in str(refused.value)


@pytest.mark.slow
def test_wheel_installs_only_gyrolab(tmp_path):
    source = tmp_path / "source"  # a copy, so that the build leaves nothing in the checkout
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(".git", "outputs", "build", "__pycache__", "*.egg-info"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(tmp_path), str(source)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    (wheel,) = tmp_path.glob("gyrolab-*.whl")
    with zipfile.ZipFile(wheel) as archive:
        tops = {name.split("/")[0] for name in archive.namelist()}
        names = archive.namelist()
    assert {top for top in tops if not top.endswith(".dist-info")} == {"gyrolab", "hydra_plugins"}
    assert "gyrolab/conf/config.yaml" in names and "gyrolab/plugins/forces/newtonian.py" in names
    assert "gyrolab/app/completion.bash" in names  # the shell function of gyrolab completion
    assert "hydra_plugins/gyrolab_sweeper/__init__.py" in names and "hydra_plugins/__init__.py" not in names
