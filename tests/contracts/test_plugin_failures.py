"""What the engine checks of plugins: every failure of a third-party plugin ends as one sentence naming it.

The plugins below are installed as a third-party distribution (entry points), as a user's would be, each
with one flaw built in by hand: a torque that raises, returns None, a string, the wrong shape or NaN; a
false ``preserves_area_integral``; a potential that does not belong to its torque; an ``__init__`` that
raises or takes ``**params``; integrators that return NaN, the wrong shape or raise. A distribution whose
module cannot be imported leaves every other command working. Each case is checked through the Python
API and, for a few, through the real command line: the exit code, exactly one ``gyrolab: error:`` line
on stderr, no traceback and no ``run.nc``.
"""

import textwrap

import numpy as np
import pytest

from gyrolab.engine.scene import compose_scene
from gyrolab.errors import ConfigError, IntegrationError
from tests.conftest import installed_distribution
from tests.helpers import run_main

PLUGINS = textwrap.dedent('''
    import time

    import numpy as np
    from gyrolab.contracts import Force, Integrator, IntegratorStats, Solution
    from gyrolab.physics.vectors import cross, dot


    class _Drag(Force):
        required_axes = frozenset()
        preserves_area_integral = False

        def __init__(self, body, *, c=0.1):
            self.c = float(c)


    class Raising(_Drag):
        name = "raising"

        def torque(self, omega, axes):
            raise RuntimeError("the field table is empty")


    class ReturnsNone(_Drag):
        name = "returns_none"

        def torque(self, omega, axes):
            -self.c * omega  # forgot the return


    class ReturnsString(_Drag):
        name = "returns_string"

        def torque(self, omega, axes):
            return "0, 0, 1"


    class WrongShape(_Drag):
        name = "wrong_shape"

        def torque(self, omega, axes):
            return -self.c * omega[:2]


    class OneComponent(_Drag):
        name = "one_component"

        def torque(self, omega, axes):
            return np.array([-self.c])  # broadcasts silently in the right-hand side: only the guard sees it


    class NanTorque(_Drag):
        name = "nan_torque"

        def torque(self, omega, axes):
            return np.full(3, np.nan) * omega


    class SqrtNegative(_Drag):
        """NaN from a formula (not a NaN constant, which does not trace): the compiled kernel meets it."""
        name = "sqrt_negative"

        def torque(self, omega, axes):
            return self.c * np.sqrt(-1.0 - dot(omega, omega)) * omega


    class NanLater(_Drag):
        """Finite at the start, NaN once the body has turned: log of a component that changes sign."""
        name = "nan_later"
        required_axes = frozenset({2})

        def torque(self, omega, axes):
            return self.c * np.log(axes[2][0] + 0.2) * omega


    class AreaLiar(_Drag):
        """Drag −c ω has a component along γ, so Iω·γ decays: declaring it preserved is false."""
        name = "area_liar"
        preserves_area_integral = True

        def torque(self, omega, axes):
            return -self.c * omega


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


    class HalfPotential(Tilted):
        """The right potential, off by a constant factor: the energy it defines is not conserved."""
        name = "half_potential"

        def potential(self, axes):
            return -0.5 * dot(self.field(axes), self.m)


    class InitFails(_Drag):
        name = "init_fails"

        def __init__(self, body, *, kind="RuntimeError"):
            raise {"RuntimeError": RuntimeError, "ImportError": ImportError,
                   "SyntaxError": SyntaxError}[kind](f"cannot load the field model ({kind})")

        def torque(self, omega, axes):
            return np.zeros(3)


    class Variadic(_Drag):
        name = "variadic"

        def __init__(self, body, **params):
            self.c = float(params.get("c", 0.1))

        def torque(self, omega, axes):
            return -self.c * omega


    class _Fake(Integrator):
        adaptive = False

        def __init__(self, *, step=0.01):
            self.step = float(step)

        def honest(self, fun, t_out, y0):
            y = np.empty((len(t_out), len(y0)))
            y[0] = y0
            for i in range(1, len(t_out)):  # explicit midpoint, one step per output interval (short tests)
                h = t_out[i] - t_out[i - 1]
                y[i] = y[i - 1] + h * fun(t_out[i - 1] + h / 2, y[i - 1] + h / 2 * fun(t_out[i - 1], y[i - 1]))
            return Solution(np.asarray(t_out), y, IntegratorStats(nfev=2 * len(t_out), n_steps=len(t_out),
                                                                  n_rejected=0, wall_time=0.0))


    class Midpoint(_Fake):
        name = "midpoint"

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            return self.honest(fun, t_out, y0)


    class HalfNan(_Fake):
        name = "half_nan"

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            solution = self.honest(fun, t_out, y0)
            solution.y[len(t_out) // 2:] = np.nan
            return solution


    class WrongRows(_Fake):
        name = "wrong_rows"

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            solution = self.honest(fun, t_out, y0)
            return Solution(solution.t, solution.y[:-1], solution.stats)


    class Crashing(_Fake):
        name = "crashing"

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            return 1 / 0


    class NoSolution(_Fake):
        name = "no_solution"

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            return None
''')
FORCES = ("raising", "returns_none", "returns_string", "wrong_shape", "one_component", "nan_torque", "nan_later",
          "sqrt_negative",
          "area_liar", "tilted", "half_potential", "init_fails", "variadic")
INTEGRATORS = ("midpoint", "half_nan", "wrong_rows", "crashing", "no_solution")
SHORT = ["time.end=2", "time.n_output=21", "output.figures=false"]


def _class_name(name):
    return "".join(w.title() for w in name.split("_"))


@pytest.fixture(scope="module")
def plugins(tmp_path_factory):
    site = tmp_path_factory.mktemp("site")
    (site / "contract_plugins.py").write_text(PLUGINS)
    with installed_distribution(site, "gyrolab-contract-plugins", "0.1",
                                {"gyrolab.forces": {n: f"contract_plugins:{_class_name(n)}" for n in FORCES},
                                 "gyrolab.integrators": {n: f"contract_plugins:{_class_name(n)}" for n in INTEGRATORS}}):
        with pytest.warns(Warning):  # variadic's **params: one warning while composing, the rest works
            compose_scene(SHORT)
        yield site


def one_sentence(error):
    text = str(error)
    assert "\n" not in text and "Traceback" not in text, text
    return text


# ---- the force side ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("force, needles", [
    ("raising", ["torque of force 'raising' raised RuntimeError", "the field table is empty"]),
    ("returns_none", ["torque of force 'returns_none' returned NoneType None", "shape (3,)"]),
    ("returns_string", ["torque of force 'returns_string' returned str", "shape (3,)"]),
    ("wrong_shape", ["torque of force 'wrong_shape' returned ndarray of shape (2,)"]),
    ("one_component", ["torque of force 'one_component' returned ndarray of shape (1,)"]),
    ("nan_torque", ["torque of force 'nan_torque' returned the non-finite torque"]),
    ("nan_later", ["torque of force 'nan_later' returned the non-finite torque"]),
])
@pytest.mark.parametrize("integrator", ["dop853", "rk4"])
def test_a_bad_torque_is_one_integration_error_naming_the_force(plugins, force, needles, integrator):
    scene = compose_scene([f"force=[uniform_gravity,{force}]", f"integrator={integrator}", *SHORT,
                           "time.end=20", "initial.r0=3"])
    with pytest.raises(IntegrationError) as caught:
        scene.run()  # a NaN torque under DOP853 ends at once (it used to reject steps forever)
    text = one_sentence(caught.value)
    for needle in needles:
        assert needle in text, text


def test_a_nan_torque_does_not_hang_dop853(plugins):
    import time

    scene = compose_scene(["force=[nan_torque]", "integrator=dop853", "time.end=1", "output.figures=false"])
    start = time.perf_counter()
    with pytest.raises(IntegrationError, match="nan_torque"):
        scene.run()
    assert time.perf_counter() - start < 5


def test_built_in_forces_run_unguarded_and_plugin_forces_guarded(plugins):
    from gyrolab.engine.force_guard import GuardedRhs

    builtin = compose_scene(SHORT)
    assert not isinstance(builtin.rhs, GuardedRhs)  # no guard: the built-in scenes pay nothing
    guarded = compose_scene(["force=[uniform_gravity,tilted]", "integrator=dop853", *SHORT])
    assert isinstance(guarded.rhs, GuardedRhs)
    y0 = guarded.system.initial_state()
    np.testing.assert_array_equal(guarded.rhs(0.0, y0), guarded.system.rhs(0.0, y0))
    assert "torque" not in vars(guarded.system.forces[1])  # the inspection left the force as it was
    guarded.run()


@pytest.mark.parametrize("kind", ["RuntimeError", "ImportError", "SyntaxError"])
def test_an_init_that_raises_anything_is_one_config_error(plugins, kind):
    with pytest.raises(ConfigError) as caught:
        compose_scene(["force=[init_fails]", f"force.init_fails.kind={kind}", *SHORT])
    text = one_sentence(caught.value)
    assert text.startswith("force.init_fails: plugin 'init_fails'") and f"{kind}: cannot load the field model" in text


def test_an_init_with_var_keyword_is_refused_naming_the_fix(plugins):
    with pytest.raises(ConfigError) as caught:
        compose_scene(["force=[variadic]", *SHORT])
    text = one_sentence(caught.value)
    assert "'variadic'" in text and "**params" in text and "declare each parameter as a keyword with a default" in text


# ---- claims checked at build ---------------------------------------------------------------------------------

def test_a_false_area_claim_is_refused_at_build(plugins):
    with pytest.raises(ConfigError) as caught:
        compose_scene(["force=[uniform_gravity,area_liar]", *SHORT])
    text = one_sentence(caught.value)
    assert "force 'area_liar' declares preserves_area_integral = True" in text
    assert "torque·γ = " in text and "the initial state" in text and "declare preserves_area_integral = False" in text


def test_a_potential_off_by_a_factor_is_refused_at_build(plugins):
    compose_scene(["force=[tilted]", *SHORT])  # the right potential passes
    with pytest.raises(ConfigError) as caught:
        compose_scene(["force=[half_potential]", *SHORT])
    text = one_sentence(caught.value)
    assert "the potential of force 'half_potential' does not belong to its torque" in text
    assert "Σ e_i × ∂V/∂e_i" in text and "difference" in text


def test_claims_are_checked_on_the_satellite_too(plugins):
    with pytest.raises(ConfigError, match="'area_liar' declares preserves_area_integral = True"):
        compose_scene(["experiment=gyrostat", "force=[newtonian,area_liar]", *SHORT])


def test_the_claim_check_measures_rotations_like_the_force_kit():
    """The engine's numeric helper is the kit's (moved below the engine): one derivative, one verdict."""
    from gyrolab import testing
    from gyrolab.contracts import claims

    assert testing.rotation_torque is claims.rotation_torque and testing.random_states is claims.random_states


# ---- the run checks its invariants ---------------------------------------------------------------------------

def _unchecked(monkeypatch):
    """Let a false claim through the build, as a claim true at the checked states but false later would."""
    from gyrolab.engine import scene

    monkeypatch.setattr(scene, "check_force_claims", lambda system, t0=0.0: None)


@pytest.mark.parametrize("integrator", [["integrator=dop853"], ["integrator=rk4", "integrator.step=0.001"]])
def test_a_drifting_invariant_is_flagged_not_drawn_as_conserved(plugins, monkeypatch, caplog, tmp_path, integrator):
    _unchecked(monkeypatch)
    overrides = ["force=[uniform_gravity,area_liar]", "force.area_liar.c=0.05", *integrator, "time.end=10",
                 "time.n_output=201"]
    with caplog.at_level("WARNING"):
        ds = compose_scene(overrides).run()
    assert ds.attrs["violated_invariants"] == "area_integral"
    assert ds.area_integral.attrs["invariant_check"] == "violated"
    assert ds.area_integral.attrs["max_abs_drift"] > 10 * ds.area_integral.attrs["invariant_allowed_drift"]
    assert "invariant 'area_integral' drifts by" in ds.area_integral.attrs["comment"]
    assert "energy" not in ds  # drag has no potential: the energy is not monitored
    assert "invariant_check" not in ds.gamma_norm.attrs and "invariant_check" not in ds.frame_error.attrs
    assert len([r for r in caplog.records if "area_integral" in r.getMessage()]) == 1
    from gyrolab.figures.run import draw_invariants

    fig = draw_invariants(ds)
    ax = fig.axes[0]
    labels = [line.get_label() for line in ax.get_lines()]
    assert not any("area" in label for label in labels) and any("norm" in label for label in labels), labels
    assert "NOT conserved by this run" in ax.get_title(loc="left")


def test_an_honest_plugin_and_the_built_in_scenes_are_not_flagged(plugins):
    for overrides in (["force=[uniform_gravity,tilted]"], [], ["integrator=rk4", "integrator.step=0.05"],
                      ["integrator=rk45", "integrator.rtol=1e-3", "integrator.atol=1e-3"],
                      ["integrator=lie_poisson", "integrator.step=0.02"], ["experiment=gyrostat"]):
        ds = compose_scene([*overrides, "time.end=20", "output.figures=false"]).run()
        assert "violated_invariants" not in ds.attrs, overrides


def test_the_criterion_judges_drift_against_the_integration_error():
    from gyrolab.output.invariant_check import FLOOR, explained_error, violated_invariants

    t = np.linspace(0, 1, 11)
    kinematic = 1 + 1e-9 * t  # |γ| drifts by 1e-9: the integration error actually made
    series = {name: (v[0], v.max(), v.min()) for name, v in {"energy": 2 + 1e-4 * t, "gamma_norm": kinematic}.items()}
    attrs = {"integrator_rtol": 1e-10, "integrator_atol": 1e-10, "integrator_n_steps": 100}
    assert explained_error(attrs, True, 1e-9, 1.0) == pytest.approx(1e-5)  # max(1e3·1e-10·100, 1e3·1e-9, FLOOR)
    assert set(violated_invariants(series, ["energy", "gamma_norm"], attrs, True, 1.0)) == {"energy"}
    loose = {**attrs, "integrator_rtol": 1e-3}  # a loose tolerance explains the same drift
    assert violated_invariants(series, ["energy", "gamma_norm"], loose, True, 1.0) == {}
    assert explained_error({}, True, None, 1.0) is None  # nothing to judge by: no verdict
    assert explained_error({"integrator_step": 0.01, "sampling_fastest_rate": 2.0}, False, None, 10.0) \
        == pytest.approx(0.02 ** 2 * 20)  # (hν)^2 νT: order 2 unless the dataset states it
    assert explained_error({"integrator_step": 0.01, "sampling_fastest_rate": 2.0, "integrator_order": 4}, False,
                           None, 10.0) == pytest.approx(max(FLOOR, 0.02 ** 4 * 20))


# ---- the integrator side -------------------------------------------------------------------------------------

def test_a_third_party_integrator_overriding_integrate_keeps_working_and_is_checked(plugins):
    from gyrolab.contracts.integrator_rules import _CHECKED
    from gyrolab.plugins.integrators.scipy_solvers import DOP853

    scene = compose_scene(["integrator=midpoint", *SHORT])
    assert getattr(type(scene.integrator).integrate, _CHECKED)
    assert getattr(DOP853.integrate, _CHECKED)  # the built-ins too
    ds = scene.run()
    assert np.isfinite(ds.omega.values).all()


@pytest.mark.parametrize("integrator, needles", [
    ("half_nan", ["integrator 'half_nan' returned 66 non-finite values of 21×6 (from t = 1)"]),
    ("wrong_rows", ["integrator 'wrong_rows' returned states of shape (20, 6)", "21×6"]),
    ("crashing", ["integrator 'crashing' raised ZeroDivisionError: division by zero"]),
    ("no_solution", ["integrator 'no_solution' returned NoneType, not a gyrolab.contracts.Solution"]),
])
def test_a_broken_integrator_is_one_integration_error_naming_it(plugins, integrator, needles):
    scene = compose_scene([f"integrator={integrator}", *SHORT, "output.euler_angles=false"])
    with pytest.raises(IntegrationError) as caught:
        scene.run()
    text = one_sentence(caught.value)
    for needle in needles:
        assert needle in text, text


@pytest.mark.parametrize("compiled", [False, True], ids=["numpy scans", "compiled scans"])
def test_integrate_refuses_bad_inputs(compiled):
    from gyrolab.plugins.integrators.compiled_solvers import Taylor
    from gyrolab.plugins.integrators.rk4 import RK4

    if compiled:  # a run with a compiled model scans with gyrolab.kernels.scans
        scene = compose_scene(["integrator=taylor", *SHORT, "output.euler_angles=false"])
        fun, model, good, method = None, scene.compiled, scene.system.initial_state(), Taylor(tol=1e-9)
    else:
        fun, model, good, method = (lambda t, y: -y), None, np.array([1.0, 2.0]), RK4()
    bad = good.copy()
    bad[-1] = np.nan
    with pytest.raises(IntegrationError, match=f"initial state of shape \\({len(good)},\\) \\(1 non-finite values\\)"):
        method.integrate(fun, np.linspace(0, 1, 3), bad, None, model)
    for times in ([0.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, np.nan, 2.0], [0.0, np.inf, 2.0], [0.0, 1.0, np.inf],
                  [np.nan, 1.0], [-np.inf, 1.0]):
        with pytest.raises(IntegrationError, match="strictly increasing"):
            method.integrate(fun, np.array(times), good, None, model)
    assert method.integrate(fun, np.linspace(0, 1, 3), list(good), None, model).y.shape == (3, len(good))


# ---- the command line: exit code, one line, no traceback, no run.nc ------------------------------------------

@pytest.mark.parametrize("argv, code, needle", [
    (["force=[uniform_gravity,raising]"], 3, "torque of force 'raising' raised RuntimeError"),
    (["force=[returns_none]"], 3, "torque of force 'returns_none' returned NoneType"),
    (["integrator=half_nan"], 3, "integrator 'half_nan' returned"),
    (["integrator=crashing"], 3, "integrator 'crashing' raised ZeroDivisionError"),
    (["force=[area_liar]"], 2, "declares preserves_area_integral = True"),
    (["force=[half_potential]"], 2, "does not belong to its torque"),
    (["force=[init_fails]", "force.init_fails.kind=ImportError"], 2, "failed to build: ImportError"),
])
def test_command_line_failures_are_one_line(plugins, tmp_path, monkeypatch, capsys, argv, code, needle):
    monkeypatch.chdir(tmp_path)
    status, err = run_main([*argv, *SHORT, "hydra.run.dir=out"], monkeypatch, capsys)
    errors = [line for line in err.splitlines() if line.startswith("gyrolab: error:")]
    assert status == code, err
    assert len(errors) == 1 and needle in errors[0], err
    assert "Traceback" not in err
    assert not list(tmp_path.rglob("run.nc"))


BROKEN = {"broken": "broken_field:Broken"}


@pytest.fixture
def broken_site(tmp_path_factory):
    site = tmp_path_factory.mktemp("broken_site")
    (site / "broken_field.py").write_text('raise ImportError("broken_field needs libfield 2.0")\n')
    with installed_distribution(site, "gyrolab-broken-field", "1.2", BROKEN):
        yield site


def test_a_broken_entry_point_is_one_warning_and_a_refusal_in_the_api(broken_site):
    from gyrolab.contracts.registry import PluginLoadWarning

    with pytest.warns(PluginLoadWarning) as caught:
        ds = compose_scene(SHORT).run()  # a built-in scene works
    assert np.isfinite(ds.omega.values).all()
    (warning,) = [w for w in caught if issubclass(w.category, PluginLoadWarning) and "'broken'" in str(w.message)]
    text = str(warning.message)
    assert "'broken'" in text and "'gyrolab-broken-field'" in text and "broken_field:Broken" in text
    assert "ImportError: broken_field needs libfield 2.0" in text
    with pytest.raises(ConfigError) as refused:
        compose_scene(["force=[uniform_gravity,broken]", *SHORT])
    text = one_sentence(refused.value)
    assert text.startswith("force plugin 'broken' from distribution 'gyrolab-broken-field' (entry point broken = "
                           "broken_field:Broken) cannot be imported (ImportError: broken_field needs libfield 2.0)")


def test_a_broken_entry_point_leaves_the_command_line_working(broken_site, cli, tmp_path):
    env = {"PYTHONPATH": str(broken_site)}
    helped = cli("--help", env_extra=env)
    assert helped.returncode == 0 and "Configuration groups" in helped.stdout, helped.stderr
    warnings = [line for line in helped.stderr.splitlines() if line.strip()]
    assert len(warnings) == 1 and warnings[0].startswith("gyrolab: warning: force plugin 'broken' from "
                                                         "distribution 'gyrolab-broken-field'"), helped.stderr
    ran = cli(*SHORT, "hydra.run.dir=ok", env_extra=env)
    assert ran.returncode == 0, ran.stderr
    assert (tmp_path / "ok" / "run.nc").exists()
    assert ran.stderr.count("gyrolab: warning:") == 1 and "Traceback" not in ran.stderr
    refused = cli("force=[broken]", *SHORT, "hydra.run.dir=refused", env_extra=env)
    assert refused.returncode == 2
    errors = [line for line in refused.stderr.splitlines() if line.startswith("gyrolab: error:")]
    assert len(errors) == 1 and "cannot be imported (ImportError: broken_field needs libfield 2.0)" in errors[0]
    assert "Traceback" not in refused.stderr and not (tmp_path / "refused").exists()


def test_a_bad_torque_through_the_real_command_line(plugins, cli, tmp_path):
    done = cli("force=[uniform_gravity,nan_torque]", *SHORT, "hydra.run.dir=out",
               env_extra={"PYTHONPATH": str(plugins)})
    assert done.returncode == 3, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("gyrolab: error:")]
    assert len(errors) == 1 and "torque of force 'nan_torque' returned the non-finite torque" in errors[0]
    assert "Traceback" not in done.stderr
    assert not list(tmp_path.rglob("run.nc"))


def test_a_nan_torque_on_the_compiled_path_is_named_too(plugins):
    with pytest.raises(ConfigError, match="force 'nan_torque' cannot be compiled: it uses the non-finite number"):
        compose_scene(["force=[uniform_gravity,nan_torque]", "integrator=dop853_numba", *SHORT])  # refused at build
    scene = compose_scene(["force=[uniform_gravity,sqrt_negative]", "integrator=dop853_numba", *SHORT])
    assert scene.compiled is not None  # the formula traces: the compiled kernel meets the NaN
    with pytest.raises(IntegrationError) as caught:
        scene.run()
    assert "torque of force 'sqrt_negative' returned the non-finite torque" in one_sentence(caught.value)
    later = compose_scene(["force=[uniform_gravity,nan_later]", "integrator=dop853_numba", *SHORT, "time.end=20",
                           "initial.r0=3"])
    with pytest.raises(IntegrationError) as caught:  # NaN only later: the kernel's own sentence
        later.run()
    assert "dop853_numba failed near t=" in one_sentence(caught.value)
