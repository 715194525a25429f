"""The plugin's own tests: gyrolab's contract kit, and the free symmetric top's exact solution."""

import numpy as np
import pytest

from gyrolab import run
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.testing import check_integrator
from gyrolab_scipy_rk23 import ScipyRK23


def test_contract():
    check_integrator(ScipyRK23)
    check_integrator(ScipyRK23, rtol=1e-10, atol=1e-12)


def test_declares_no_capabilities():
    assert ScipyRK23.capabilities == frozenset()      # no compiled model, no batch kernel


def test_bad_tolerance_is_one_sentence():
    with pytest.raises(ConfigError, match=r"^integrator\.rtol=-1 must be positive$"):
        ScipyRK23(rtol=-1)


def test_blow_up_is_an_integration_error():
    with pytest.raises(IntegrationError, match=r"^scipy_rk23 stopped near t=1"):
        ScipyRK23().integrate(lambda t, y: y * y, np.array([0.0, 2.0]), np.array([1.0]))


def test_free_symmetric_top():
    # A = B, no torque: I ω̇ = (Iω) × ω gives ṙ = 0, ṗ = −λ q, q̇ = λ p with λ = (C − A) r / A (here a = b = 0.8,
    # C = 1 in the nondimensional body, so λ = 0.25 r0): (p, q) turn at λ and r stays r0.
    a, p0, q0, r0 = 0.8, 0.1, -0.05, 5.0
    ds = run(["body=lagrange_top", "force=[]", "integrator=scipy_rk23", "integrator.rtol=1e-10",
              "integrator.atol=1e-12", f"initial.p0={p0}", f"initial.q0={q0}", f"initial.r0={r0}", "time.end=10",
              "time.n_output=101"])
    t = ds.time.values
    lam = (1.0 - a) * r0 / a
    expected = np.stack([p0 * np.cos(lam * t) - q0 * np.sin(lam * t), p0 * np.sin(lam * t) + q0 * np.cos(lam * t),
                         np.full_like(t, r0)], axis=1)
    np.testing.assert_allclose(ds.omega.values, expected, rtol=0, atol=1e-8)
    assert ds.attrs["integrator"] == "scipy_rk23" and ds.attrs["integrator_rtol"] == 1e-10
    assert ds.attrs["integrator_nfev"] > 0
