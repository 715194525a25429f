"""The tangent flow generated from a model's traced equations (``gyrolab.kernels.tangent``): its directional
derivative against central differences of the Python right-hand side (an independent computation), and its chaos
indicators against laws: MEGNO → 2 on the quasi-periodic motions of an integrable body (Cincotta & Simó 2000),
and growth on the docs' chaotic top, for the fixed point and the orbiting gyrostat alike."""

import ctypes

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.analysis import chaos
from gyrolab.kernels import model, tangent
from gyrolab.plugins.systems.fixed_point import traced_model

GYROSTAT = ["experiment=gyrostat", "body=gyrostat_asymmetric", "force.magnetic.field=0.7",
            "force.magnetic.direction=[0.6,0,0.8]", "initial.euler_rates0=[0.3,-0.4,1.1]"]


def _rhs_kernel(compiled):
    kernel = ctypes.CFUNCTYPE(None, ctypes.c_double, *[ctypes.POINTER(ctypes.c_double)] * 3)(
        int(compiled.params[model.TRACED_ADDRESS]))
    ptr = ctypes.POINTER(ctypes.c_double)

    def f(z, p):
        out = np.empty(len(z))
        kernel(1.0, np.ascontiguousarray(z).ctypes.data_as(ptr), p.ctypes.data_as(ptr), out.ctypes.data_as(ptr))
        return out
    return f


@pytest.mark.parametrize("overrides", [["integrator=dop853_numba", "force=[uniform_gravity,newtonian]"], GYROSTAT],
                         ids=["fixed_point", "gyrostat"])
def test_generated_tangent_is_the_derivative_of_the_right_hand_side(overrides):
    scene = compose_scene(overrides)
    system = scene.system
    compiled = (traced_model(system.inertia, system.forces, system.carries_alpha) if system.name == "fixed_point"
                else system.compiled_model())
    augmented = tangent.compiled_megno(compiled)
    f = _rhs_kernel(augmented)
    P = tangent.megno_params(augmented, compiled.params)[0]
    rng = np.random.default_rng(3)
    n = system.state_size
    for _ in range(10):
        x, u = rng.normal(size=n), rng.normal(size=n)
        u /= np.linalg.norm(u)
        z = np.concatenate([x, u, [0.0, 0.0, 0.0]])
        rates = f(z, P)
        np.testing.assert_allclose(rates[:n], system.rhs(1.0, x), rtol=1e-13, atol=1e-13)
        eps = 1e-6
        central = (system.rhs(1.0, x + eps * u) - system.rhs(1.0, x - eps * u)) / (2 * eps)
        lam = float(u @ central)
        np.testing.assert_allclose(rates[2 * n], lam, rtol=1e-6, atol=1e-8)   # ℓ' = u·Ju
        np.testing.assert_allclose(rates[n:2 * n], central - lam * u, rtol=1e-6, atol=1e-8)


def _megno(overrides, t_end):
    scene = compose_scene([*overrides, "integrator=dop853_numba", "integrator.rtol=1e-10", "integrator.atol=1e-10",
                           f"time.end={t_end}", "output.euler_angles=false"])
    system = scene.system
    compiled = (traced_model(system.inertia, system.forces, False) if system.name == "fixed_point"
                else system.compiled_model())
    times = np.linspace(0.0, t_end, 401)
    run = chaos.megno_run(compiled, scene.integrator, times, system.initial_state()[None, :])
    return run


def test_megno_of_an_integrable_top_tends_to_two():
    run = _megno(["body=lagrange_top", "initial.theta0=1.0", "initial.r0=3"], 400.0)
    assert not run["failed"][0]
    assert abs(run["megno"][0, -1] - 2.0) < 0.25


def test_megno_separates_the_docs_chaotic_top_from_a_fast_regular_one():
    chaotic = _megno(["initial.p0=0.3", "initial.q0=-0.2", "initial.r0=2"], 200.0)
    regular = _megno(["initial.r0=20"], 200.0)
    assert chaotic["megno"][0, -1] > 5.0 and chaotic["fli"][0] > 10.0
    assert regular["megno"][0, -1] < 2.5


def test_gyrostat_megno_runs_from_its_generated_tangent_flow():
    run = _megno(GYROSTAT, 60.0)
    assert not run["failed"][0] and np.isfinite(run["megno"][0, -1]) and np.isfinite(run["max_nutation_deviation"][0])
