"""The three example packages beyond forces: an integrator, a system and a regime from outside the source tree.

Each is installed the way pip lays a distribution out (``installed_distribution``: its package on the path, a
.dist-info with its pyproject's entry points), found through its entry point, run from the Python API (and the
integrator and the system from the command line), and its own tests (gyrolab's contract kits and an exact solution)
run here. The kits themselves are tested below on deliberately broken plugins: a kit that cannot fail checks nothing.
"""

import inspect
import tomllib

import numpy as np
import pytest
import xarray as xr

from gyrolab import compose_scene
from gyrolab.contracts import Integrator, IntegratorStats, Solution, registry
from gyrolab.errors import ConfigError
from gyrolab.plugins.integrators.scipy_solvers import DOP853
from gyrolab.plugins.regimes.small_parameter import SmallParameter
from gyrolab.plugins.systems.fixed_point import FixedPoint
from gyrolab.testing import check_integrator, check_regime, check_system
from tests.conftest import installed_distribution
from tests.helpers import REPO, example_tests

EXAMPLES = {  # folder -> (entry-point group, plugin name, the example's own test file)
    "gyrolab-scipy-rk23": ("gyrolab.integrators", "scipy_rk23", "test_scipy_rk23.py"),
    "gyrolab-rotor-body": ("gyrolab.systems", "rotor_body", "test_rotor_body.py"),
    "gyrolab-steady-precession": ("gyrolab.regimes", "steady_precession", "test_steady_precession.py"),
}
LAGRANGE_TOP = ["body=lagrange_top", "force=[uniform_gravity]", "initial.phi0=1.5707963267948966"]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """All three examples installed at once (each its own distribution); yields the folders to put on PYTHONPATH."""
    from contextlib import ExitStack

    with ExitStack() as stack:
        paths = []
        for folder, (group, _, _) in EXAMPLES.items():
            example = REPO / "examples" / folder
            project = tomllib.loads((example / "pyproject.toml").read_text())["project"]
            site = stack.enter_context(installed_distribution(
                tmp_path_factory.mktemp("site"), project["name"], project["version"],
                project["entry-points"][group], [example], group=group))
            paths += [str(site), str(example)]
        yield paths


def _run_all(module):
    """Every test function of an example's test module, each parametrization included (no fixtures are used)."""
    ran = 0
    for name, test in inspect.getmembers(module, inspect.isfunction):
        if not name.startswith("test_"):
            continue
        marks = [m for m in getattr(test, "pytestmark", []) if m.name == "parametrize"]
        cases = [()] if not marks else [c if isinstance(c, tuple) else (c,) for c in marks[0].args[1]]
        for case in cases:
            test(*case)
            ran += 1
    return ran


@pytest.mark.parametrize("folder", sorted(EXAMPLES))
def test_example_is_found_through_its_entry_point(installed, folder):
    group, name, _ = EXAMPLES[folder]
    config_group = next(g for g, (ep_group, _) in registry.GROUPS.items() if ep_group == group)
    assert name in registry.names(config_group)
    assert registry.load(config_group, name).__module__.startswith(folder.replace("-", "_"))


@pytest.mark.parametrize("folder", sorted(EXAMPLES))
def test_example_package_passes_its_own_tests(installed, folder):
    assert _run_all(example_tests(folder, EXAMPLES[folder][2])) >= 3


def test_integrator_runs_from_the_api(installed):
    ds = compose_scene(["integrator=scipy_rk23", "integrator.rtol=1e-9", "time.end=2", "time.n_output=21"]).run()
    reference = compose_scene(["integrator=dop853", "integrator.rtol=1e-12", "integrator.atol=1e-12", "time.end=2",
                               "time.n_output=21"]).run()
    np.testing.assert_allclose(ds.omega.values, reference.omega.values, atol=1e-6)
    assert ds.attrs["integrator"] == "scipy_rk23"


def test_example_integrator_joins_batch_with_its_single_runs_numbers(installed, tmp_path):
    # issue 21's "done when": an external integrator from examples/ runs --batch (no batch kernel: one integrate()
    # call per point), with the numbers of its single runs
    from gyrolab.batch.sweep import run_batch_sweep

    scene = ["integrator=scipy_rk23", "integrator.rtol=1e-9", "time.end=2", "time.n_output=21"]
    path = run_batch_sweep([*scene, "batch.output=trajectory", "initial.r0=1,3"], tmp_path / "grid")
    with xr.open_dataset(path) as ds:
        assert ds.attrs["batch_path"] == "one integrate() call per point"
        for i, r0 in enumerate([1, 3]):
            single = compose_scene([*scene, f"initial.r0={r0}"]).run()
            np.testing.assert_array_equal(ds.omega[i].values, single.omega.values)


def test_system_runs_from_the_api(installed):
    ds = compose_scene(["body=rotor_body", "force=[]", "integrator=dop853", "time.end=5", "time.n_output=51"]).run()
    assert ds.attrs["system"] == "rotor_body"
    assert ds.attrs["monitored_invariants"] == "kinetic_energy momentum_squared gamma_norm"
    assert list(ds.attrs["body_rotor_momentum"]) == [0.0, 0.0, 0.5]


def test_system_body_typo_is_one_sentence(installed):
    with pytest.raises(ConfigError, match=r"^body\.rotor_momentm is not a parameter of the rotor body"):
        compose_scene(["body=rotor_body", "force=[]", "+body.rotor_momentm=[0,0,1]"])


def test_regime_runs_from_the_api(installed):
    # regime=steady_precession in a scene's config; the scene run from the regime's own t = 0 state follows it
    scene = [*LAGRANGE_TOP, "regime=steady_precession", "regime.branch=fast", "initial.theta0=2.5", "initial.r0=3"]
    regime_cls = registry.load("regime", "steady_precession")
    composed = compose_scene(scene)
    regime = regime_cls(**{k: v for k, v in composed.config.regime.items() if k != "_target_"})
    assert regime.branch == "fast" and regime.check_domain(composed.system)  # p0, q0 are reseated: one warning
    y0, period = regime.initial_state(composed.system), regime.period(composed.system)
    ds = compose_scene([*scene, f"initial.p0={float(y0[0])!r}", f"initial.q0={float(y0[1])!r}",
                        f"time.end={2 * float(period)!r}", "time.n_output=101"]).run()
    expected = regime.solution(composed.system, ds.time.values)
    np.testing.assert_allclose(ds.omega.values, expected[:, :3], atol=1e-8)   # dop853 at its default rtol = 1e-10
    np.testing.assert_allclose(ds.gamma.values, expected[:, 3:], atol=1e-8)
    np.testing.assert_allclose(expected[-1], expected[0], atol=1e-12)          # periodic in the body frame


def test_integrator_and_system_run_from_the_command_line(installed, cli, tmp_path):
    env = {"PYTHONPATH": ":".join(installed)}
    done = cli("body=rotor_body", "force=[]", "integrator=scipy_rk23", "integrator.rtol=1e-8", "time.end=2",
               "time.n_output=21", "hydra.run.dir=out", env_extra=env)
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "out" / "run.nc") as ds:
        assert ds.attrs["system"] == "rotor_body" and ds.attrs["integrator"] == "scipy_rk23"
        assert ds.kinetic_energy.attrs["units"] == "J"
    figures = {p.stem for p in (tmp_path / "out" / "figures").glob("*.png")}
    assert figures == {"state", "invariant_drift", "euler_angles", "body_axis_sphere"}
    typo = cli("body=rotor_body", "force=[]", "body.rotor_momentm=[0,0,1]", env_extra=env)
    assert typo.returncode == 2 and "did you mean `body.rotor_momentum`?" in typo.stderr


# ---- the kits fail on broken plugins ------------------------------------------------------------------------

class WrongShape(DOP853):
    """Drops the last output time."""

    name = "wrong_shape"

    def integrate(self, fun, t_out, y0, progress=None, compiled=None):
        solution = super().integrate(fun, t_out, y0, progress, compiled)
        return Solution(t=solution.t[:-1], y=solution.y[:-1], stats=solution.stats)


class NaNOnBlowUp(Integrator):
    """Explicit Euler that lets the state overflow instead of raising IntegrationError."""

    name = "nan_on_blow_up"
    adaptive = False

    def integrate(self, fun, t_out, y0, progress=None, compiled=None):
        y, out, n = np.array(y0, dtype=float), [np.array(y0, dtype=float)], 0
        with np.errstate(all="ignore"):
            for t0, t1 in zip(t_out[:-1], t_out[1:]):
                steps = int(np.ceil((t1 - t0) / 1e-4))
                for k in range(steps):
                    y = y + (t1 - t0) / steps * fun(t0 + k * (t1 - t0) / steps, y)
                    n += 1
                out.append(y.copy())
                if progress is not None:
                    progress(t1)
        return Solution(t=np.asarray(t_out), y=np.array(out), stats=IntegratorStats(n, n, 0, 0.0))


class DriftingEnergy(FixedPoint):
    """Monitors an "energy" that leaks: the kit must catch an invariant that is not conserved."""

    def variables(self, t, y):
        out = super().variables(t, y)
        out["energy"] = out["energy"].copy(data=out["energy"].values + 1e-6 * t)
        return out


class OffStart(SmallParameter):
    """A solution that does not start at its initial state."""

    def initial_state(self, system):
        return super().initial_state(system) + np.array([0.0, 0.0, 1e-6, 0.0, 0.0, 0.0])


class Silent(DOP853):
    """Never reports progress."""

    name = "silent"

    def integrate(self, fun, t_out, y0, progress=None, compiled=None):
        return super().integrate(fun, t_out, y0, None, compiled)


class Sloppy(DOP853):
    """States rtol = 1e-10 but integrates at 1e-3."""

    name = "sloppy"

    def integrate(self, fun, t_out, y0, progress=None, compiled=None):
        return DOP853(rtol=1e-3, atol=1e-3).integrate(fun, t_out, y0, progress, compiled)


class Unvalidated(DOP853):
    """Takes any step without checking it."""

    name = "unvalidated"

    def __init__(self, *, rtol=1e-10, atol=1e-10, first_step=0.1):
        super().__init__(rtol=rtol, atol=atol)
        self.first_step = first_step


class NoUnits(FixedPoint):
    def variables(self, t, y):
        out = super().variables(t, y)
        del out["theta"].attrs["units"]
        return out


class TwoAngles(SmallParameter):
    def euler_angles(self, system, t):
        angles = super().euler_angles(system, t)
        del angles["phi"]
        return angles


BODY = {"units": "nondimensional", "a": 2.0, "b": 1.5, "com_direction": [0.3, 0.2, 0.9327379053088815]}
INITIAL = {"p0": 0.1, "q0": -0.05, "r0": 5.0, "theta0": 1.0, "phi0": 1.57, "psi0": 0.0}


def test_integrator_kit_fails_on_wrong_shapes():
    with pytest.raises(AssertionError, match=r"^WrongShape: Solution\.t is .* not the requested t_out"):
        check_integrator(WrongShape)


def test_integrator_kit_fails_on_nan_instead_of_an_integration_error():
    with pytest.raises(AssertionError, match=r"^NaNOnBlowUp: on y' = y², y\(0\) = 1 \(blow-up at t = 1\) it returned "
                                             r"non-finite values"):
        check_integrator(NaNOnBlowUp)


@pytest.mark.parametrize("name, params", [("dop853", {}), ("rk45", {"rtol": 1e-8, "atol": 1e-8}), ("rk4", {}),
                                          ("lsoda", {}), ("radau", {"rtol": 1e-8, "atol": 1e-8}),
                                          ("bdf", {"rtol": 1e-8, "atol": 1e-8})])
def test_integrator_kit_passes_gyrolab_own(name, params):
    # lsoda looped forever on y' = y² (scipy's LSODA "succeeds" with a zero step); the kit found it
    check_integrator(registry.load("integrator", name), **params)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["dop853_numba", "rk4_numba", "taylor", "lie_poisson"])
def test_integrator_kit_checks_compiled_integrators_on_the_free_top(name):
    check_integrator(registry.load("integrator", name))  # numba's kernels: compiled once, cached for every test


def test_system_kit_fails_on_a_drifting_invariant():
    from gyrolab.plugins.forces.uniform_gravity import UniformGravity

    with pytest.raises(AssertionError, match=r"^DriftingEnergy: invariant 'energy' drifts by 2e-06"):
        check_system(DriftingEnergy, BODY, INITIAL, forces=[(UniformGravity, {})])
    check_system(FixedPoint, BODY, INITIAL, forces=[(UniformGravity, {})])  # the unbroken system passes


def test_system_kit_fails_on_a_compiled_model_that_is_not_its_rhs():
    from gyrolab.plugins.forces.uniform_gravity import UniformGravity
    from gyrolab.plugins.systems.fixed_point import traced_model

    class WrongCompiled(FixedPoint):
        name = "wrong_compiled"

        def compiled_model(self):  # the equations of another body: what a stale or hand-written model would be
            return traced_model(self.inertia * 1.01, self.forces, self.carries_alpha)

    with pytest.raises(AssertionError, match=r"^WrongCompiled: the compiled right-hand side .* differs from rhs"):
        check_system(WrongCompiled, BODY, INITIAL, forces=[(UniformGravity, {})])


def test_regime_kit_fails_when_the_solution_does_not_start_at_the_initial_state():
    with pytest.raises(AssertionError, match=r"^OffStart: solution\(system, \[0\]\) = .* differs from initial_state"):
        check_regime(OffStart)
    check_regime(SmallParameter)  # the unbroken regime passes


def test_regime_runs_from_the_command_line(installed, cli, tmp_path):
    done = cli("regime=steady_precession", "regime.branch=fast", *LAGRANGE_TOP, "initial.r0=5", "initial.theta0=2.5",
               "output.figures=false", "hydra.run.dir=out", env_extra={"PYTHONPATH": ":".join(installed)})
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "out" / "regime.nc") as ds:
        assert ds.attrs["regime"] == "steady_precession" and ds.attrs["regime_branch"] == "fast"
        assert ds.attrs["exact_orbit"] == "found"
        assert float(ds.max_error_vs_orbit.max()) < 1e-9   # Newton shooting lands on the analytic orbit
        assert float(ds.max_error_vs_full.max()) < 1e-7    # the scene's dop853 at its default rtol = 1e-10


@pytest.mark.parametrize("check, expected", [
    (lambda: check_integrator(Silent), r"^Silent: integrate never called progress\(t\)"),
    (lambda: check_integrator(Sloppy), r"^Sloppy: its error on the harmonic oscillator x'' = −x is .* above 1e-07"),
    (lambda: check_integrator(Unvalidated), r"^Unvalidated: integrator\.first_step='abc' was accepted"),
    (lambda: check_system(NoUnits, BODY, INITIAL), r"^NoUnits: variable 'theta' has no CF units"),
    (lambda: check_regime(TwoAngles), r"^TwoAngles: euler_angles\(system, t\) returned keys \['psi', 'theta'\]"),
])
def test_kits_name_the_rule_a_broken_plugin_violates(check, expected):
    with pytest.raises(AssertionError, match=expected):
        check()


def test_plugins_sweep_from_the_command_line(installed, cli, tmp_path):
    done = cli("-m", "body=rotor_body", "force=[]", "integrator=scipy_rk23", "integrator.rtol=1e-6,1e-8", "time.end=2",
               "time.n_output=21", "output.figures=false", "hydra.sweep.dir=sw",
               env_extra={"PYTHONPATH": ":".join(installed)})
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "sw" / "sweep.nc") as sweep:
        assert sweep.sizes["rtol"] == 2                                  # the swept key is a dimension
        assert sweep.kinetic_energy_max_abs_drift.dims == ("rtol",)      # the plugin system's invariants, per job
