"""The orbiting gyrostat against independent evidence: Lagrange equations vs vector equations, Jacobi
integral, precession verdicts from residuals and integration (never copied from the paper), finder, bad input."""

import numpy as np
import pytest

from pipeline import compose_scene
from pipeline.errors import ConfigError
from pipeline.precession.cases import BY_LABEL, CASES
from pipeline.precession.finder import find_precessions
from pipeline.precession.motion import Precession, build_system, theta_deviation, vector_residual, window
from plugins.integrators.scipy_solvers import DOP853
from plugins.systems.gyrostat_euler import GyrostatParameters, kinematic_matrix, lagrange_equations

GYROSTAT = ["body=gyrostat_asymmetric", "initial=gyrostat_precession", "force=[newtonian,magnetic]",
            "force.newtonian.k=null"]


def test_euler_angle_equations_are_the_projected_vector_equations():
    # E(q, q̇, q̈) = Jᵀ R with R = I ω̇ − [(Iω + k) × ω + torques] from the system plugin (vector form).
    rng = np.random.default_rng(4)
    worst = 0.0
    for _ in range(50):
        p = GyrostatParameters(tuple(rng.uniform(0.5, 2, 3)), tuple(rng.normal(size=3)), tuple(rng.normal(size=3)),
                               (rng.normal(), 0.0, rng.normal()), rng.uniform(0.5, 2))
        system = build_system(p)
        q, qd, qdd = rng.uniform(0.2, 2.9, 3), rng.normal(size=3), rng.normal(size=3)
        th, ph = q[1], q[2]
        st, ct, sf, cf = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
        J = kinematic_matrix(th, ph)
        J_dot = np.array([[ct * sf * qd[1] + st * cf * qd[2], -sf * qd[2], 0.0],
                          [ct * cf * qd[1] - st * sf * qd[2], -cf * qd[2], 0.0], [-st * qd[1], 0.0, 0.0]])
        from pipeline.attitude import frame_from_angles
        alpha, _, gamma = frame_from_angles(*q)
        relative = J @ qd
        omega = relative + p.Omega * gamma
        omega_dot = J @ qdd + J_dot @ qd + p.Omega * np.cross(gamma, relative)
        f = system.derivative(np.concatenate([omega, alpha, gamma]))
        R = system.inertia * (omega_dot - f[0:3])
        worst = max(worst, np.max(np.abs(lagrange_equations(q, qd, qdd, p) - J.T @ R)))
    assert worst < 1e-12


def test_jacobi_integral_conserved_on_a_tumbling_motion():
    ds = compose_scene([*GYROSTAT, "force.magnetic.field=0.7", "force.magnetic.direction=[0.6,0,0.8]",
                        "initial.euler_rates0=[0.3,-0.4,1.1]", "integrator.rtol=1e-12", "integrator.atol=1e-12",
                        "time.end=31.4", "time.n_output=301", "output.figures=false"]).run()
    assert "jacobi_integral" in ds.attrs["monitored_invariants"]
    assert ds.jacobi_integral.attrs["max_abs_drift"] / abs(float(ds.jacobi_integral[0])) < 1e-10
    assert ds.frame_error.max() < 1e-10
    assert np.ptp(ds.theta.values) > 0.1  # a genuinely tumbling motion


@pytest.mark.parametrize("label", [c.label for c in CASES])
def test_case_verdict_from_vector_residual_and_integration(label):
    case = BY_LABEL[label]
    system = build_system(case.params, case.motion)
    residual = vector_residual(system, case.motion, window(system, 5.0, 501))
    failing = {"14.1", "14.2", "19.1L", "29.1"}  # printed sets whose residual does not vanish
    if label in failing:
        assert residual > 1e-2
        deviation = theta_deviation(system, case.motion, DOP853(rtol=1e-10, atol=1e-10), orbits=1, points=201)
        assert deviation["max_theta_deviation"] > 1e-2  # the integrated motion leaves the precession
    else:
        assert residual < 1e-10
        deviation = theta_deviation(system, case.motion, DOP853(rtol=1e-12, atol=1e-12), orbits=1, points=201)
        assert deviation["max_theta_deviation"] < 1e-6


@pytest.mark.parametrize("label, window_, fixed", [
    ("19.2", {"n": (-1.5, 1.5), "m": (-1.5, 1.5), "theta0": (0.0, np.pi)}, ("psi0",)),
    ("N2", {"n": (-1.5, 1.5), "m": (-1.5, 1.5), "theta0": (0.0, np.pi)}, ("psi0",)),
    ("17.2", {"n": (-1.0, 1.0), "m": (-2.0, 2.0)}, ("psi0", "theta0")),
    ("29.2", {"n": (0.1, 1.5), "m": (0.1, 1.5)}, ("psi0", "theta0")),
])
def test_finder_recovers_the_catalogue_case(label, window_, fixed):
    case = BY_LABEL[label]
    fixed_values = {k: getattr(case.motion, k) for k in fixed}
    found = find_precessions(case.params, window_, fixed_values, starts=16, samples=32)
    system = build_system(case.params, case.motion)
    t = np.linspace(0.0, 6.0, 7)
    from pipeline.precession.motion import states
    target = states(system, case.motion, t)[0]
    assert any(np.max(np.abs(states(build_system(s.params, s.motion), s.motion, t)[0] - target)) < 1e-7
               for s in found), [s.motion for s in found]
    assert all(s.residual < 1e-9 for s in found)


@pytest.mark.parametrize("overrides, words", [
    (["body.orbit_rate=0"], "body.orbit_rate=0"),
    (["body.orbit_rate=-1"], "body.orbit_rate=-1"),
    (["body.inertia=[1,1,3]"], "triangle"),
    (["initial.theta0=abc"], "initial.theta0"),
    (["initial.euler_rates0=[1,x,2]"], "initial.euler_rates0"),
])
def test_bad_input_is_one_sentence(overrides, words):
    with pytest.raises(ConfigError) as error:
        compose_scene([*GYROSTAT, *overrides])
    assert words in str(error.value) and "\n" not in str(error.value)


def test_precession_parameters_must_be_numbers():
    with pytest.raises(ConfigError, match="precession.n"):
        Precession.from_config({"n": "fast", "m": 1, "psi0": 0, "theta0": 1}, "precession")
