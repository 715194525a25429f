"""A force field from outside the source tree, found through its package's entry point."""

import textwrap

import numpy as np
import pytest

from gyrolab.engine import config, registry
from gyrolab import run

PLUGIN = textwrap.dedent('''
    """Linear viscous drag on the body: torque −c ω (a third-party plugin)."""
    from gyrolab.contracts import Force


    class ViscousDrag(Force):
        name = "viscous_drag"
        required_axes = frozenset()

        def __init__(self, body, *, coefficient=0.1):
            self.coefficient = float(coefficient)

        def torque(self, omega, axes):
            return -self.coefficient * omega
''')


@pytest.fixture
def installed_plugin(tmp_path, monkeypatch):
    """Install a distribution the way pip lays it out: a package plus its .dist-info with entry points."""
    site = tmp_path / "site"
    (site / "gyrolab_drag").mkdir(parents=True)
    (site / "gyrolab_drag" / "__init__.py").write_text(PLUGIN)
    info = site / "gyrolab_drag-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: gyrolab-drag\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text("[gyrolab.forces]\nviscous_drag = gyrolab_drag:ViscousDrag\n")
    monkeypatch.syspath_prepend(str(site))
    registry.external.cache_clear()
    config.register_plugin_configs.cache_clear()
    yield site
    registry.external.cache_clear()
    config.register_plugin_configs.cache_clear()


def test_external_force_runs_through_the_python_api(installed_plugin):
    assert "viscous_drag" in registry.names("force")
    # A spherical body (A = B = C) with drag only: ω(t) = ω0 exp(−c t) exactly.
    ds = run(["force=[viscous_drag]", "force.viscous_drag.coefficient=0.3", "body.a=1", "body.b=1",
              "integrator.rtol=1e-12", "integrator.atol=1e-12", "time.end=5", "time.n_output=51"])
    expected = np.array([0.1, -0.05, 5.0]) * np.exp(-0.3 * ds.time.values)[:, None]
    np.testing.assert_allclose(ds.omega.values, expected, rtol=1e-9, atol=1e-12)
    assert "energy" not in ds.attrs["monitored_invariants"].split()  # drag has no potential


def test_external_force_runs_from_the_command_line(installed_plugin, cli):
    done = cli("force=[uniform_gravity,viscous_drag]", "force.viscous_drag.coefficient=0.2", "time.end=1",
               "time.n_output=11", "output.figures=false", "hydra.run.dir=out",
               env_extra={"PYTHONPATH": str(installed_plugin)})
    assert done.returncode == 0, done.stderr
    import xarray as xr

    with xr.open_dataset(installed_plugin.parent / "out" / "run.nc") as ds:
        assert "viscous_drag" in ds.attrs["title"]
