"""Every option of every config group composes and builds; the registry refuses foreign targets."""


import pytest

from gyrolab import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.contracts.registry import BUILTINS, names
from tests.helpers import REPO

CONF = REPO / "conf"


def _options(group):
    return sorted(p.stem for p in (CONF / group).glob("*.yaml"))


@pytest.mark.parametrize("group", ["system", "body", "initial", "integrator"])
def test_every_option_composes_and_builds(group):
    for option in _options(group):
        needs = ["accuracy=1e-8"] if (group, option) == ("integrator", "auto") else []
        if "gyrostat" in option:  # the satellite's options come with its preset (forces of an orbit)
            needs.append("experiment=gyrostat")
        scene = compose_scene([f"{group}={option}", *needs])
        assert scene.system.state_size in (6, 9)
        assert len(scene.times) >= 2


@pytest.mark.parametrize("option", _options("force"))
def test_every_force_builds_alone_and_with_the_others(option):
    scene = compose_scene([f"force=[{option}]"])
    assert [f.name for f in scene.system.forces] == [option]
    everything = compose_scene([f"force=[{','.join(_options('force'))}]"])
    assert len(everything.system.forces) == len(_options("force"))


def test_every_builtin_plugin_has_a_config_file():
    for group, plugins in BUILTINS.items():
        assert set(plugins) == set(_options(group)), group


def test_every_scene_preset_builds():
    scene = compose_scene(["experiment=gyrostat"])
    assert scene.system.name == "orbiting_gyrostat"
    assert [f.name for f in scene.system.forces] == ["newtonian", "magnetic"]


def test_a_satellite_refuses_a_weight():
    with pytest.raises(ConfigError, match="uniform_gravity acts on a body about a fixed point"):
        compose_scene(["experiment=gyrostat", "force=[uniform_gravity,newtonian]"])


def test_compiled_integrator_refuses_a_system_without_compiled_form(monkeypatch):
    """Every system is compiled from its traced rhs; one whose torque branches on the state cannot be, and a
    compiled integrator is refused in one sentence naming the force and the construct."""
    from gyrolab.plugins.forces.newtonian import Newtonian

    monkeypatch.setattr(Newtonian, "torque", lambda self, omega, axes: omega if omega[0] > 0 else -omega)
    with pytest.raises(ConfigError, match=r"torque of force 'newtonian' cannot be compiled: it (compares|branches)"):
        compose_scene(["experiment=gyrostat", "integrator=taylor"])


def test_no_force_gives_euler_poinsot():
    scene = compose_scene(["force=[]"])
    assert scene.system.forces == []


def test_target_outside_the_registry_is_refused():
    with pytest.raises(ConfigError, match="not a registered integrator plugin"):
        compose_scene(["integrator._target_=os.system"])
    with pytest.raises(ConfigError, match="not a registered force plugin"):
        compose_scene(["force.newtonian._target_=subprocess.call"])


def test_unknown_plugin_parameter_is_refused():
    with pytest.raises(ConfigError, match="not a parameter of DOP853"):
        compose_scene(["+integrator.order=5"])


def test_registry_lists_builtins():
    assert names("integrator") == ["auto", "bdf", "dop853", "dop853_numba", "lie_poisson", "lsoda", "radau", "rk4",
                                   "rk45", "rk4_numba", "taylor"]
    assert {"uniform_gravity", "newtonian", "magnetic"} <= set(names("force"))
