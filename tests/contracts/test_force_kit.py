"""gyrolab.testing.check_force, and third-party torques compiled into the compiled integrators.

The test forces below are installed as a third-party distribution (entry points), as a user's
plugin would be. Every expected number is independent of the code under test: the kit's
verdicts are checked on forces whose flaw is built in by hand; the compiled torque is compared
with the plugin's own Python torque (scipy's DOP853 on the Python right-hand side), and drag on a
spherical body with its exact solution ω0 exp(−c t).
"""

import textwrap

import numpy as np
import pytest

from gyrolab.engine.scene import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.plugins.forces.magnetic import Magnetic
from gyrolab.plugins.forces.newtonian import Newtonian
from gyrolab.plugins.forces.uniform_gravity import UniformGravity
from gyrolab.testing import check_force
from tests.conftest import installed_distribution

FORCES = textwrap.dedent('''
    import numpy as np
    from gyrolab.contracts import Force
    from gyrolab.physics.vectors import cross, dot


    class Tilted(Force):
        """A uniform field along (sin a, 0, cos a) acting on a dipole m: m × B with B = b (sin a α + cos a γ)."""
        name = "tilted"
        required_axes = frozenset({0, 2})
        preserves_area_integral = False

        def __init__(self, body, *, b=0.4, a=0.6, m=(0.2, -0.1, 1.0)):
            self.b, self.a, self.m = float(b), float(a), np.array(m, dtype=float)

        def field(self, axes):
            return self.b * (np.sin(self.a) * axes[0] + np.cos(self.a) * axes[2])

        def torque(self, omega, axes):
            return cross(self.m, self.field(axes))

        def potential(self, axes):
            return -dot(self.field(axes), self.m)


    class WrongPotential(Tilted):
        name = "wrong_potential"

        def potential(self, axes):
            return dot(self.field(axes), self.m)  # sign error


    class Pulsed(Force):
        """A time-dependent, nonlinear torque on β = γ × α and ω: exercises sqrt, exp, sin, powers, quotients."""
        name = "pulsed"
        required_axes = frozenset({1, 2})
        time_dependent = True
        preserves_area_integral = False

        def __init__(self, body, *, c=0.05):
            self.c = float(c)

        def torque(self, omega, axes, t):
            beta, gamma = axes[1], axes[2]
            r = np.sqrt(dot(omega, omega) + 1.0)
            return self.c * np.sin(2.0 * t) * cross(beta, gamma * r) - self.c * np.exp(-t) * omega ** 2 / r


    class Branchy(Force):
        name = "branchy"
        required_axes = frozenset()
        preserves_area_integral = False

        def __init__(self, body, *, c=0.1):
            self.c = float(c)

        def torque(self, omega, axes):
            return -self.c * omega if omega[2] > 0 else self.c * omega


    class Undeclared(Force):
        name = "undeclared"

        def __init__(self, body, *, c=0.1):
            self.c = float(c)

        def torque(self, omega, axes):
            return -self.c * omega
''')
NAMES = ("tilted", "wrong_potential", "pulsed", "branchy", "undeclared")


@pytest.fixture(scope="module")
def kit_forces(tmp_path_factory):
    site = tmp_path_factory.mktemp("site")
    (site / "kit_forces.py").write_text(FORCES)
    classes = {n: f"kit_forces:{''.join(w.title() for w in n.split('_'))}" for n in NAMES}
    with installed_distribution(site, "kit-forces", "0.1", classes):
        import kit_forces

        yield kit_forces


@pytest.mark.parametrize("cls, params", [(UniformGravity, {}), (Newtonian, {"k": 1.5}), (Magnetic, {"field": 0.7}),
                                         (Magnetic, {"field": 0.7, "direction": [0.6, 0.0, 0.8]})])
def test_kit_passes_every_builtin(cls, params):
    check_force(cls, **params)


def test_kit_passes_a_correct_plugin_and_its_compiled_torque(kit_forces):
    check_force(kit_forces.Tilted)
    check_force(kit_forces.Pulsed)  # time-dependent, nonlinear: compiled torque = Python torque at random states


def test_kit_rejects_a_wrong_potential(kit_forces):
    with pytest.raises(AssertionError, match="WrongPotential: potential does not belong to the torque"):
        check_force(kit_forces.WrongPotential)


@pytest.mark.parametrize("declared, torque, needle", [
    (True, "-0.1 * omega", "preserves_area_integral is True, but the torque has a component"),
    (False, "cross(np.array([0.0, 0.3, 1.0]), axes[2])", "preserves_area_integral is False, but torque·γ = 0"),
])
def test_kit_rejects_a_wrong_area_flag(declared, torque, needle):
    namespace = {}
    exec(textwrap.dedent(f'''
        import numpy as np
        from gyrolab.contracts import Force
        from gyrolab.physics.vectors import cross

        class Flagged(Force):
            name = "flagged"
            required_axes = frozenset({{2}})
            preserves_area_integral = {declared}

            def __init__(self, body):
                pass

            def torque(self, omega, axes):
                return {torque}
    '''), namespace)
    with pytest.raises(AssertionError, match=needle):
        check_force(namespace["Flagged"])


def test_kit_rejects_an_undeclared_axis_and_a_silent_bad_parameter(kit_forces):
    class ReadsGamma(kit_forces.Tilted):
        name = "reads_gamma"
        required_axes = frozenset({2})  # but the field reads α too

    with pytest.raises(AssertionError, match="reads a reference axis not in required_axes"):
        check_force(ReadsGamma)

    class Lax(kit_forces.Tilted):
        name = "lax"

        def __init__(self, body, *, b=0.4, a=0.6, m=(0.2, -0.1, 1.0), label="x"):
            super().__init__(body, b=b, a=a, m=m)
            self.label = label  # accepts anything

    with pytest.raises(AssertionError, match="label='abc' was accepted"):
        check_force(Lax)


def test_scene_turns_plugin_init_errors_and_a_missing_area_flag_into_one_sentence(kit_forces):
    with pytest.raises(ConfigError, match=r"^force\.tilted\.b='abc' is not valid for Tilted: ValueError"):
        compose_scene(["force=[tilted]", "force.tilted.b=abc"])
    with pytest.raises(ConfigError, match="must declare preserves_area_integral"):
        compose_scene(["force=[undeclared]"])


SHORT = ["time.end=3", "time.n_output=31", "output.euler_angles=false"]


def test_expression_runs_compiled_like_the_python_path(kit_forces):
    overrides = ["force=[uniform_gravity,tilted,pulsed]", *SHORT]
    scene = compose_scene([*overrides, "integrator=dop853_numba"])
    assert scene.compiled is not None
    from gyrolab.plugins.integrators.step_guard import compiled_rhs

    fun = compiled_rhs(scene.compiled)
    rng = np.random.default_rng(1)
    for t in (0.0, 0.4, 2.5):  # the compiled right-hand side equals the system's Python one
        y = scene.system.initial_state() + rng.normal(scale=0.3, size=scene.system.state_size)
        np.testing.assert_allclose(fun(t, y), scene.system.rhs(t, y), rtol=1e-13, atol=1e-14)
    tol = ["integrator.rtol=1e-11", "integrator.atol=1e-11"]
    compiled = compose_scene([*overrides, "integrator=dop853_numba", *tol]).run()
    python = compose_scene([*overrides, "integrator=dop853", *tol]).run()
    np.testing.assert_allclose(compiled.omega.values, python.omega.values, rtol=0, atol=1e-8)
    assert "energy" not in compiled.attrs["monitored_invariants"]  # time-dependent forces have no energy


def test_auto_batch_taylor_and_untraceable_torques(kit_forces):
    auto = compose_scene(["force=[tilted]", "integrator=auto", "integrator.accuracy=1e-6", *SHORT])
    assert auto.compiled is not None
    reference = compose_scene(["force=[tilted]", "integrator=dop853", "integrator.rtol=1e-12",
                               "integrator.atol=1e-12", *SHORT]).run()
    ran = auto.run()
    assert ran.attrs["auto_method"] == "taylor"  # the traced torque has Taylor coefficients
    assert np.max(np.abs(ran.omega.values[-1] - reference.omega.values[-1])) <= 1e-6
    taylor = compose_scene(["force=[tilted]", "integrator=taylor", "integrator.tol=1e-14", *SHORT]).run()
    np.testing.assert_allclose(taylor.omega.values, reference.omega.values, rtol=0, atol=1e-9)
    # a time-dependent torque too: its series read the step's start time (reference: scipy on the Python torque)
    pulsed = compose_scene(["force=[pulsed]", "integrator=taylor", "integrator.tol=1e-14", *SHORT]).run()
    python = compose_scene(["force=[pulsed]", "integrator=dop853", "integrator.rtol=1e-12", "integrator.atol=1e-12",
                            *SHORT]).run()
    np.testing.assert_allclose(pulsed.omega.values, python.omega.values, rtol=0, atol=1e-9)
    timed = compose_scene(["force=[pulsed]", "integrator=auto", "integrator.accuracy=1e-6", *SHORT])
    assert timed.run().attrs["auto_method"] == "taylor"
    with pytest.raises(ConfigError, match="torque of force 'branchy' cannot be compiled: it compares the state"):
        compose_scene(["force=[branchy]", "integrator=dop853_numba", *SHORT])
    fallback = compose_scene(["force=[branchy]", "integrator=auto", "integrator.accuracy=1e-6", *SHORT])
    assert fallback.compiled is None  # auto runs scipy's DOP853 on the Python torque

    from gyrolab.batch.integrate import integrate_batch

    scene = compose_scene(["force=[uniform_gravity,tilted]", "integrator=rk4_numba", "integrator.step=0.01", *SHORT])
    y0 = scene.system.initial_state()
    y0s = np.stack([y0, y0 + np.r_[0.1, -0.2, 0.3, np.zeros(y0.size - 3)]])
    batch = integrate_batch(scene, y0s)
    for row, start in enumerate(y0s):  # --batch's compiled path = one compiled trajectory at a time
        alone = scene.integrator.integrate(scene.system.rhs, scene.times, start, None, scene.compiled)
        np.testing.assert_allclose(batch.y[row], alone.y, rtol=0, atol=1e-13)


def test_first_compile_of_a_form_is_logged_once_then_loaded_from_the_cache(tmp_path, monkeypatch, caplog):
    import logging

    from gyrolab.contracts import Force
    from gyrolab.kernels import compiler, expression, model

    class Once(Force):
        name = "once_only"
        preserves_area_integral = False

        def __init__(self, body):
            pass

        def torque(self, omega, axes):
            return -0.25 * omega * omega[1] / 3.0  # a form no other test traces

    def equations(t, y):
        return Once(None).torque(y[0:3], (None, None, y[3:6]))

    monkeypatch.setattr(compiler, "kernel_cache_dir", lambda: str(tmp_path))
    monkeypatch.setattr(expression, "_LOADED", {})
    with caplog.at_level(logging.INFO, logger=expression.__name__):
        first = model.compile(model.trace(equations, 6, "force once_only"))
        assert "compiling force once_only, once" in caplog.text
        caplog.clear()
        monkeypatch.setattr(expression, "_LOADED", {})  # a new process: the module and numba's cache reload
        again = model.compile(model.trace(equations, 6, "force once_only"))
        assert "compiling" not in caplog.text
    assert len(list((tmp_path / "forces").glob("gyrolab_rhs_*.py"))) == 1
    np.testing.assert_array_equal(first.params[1:-4], again.params[1:-4])
