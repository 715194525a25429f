"""Capabilities instead of names (issue 21, item 4): a 20-line third-party integrator joins what it declares.

The integrator below (explicit midpoint rule, fixed step) is installed the way pip lays a distribution out, with a
``gyrolab.integrators`` entry point. It declares no batch kernel and no variational equations, so it runs single
scenes and ``--batch`` grids (one ``integrate`` call per point, the same numbers as its single runs), and the
chaos indicators refuse it in one sentence naming it, the capability and the integrators that have it. A last
test reads ``pipeline/`` and ``plugins/``: no built-in integrator's name is tested anywhere but in the registry's
table and in each integrator class's own ``name``.
"""

import ast
import textwrap
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from gyrolab import compose_scene
from gyrolab.batch.sweep import run_batch_sweep
from gyrolab.contracts import registry
from gyrolab.contracts.integrator import (
    BATCH_KERNEL,
    CAPABILITIES,
    CHOOSES_METHOD,
    ESTIMATES_ERROR,
    COMPILED_MODEL,
    PREFERS_COMPILED_MODEL,
    TIME_DEPENDENT,
    VARIATIONAL,
    VECTOR_LANES,
    Integrator,
    VariationalSettings,
)
from gyrolab.errors import ConfigError
from tests.conftest import installed_distribution
from tests.helpers import REPO


MIDPOINT = textwrap.dedent('''
    """Explicit midpoint rule with a fixed step: a third-party gyrolab integrator plugin."""
    import time

    import numpy as np

    from gyrolab.contracts import Force
    from gyrolab.contracts.integrator import COMPILED_MODEL, TIME_DEPENDENT, Integrator, IntegratorStats, Solution
    from gyrolab.errors import IntegrationError, as_number


    class Midpoint(Integrator):
        name = "midpoint"
        adaptive = False
        capabilities = frozenset({TIME_DEPENDENT})   # no batch kernel, no variational equations

        def __init__(self, *, step=0.01):
            self.step = as_number(step, "integrator.step", positive=True)

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            start, y, n = time.perf_counter(), np.array(y0, dtype=float), 0
            out = np.empty((len(t_out), len(y)))
            out[0] = y
            for i in range(1, len(t_out)):
                m = max(1, int(np.ceil((t_out[i] - t_out[i - 1]) / self.step)))
                h = (t_out[i] - t_out[i - 1]) / m
                for j in range(m):
                    t = t_out[i - 1] + j * h
                    y = y + h * fun(t + h / 2, y + h / 2 * fun(t, y))
                n += m
                if not np.all(np.isfinite(y)):
                    raise IntegrationError(f"midpoint became non-finite before t={t_out[i]:.6g}; reduce integrator.step")
                out[i] = y
            stats = IntegratorStats(nfev=2 * n, n_steps=n, n_rejected=0, wall_time=time.perf_counter() - start)
            return Solution(np.asarray(t_out, dtype=float), out, stats)

        def attributes(self):
            return {"integrator_step": self.step}


    class Picky(Midpoint):
        """A compiled-model integrator that refuses every model: the scene asks it, and lists the others."""
        name = "picky"
        capabilities = frozenset({COMPILED_MODEL})

        @classmethod
        def refusal(cls, compiled, system=None):
            return "refuses every compiled model, as a test"


    class Pulse(Force):
        """A torque about the body's z axis oscillating in time: a time-dependent force."""
        name = "pulse"
        required_axes = frozenset()
        time_dependent = True
        preserves_area_integral = False

        def __init__(self, body, *, amplitude=0.01):
            self.amplitude = float(amplitude)

        def torque(self, omega, axes, t):
            return np.array([0.0, 0.0, self.amplitude]) * np.cos(t)
''')
SHORT = ["time.end=2", "time.n_output=11", "output.euler_angles=false", "output.figures=false"]


@pytest.fixture(scope="module")
def midpoint(tmp_path_factory):
    """The site holding the plugin module and its .dist-info (its ``gyrolab.integrators`` entry points)."""
    site = tmp_path_factory.mktemp("site")
    (site / "midpoint_plugin.py").write_text(MIDPOINT)
    with installed_distribution(site, "gyrolab-midpoint", "0.1", {
            "gyrolab.integrators": {"midpoint": "midpoint_plugin:Midpoint", "picky": "midpoint_plugin:Picky"},
            "gyrolab.forces": {"pulse": "midpoint_plugin:Pulse"}}):
        yield site


def test_a_third_party_integrator_runs_a_single_scene(midpoint):
    ds = compose_scene(["integrator=midpoint", "integrator.step=0.001", *SHORT]).run()
    reference = compose_scene(["integrator=dop853", "integrator.rtol=1e-12", "integrator.atol=1e-12", *SHORT]).run()
    assert ds.attrs["integrator"] == "midpoint" and ds.attrs["integrator_step"] == 0.001
    np.testing.assert_allclose(ds.omega.values, reference.omega.values, atol=1e-4)   # second order, h = 1e-3
    assert "integrator_nfev_counts" not in ds.attrs   # its evaluations are right-hand-side calls


def test_a_third_party_integrator_joins_batch_with_its_single_runs_numbers(midpoint, tmp_path):
    """No batch kernel: one integrate() per point, in the runner's chunks; a point that fails is a failed entry."""
    step = ["integrator=midpoint", "integrator.step=0.05", "batch.chunk=2"]
    with np.errstate(over="ignore", invalid="ignore"):   # the failing point overflows on its way to the error
        path = run_batch_sweep([*step, *SHORT, "batch.output=trajectory", "initial.r0=1,2,500"], tmp_path / "b")
    with xr.open_dataset(path) as ds:
        assert ds.attrs["batch_path"] == "one integrate() call per point"
        assert ds.job_status.values.tolist() == [1, 1, 2]   # r0 = 500 with step 0.05 blows up
        assert "non-finite" in str(ds.error_message.values[ds.job_error.values[2]])
        for i, r0 in enumerate([1, 2]):
            single = compose_scene([*step, *SHORT, f"initial.r0={r0}"]).run()
            np.testing.assert_array_equal(ds.omega[i].values, single.omega.values)
            np.testing.assert_array_equal(ds.gamma[i].values, single.gamma.values)


def test_the_command_line_batch_runs_it_too(midpoint, cli, tmp_path):
    done = cli("--batch", "integrator=midpoint", "initial.r0=1,2", *SHORT, "hydra.sweep.dir=grid",
               env_extra={"PYTHONPATH": str(midpoint)})
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "grid" / "sweep.nc") as ds:
        single = compose_scene(["integrator=midpoint", *SHORT, "initial.r0=2"]).run()
        np.testing.assert_array_equal(ds.omega[1].values, single.omega[-1].values)


def test_the_chaos_indicators_refuse_it_in_one_sentence(midpoint, tmp_path, cli):
    sentence = ("integrator 'midpoint' has no variational equations (capability variational), which the chaos "
                "indicators of batch.output=indicator need; valid choices: rk4, rk4_numba, dop853 or dop853_numba")
    with pytest.raises(ConfigError) as refused:
        run_batch_sweep(["integrator=midpoint", "batch.output=indicator", "initial.r0=1,2"], tmp_path / "map")
    assert str(refused.value) == sentence
    done = cli("experiment=stability_map", "integrator=midpoint", "stability_map.n_theta0=2", "stability_map.n_r0=2",
               env_extra={"PYTHONPATH": str(midpoint)})
    assert done.returncode == 2 and sentence in done.stderr and done.stderr.count("valid choices") == 1
    from gyrolab.analysis.chaos import indicator_outputs

    scene = compose_scene(["integrator=midpoint", *SHORT])
    with pytest.raises(ConfigError, match=r"^integrator 'midpoint' has no variational equations .* dop853_numba$"):
        indicator_outputs(scene.system.compiled_model(), scene.integrator, [0.0, 1.0],
                          scene.system.initial_state()[None])


def test_declaring_variational_equations_joins_the_chaos_indicators():
    """VARIATIONAL with a fixed step: the indicators run the RK4 variational kernel, as for rk4 at that step."""
    from gyrolab.analysis.chaos import indicator_outputs

    class Stepper(Integrator):
        name, adaptive, capabilities = "stepper", False, frozenset({VARIATIONAL})

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            raise NotImplementedError

        def variational_settings(self):
            return VariationalSettings(step=0.02)

    scene = compose_scene(["integrator=rk4", "integrator.step=0.02", "time.end=5", "time.n_output=2"])
    y0 = scene.system.initial_state()[None]
    ours = indicator_outputs(scene.system.compiled_model(), Stepper(), scene.times, y0)
    theirs = indicator_outputs(scene.system.compiled_model(), scene.integrator, scene.times, y0)
    for key in theirs:
        np.testing.assert_array_equal(ours[key][0], theirs[key][0])


def test_the_scene_asks_a_compiled_integrator_whether_it_runs_the_model(midpoint):
    with pytest.raises(ConfigError, match=r"^integrator 'picky' refuses every compiled model, as a test; choose "
                                          r"rk4_numba, lie_poisson, dop853_numba, taylor or auto$"):
        compose_scene(["integrator=picky", *SHORT])


def test_time_dependent_forces_need_the_capability(midpoint):
    """The midpoint declares TIME_DEPENDENT and integrates a time-dependent force; lie_poisson does not: one sentence."""
    forced = compose_scene(["integrator=midpoint", "force=[uniform_gravity,pulse]", *SHORT]).run()
    free = compose_scene(["integrator=midpoint", "force=[uniform_gravity]", *SHORT]).run()
    assert not np.array_equal(forced.omega.values, free.omega.values)
    with pytest.raises(ConfigError) as refused:
        compose_scene(["integrator=lie_poisson", "force=[uniform_gravity,pulse]", *SHORT])
    assert str(refused.value) == ("integrator 'lie_poisson' does not integrate time-dependent forces (capability "
                                  "time_dependent) and force 'pulse' is one; valid choices: rk4, rk4_numba, midpoint, "
                                  "rk45, dop853, lsoda, radau, bdf, dop853_numba, taylor or auto")


def test_a_batch_kernel_hook_runs_through_integrate_arrays():
    """BATCH_KERNEL: integrate_arrays validates the arrays, calls the hook, and holds failures="raise" to its rule
    even for a kernel that only marks its failures."""
    from gyrolab.batch.integrate import integrate_arrays
    from gyrolab.errors import IntegrationError
    from gyrolab.plugins.integrators.compiled_solvers import RK4Numba

    class Marker(Integrator):
        name, adaptive, capabilities = "marker", False, frozenset({COMPILED_MODEL, BATCH_KERNEL})

        def integrate(self, fun, t_out, y0, progress=None, compiled=None):
            raise NotImplementedError

        def integrate_batch(self, compiled, times, y0s, params, failures):
            solution = RK4Numba(step=0.01).integrate_batch(compiled, times, y0s, params, "mark")
            solution.failed = np.arange(len(y0s)) == 1   # pretend the second trajectory failed
            return solution

    scene = compose_scene(["integrator=rk4_numba", *SHORT])
    y0s = np.stack([scene.system.initial_state()] * 3)
    marked = integrate_arrays(scene.compiled, Marker(), scene.times, y0s, failures="mark")
    np.testing.assert_array_equal(marked.y, integrate_arrays(scene.compiled, scene.integrator, scene.times, y0s).y)
    with pytest.raises(IntegrationError, match="^trajectory 1 of the batch failed with marker$"):
        integrate_arrays(scene.compiled, Marker(), scene.times, y0s)


def test_an_unknown_capability_is_refused():
    with pytest.raises(ValueError, match="valid: compiled_model"):
        Integrator.supports("batch")


BUILTIN_CAPABILITIES = {
    "rk4": {TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL},
    "rk4_numba": {COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL},
    "dop853": {TIME_DEPENDENT, VARIATIONAL},
    "dop853_numba": {COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, VARIATIONAL},
    "taylor": {COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, ESTIMATES_ERROR},
    "lie_poisson": {COMPILED_MODEL},
    "auto": {PREFERS_COMPILED_MODEL, TIME_DEPENDENT, BATCH_KERNEL, VECTOR_LANES, CHOOSES_METHOD},
    **{name: {TIME_DEPENDENT} for name in ("rk45", "lsoda", "radau", "bdf")},
}


def test_the_built_ins_declare_what_docs_plugins_md_lists():
    """The table of docs/plugins.md ("Integrator capabilities") is each built-in's declaration."""
    assert {n: set(registry.load("integrator", n).capabilities) for n in BUILTIN_CAPABILITIES} == \
        BUILTIN_CAPABILITIES
    docs = (REPO / "docs" / "plugins.md").read_text()
    section = docs[docs.index("## Integrator capabilities"):]
    for capability in CAPABILITIES:
        row = next(line for line in section.splitlines() if line.startswith(f"| `{capability.upper()}`"))
        listed = {n.strip(" `") for n in row.split("|")[-2].split(",") if n.strip()}
        assert listed == {n for n, caps in BUILTIN_CAPABILITIES.items() if capability in caps}, capability


def test_figures_read_what_an_evaluation_counts_from_the_runs():
    from gyrolab.figures.evaluations import nfev_notes

    recorded = xr.Dataset(attrs={"integrator": "midpoint", "integrator_nfev_counts": "stage evaluations"})
    assert nfev_notes(recorded) == {"midpoint": "stage evaluations"}
    per_job = xr.Dataset({"run_integrator": ("k", ["rk4", "taylor"]),
                          "integrator_nfev_counts": ("k", ["", "Taylor series evaluations"])})
    assert nfev_notes(per_job) == {"taylor": "Taylor series evaluations"}
    older = xr.Dataset(coords={"integrator": ["rk4", "lie_poisson"]})   # before runs recorded it: the classes say
    assert nfev_notes(older) == {"lie_poisson": "exact sub-flow evaluations"}


# -- no name tests left -------------------------------------------------------------------------------------------

BUILTIN_NAMES = frozenset(registry.BUILTINS["integrator"])
#: config keys whose value may be the word ``auto`` (not the integrator): ``time.n_output: auto``, ``batch.chunk: auto``
AUTO_VALUED_KEYS = ("n_output", "chunk")


def _name_literals(path: Path) -> list[str]:
    """``file:line: code`` of every string constant in ``path`` that is exactly a built-in integrator's name, except:

    * an integrator class's own ``name = "..."`` (the name it is registered under: that is what a name is);
    * ``"auto"`` on a statement about a config key whose value may be the word auto (``AUTO_VALUED_KEYS``), or as
      the value of ``engine/scene.py``'s ``AUTO`` (``time.n_output: auto``): a config word, not the integrator.

    Docstrings and comments never match (a docstring is not exactly a name; comments are not constants). Substrings
    do not count either: an integrator's own error message may start with its name ("taylor's step fell ...").
    """
    source = path.read_text()
    lines = source.splitlines()
    tree = ast.parse(source)
    allowed: set[int] = set()   # ids of constants that are allowed
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            for statement in node.body:
                if isinstance(statement, ast.Assign) and [getattr(t, "id", None) for t in statement.targets] == ["name"]:
                    allowed.add(id(statement.value))
        elif isinstance(node, ast.Assign) and [getattr(t, "id", None) for t in node.targets] == ["AUTO"]:
            allowed.add(id(node.value))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value in BUILTIN_NAMES and id(node) not in allowed:
            statement = lines[node.lineno - 1]
            if node.value == "auto" and any(key in statement for key in AUTO_VALUED_KEYS):
                continue
            found.append(f"{path.relative_to(REPO)}:{node.lineno}: {statement.strip()}")
    return found


def test_no_built_in_integrator_name_is_tested_outside_the_registry_and_the_classes():
    registry_table = REPO / "pipeline" / "contracts" / "registry.py"
    files = [p for folder in ("pipeline", "plugins") for p in sorted((REPO / folder).rglob("*.py")) if p != registry_table]
    found = [hit for path in files for hit in _name_literals(path)]
    assert not found, "built-in integrator names outside the registry and the classes' name:\n" + "\n".join(found)
    # the check itself sees what it must see
    probe = Path(__file__)
    assert any('"taylor"' in hit for hit in _name_literals(probe))
