"""The orbiting gyrostat under the compiled integrators: its kernels are generated from its traced equations
(``gyrolab.kernels.model``), so they are checked against an oracle written separately — the paper's Lagrange
equations in Euler angles (``physics.gyrostat_euler``: other coordinates, other formulas), integrated by scipy at
tight tolerance — and against the Jacobi integral, a law of the system."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gyrolab import compose_scene
from gyrolab.analysis.precession.motion import build_system
from gyrolab.kernels import model
from gyrolab.physics.attitude import frame_from_angles
from gyrolab.physics.gyrostat_euler import GyrostatParameters, kinematic_matrix, rhs_euler_angles
from tests.helpers.taylor import single_kernel_runs

# an asymmetric gyrostat with rotors and a tilted magnetic field, tumbling (θ stays away from 0 and π, where the
# Euler angles are singular)
PARAMS = GyrostatParameters((1.0, 1.4, 1.9), (0.1, -0.2, 0.4), (0.3, 0.0, 0.9), (0.5, 0.0, -0.6), 1.0)
ANGLES, RATES = np.array([0.2, 1.1, 0.4]), np.array([0.3, -0.2, 1.2])
TIMES = np.linspace(0.0, 8.0, 41)


def _oracle() -> np.ndarray:
    """(ω, α, γ) at TIMES from the Euler-angle equations, scipy DOP853 at rtol 1e-13."""
    sol = solve_ivp(rhs_euler_angles, (TIMES[0], TIMES[-1]), np.concatenate([ANGLES, RATES]), args=(PARAMS,),
                    method="DOP853", rtol=1e-13, atol=1e-13, t_eval=TIMES)
    rows = []
    for psi, theta, phi, *rates in sol.y.T:
        alpha, _, gamma = (np.asarray(v) for v in frame_from_angles(psi, theta, phi))
        omega = kinematic_matrix(theta, phi) @ np.asarray(rates) + PARAMS.Omega * gamma
        rows.append(np.concatenate([omega, alpha, gamma]))
    return np.array(rows)


@pytest.fixture(scope="module")
def setup():
    system = build_system(PARAMS)
    alpha, _, gamma = (np.asarray(v) for v in frame_from_angles(*ANGLES))
    omega = kinematic_matrix(ANGLES[1], ANGLES[2]) @ RATES + PARAMS.Omega * gamma
    return system, np.concatenate([omega, alpha, gamma]), _oracle()


@pytest.mark.parametrize("integrator, settings, tolerance", [
    ("taylor", {"tol": 1e-15}, 1e-10),
    ("dop853_numba", {"rtol": 1e-12, "atol": 1e-12}, 1e-9),
    ("rk4_numba", {"step": 2e-3}, 1e-8),
])
def test_compiled_gyrostat_follows_the_euler_angle_equations(setup, integrator, settings, tolerance):
    system, y0, expected = setup
    compiled = system.compiled_model()
    assert compiled is not None
    scene = compose_scene([f"integrator={integrator}", *[f"integrator.{k}={v}" for k, v in settings.items()]])
    got = scene.integrator.integrate(system.rhs, TIMES, y0, None, compiled).y
    assert np.max(np.abs(got - expected)) < tolerance
    jacobi = system.jacobi_integral(got)
    assert np.max(np.abs(jacobi - jacobi[0])) < tolerance


def test_generated_right_hand_side_is_the_python_one_bit_for_bit(setup):
    """The generated kernel performs the Python right-hand side's operations in the same order: the same doubles."""
    import ctypes

    system, _, _ = setup
    compiled = system.compiled_model()
    kernel = ctypes.CFUNCTYPE(None, ctypes.c_double, *[ctypes.POINTER(ctypes.c_double)] * 3)(
        int(compiled.params[model.TRACED_ADDRESS]))
    ptr = ctypes.POINTER(ctypes.c_double)
    rng = np.random.default_rng(7)
    for _ in range(20):
        y = rng.normal(size=9)
        out = np.empty(9)
        kernel(0.0, y.ctypes.data_as(ptr), compiled.params.ctypes.data_as(ptr), out.ctypes.data_as(ptr))
        np.testing.assert_array_equal(out, system.rhs(0.0, y))


def test_gyrostat_scene_runs_under_taylor_with_its_invariants():
    ds = compose_scene(["experiment=gyrostat", "integrator=taylor", "time.end=10", "output.figures=false"]).run()
    assert ds.attrs["integrator"] == "taylor"
    assert float(ds.frame_error.max()) < 1e-12
    assert ds.jacobi_integral.attrs["max_abs_drift"] < 1e-12


def test_an_untraceable_system_is_refused_in_one_sentence_naming_the_construct():
    from gyrolab.contracts.system import System

    class Branching(System):
        name = "branching"
        body_type = object
        state_size = 1
        invariants = ()

        def initial_state(self):
            return np.ones(1)

        def rhs(self, t, y):
            return -y if y[0] > 0 else y

        def variables(self, t, y):
            return {}

    system = Branching(None, [], {}, {})
    assert system.compiled_model() is None
    assert "cannot be compiled" in system.compile_error and "compiled code cannot branch" in system.compile_error


def test_double_double_gyrostat_keeps_the_jacobi_integral_beyond_double_precision(setup):
    """The generated double-double series (``series_dd``): the Jacobi integral of the double-double state (high +
    low parts, evaluated in long double) stays constant far below double precision's 1e-16 — a law of the system,
    which no double-precision run can show."""
    from gyrolab.kernels import taylor_dd
    from gyrolab.plugins.integrators.compiled_solvers import _ready_for_double_double

    system, y0, expected = setup
    compiled = system.compiled_model()
    _ready_for_double_double(compiled)
    hi, lo = taylor_dd.propagate(compiled.params, 1e-30, TIMES, y0)
    assert np.max(np.abs(hi - expected)) < 1e-10  # the same motion as the Euler-angle oracle
    y = hi.astype(np.longdouble) + lo.astype(np.longdouble)
    if np.finfo(np.longdouble).eps > 1e-18:
        pytest.skip("numpy.longdouble is plain double on this platform")
    inertia, k, omega_rate = (np.asarray(v, dtype=np.longdouble) for v in (system.inertia, system.k, system.Omega))
    omega, alpha, gamma = y[:, 0:3], y[:, 3:6], y[:, 6:9]
    potential = system.potential(y.astype(float))  # the potential's own drift is checked on the kinetic part below
    kinetic = 0.5 * np.sum(omega * inertia * omega, axis=1) - omega_rate * np.sum(gamma * (inertia * omega + k), axis=1)
    # the magnetic and gradient potentials are polynomial in α, γ: evaluate them in long double too
    N = 3 * omega_rate ** 2
    gradient = 0.5 * N * np.sum(alpha * inertia * alpha, axis=1)
    magnetic = next(f for f in system.forces if f.name == "magnetic")
    h = np.asarray(-magnetic.field * magnetic.direction, dtype=np.longdouble)  # V = +μ·(h1 α + h2 β + h3 γ)
    mu = np.asarray(magnetic.moment, dtype=np.longdouble)
    beta = np.cross(gamma, alpha)
    field = h[0] * alpha + h[1] * beta + h[2] * gamma
    jacobi = kinetic + gradient + np.sum(mu * field, axis=1)
    assert np.allclose(np.asarray(jacobi, dtype=float) - np.asarray(jacobi[0], dtype=float),
                       potential - potential[0] + (np.asarray(kinetic, dtype=float) - float(kinetic[0])), atol=1e-12)
    assert np.max(np.abs(jacobi - jacobi[0])) < 1e-18


@pytest.mark.parametrize("integrator", ["rk4_numba", "rk4", "dop853", "taylor integrator.tol=1e-9"])
def test_gyrostat_error_estimate_measures_the_actual_error(integrator):
    """The stored estimate against the actual error (the double-double Taylor run as the reference), within the
    docs' factor 2 — also when the outputs are closer than half the step (rk4: both runs once took one step per
    interval, an estimate of 0)."""
    common = ["experiment=gyrostat", "time.end=6", "time.n_output=1201", "output.figures=false"]
    ds = compose_scene([*common, *f"integrator={integrator}".split(), "output.error_estimate=true"]).run()
    reference = compose_scene([*common, "integrator=taylor", "integrator.precision=double-double",
                               "integrator.tol=1e-24"]).run()
    actual = float(np.abs(ds.omega - reference.omega).max())
    estimate = float(ds.attrs["error_estimate_max_omega"])
    assert actual > 1e-13  # a measurable error (not round-off), so the ratio says something
    assert 0.5 <= estimate / actual <= 2.0


def test_a_gyrostat_stability_map_runs_from_its_generated_tangent_flow(cli, tmp_path):
    """``experiment=stability_map`` on the orbiting gyrostat: MEGNO from the generated tangent flow, no Poincaré
    sections (the heavy body's), the figure drawn without the heavy body's regimes and with the gyrostat's rate
    unit."""
    import xarray as xr

    done = cli("experiment=stability_map", "system=orbiting_gyrostat", "body=gyrostat_symmetric",
               "initial=gyrostat_precession", "force=[newtonian,magnetic]", "force.newtonian.k=null",
               "initial.euler_rates0=null", "initial.p0=0", "initial.q0=0", "stability_map.n_theta0=3",
               "stability_map.n_r0=3", "stability_map.r0=[0.5,3]", "time.end=30", "hydra.run.dir=map")
    assert done.returncode == 0, done.stderr
    with xr.open_dataset(tmp_path / "map" / "stability_map.nc") as ds:
        assert np.all(np.isfinite(ds.indicator.values)) and "section_phi" not in ds
        assert np.all(ds.indicator.values > 0.5)  # MEGNO of these motions: regular (≈ 2) or above
    assert (tmp_path / "map" / "figures" / "stability_map.png").stat().st_size > 10_000


def test_gyrostat_batch_runs_by_vector_lanes_against_the_euler_angle_equations(setup):
    """``taylor``'s batch on the gyrostat runs the lanes generated from its traced equations (``batch_taylor``): a
    batch of copies of the oracle's start follows the Euler-angle equations within 1e-10 in every lane, and a
    batch of perturbed starts takes the single-trajectory kernel's steps, its outputs within 1e-13 of it."""
    from gyrolab.batch.integrate import integrate_arrays
    from gyrolab.kernels import batch_taylor

    system, y0, expected = setup
    compiled = system.compiled_model()
    scene = compose_scene(["integrator=taylor", "integrator.tol=1e-15"])
    count = batch_taylor.LANES + 3
    copies = integrate_arrays(compiled, scene.integrator, TIMES, np.tile(y0, (count, 1)))
    assert np.max(np.abs(copies.y - expected[None])) < 1e-10
    rng = np.random.default_rng(5)
    y0s = np.tile(y0, (count, 1))
    y0s[:, 0:3] += rng.normal(scale=0.1, size=(count, 3))
    batch = integrate_arrays(compiled, scene.integrator, TIMES, y0s)
    out, steps = single_kernel_runs(compiled, np.tile(compiled.params, (count, 1)), scene.integrator, TIMES, y0s)
    np.testing.assert_array_equal(batch.steps, steps)
    np.testing.assert_allclose(batch.y, out, rtol=0, atol=1e-13)
