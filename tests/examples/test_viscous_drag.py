"""A force field from outside the source tree: the example package examples/gyrolab-viscous-drag.

It is installed the way pip lays a distribution out (its package on the path, a .dist-info with
its entry points), found through the entry point, run from the API and the command line; the
The plugin page's (docs/writing-a-force.md) example is its literal content; ``gyrolab --new-force`` reproduces it; its own
tests (gyrolab's contract kit and the exact solution of drag) run here.
"""

import re
import tomllib

import pytest

from gyrolab.engine.scene import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.scaffold import new_force_package, render
from tests.conftest import installed_distribution
from tests.helpers import REPO, VISCOUS_DRAG, example_tests



@pytest.fixture(scope="module")
def installed_plugin(tmp_path_factory):
    """The example's package on the path, plus a .dist-info carrying its pyproject's entry points."""
    project = tomllib.loads((VISCOUS_DRAG / "pyproject.toml").read_text())["project"]
    with installed_distribution(tmp_path_factory.mktemp("site"), project["name"], project["version"],
                                project["entry-points"]["gyrolab.forces"], [VISCOUS_DRAG]) as site:
        yield site


def test_plugin_page_is_the_example_package():
    readme = (REPO / "docs" / "writing-a-force.md").read_text()
    section = readme[readme.index("## Adding a force plugin"):]
    blocks = re.findall(r"`examples/gyrolab-viscous-drag/([^`]+)`:\n\n```\w+\n(.*?)```\n", section, re.S)
    assert {path for path, _ in blocks} >= {"gyrolab_viscous_drag/__init__.py", "pyproject.toml",
                                           "tests/test_viscous_drag.py"}
    for path, text in blocks:
        assert text == (VISCOUS_DRAG / path).read_text(), f"README's block for {path} differs from the example's file"


def test_new_force_scaffold_reproduces_the_example(tmp_path):
    assert render("viscous_drag") == {p.relative_to(VISCOUS_DRAG).as_posix(): p.read_text()
                                      for p in VISCOUS_DRAG.rglob("*") if p.is_file() and "__pycache__" not in p.parts}
    root = new_force_package("tidal_lock", tmp_path)
    assert (root / "gyrolab_tidal_lock" / "__init__.py").read_text().count("class TidalLock(Force):") == 1
    assert 'tidal_lock = "gyrolab_tidal_lock:TidalLock"' in (root / "pyproject.toml").read_text()
    with pytest.raises(ConfigError, match="already exists"):
        new_force_package("tidal_lock", tmp_path)
    with pytest.raises(ConfigError, match="lower-case letters"):
        new_force_package("Tidal-Lock", tmp_path)


def test_example_package_passes_its_own_tests(installed_plugin):
    tests = example_tests("gyrolab-viscous-drag", "test_viscous_drag.py")
    tests.test_contract()  # gyrolab.testing.check_force
    tests.test_bad_coefficient_is_one_sentence()
    for integrator in ("dop853", "dop853_numba"):  # exact solution ω0 exp(−c t), Python and compiled
        tests.test_spherical_body_decays_exponentially(integrator)


def test_bad_parameter_is_one_config_error(installed_plugin):
    with pytest.raises(ConfigError, match=r"^force\.viscous_drag\.coefficient="):
        compose_scene(["force=[viscous_drag]", "force.viscous_drag.coefficient=abc"])


def test_external_force_runs_from_the_command_line(installed_plugin, cli, tmp_path):
    done = cli("force=[uniform_gravity,viscous_drag]", "force.viscous_drag.coefficient=0.2", "time.end=1",
               "time.n_output=11", "output.figures=false", "hydra.run.dir=out",
               env_extra={"PYTHONPATH": f"{installed_plugin}:{VISCOUS_DRAG}"})
    assert done.returncode == 0, done.stderr
    import xarray as xr

    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        assert "viscous_drag" in ds.attrs["title"]
        assert ds.attrs["force_viscous_drag_coefficient"] == 0.2
        assert "area_integral" not in ds.attrs["monitored_invariants"].split()  # declared False: drag breaks it
