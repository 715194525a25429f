"""Newton shooting for exact periodic orbits: quadratic convergence, Floquet multipliers, the research's numbers."""

import numpy as np

from gyrolab.analysis.periodic import FixedPointModel, shoot

# Seed 001 report §9: B1 body at μ = 0.1 (r0 = √0.8/0.1): exact period 0.70318806/c and
# initial state (0.0310965218, 0.0380844784, 8.94427191, 0.6, 0, 0.8) found by an independent
# DOP853 shooting (docs/derivations/scripts/seed001/fullmodel.py).
MODEL = FixedPointModel(np.array([0.4, 1 / 7, 1.0]), np.array([0.48, 0.36, 0.8]), 1.0)
R0 = np.sqrt(0.8) / 0.1


def test_shooting_converges_quadratically_to_the_independent_orbit():
    # start 1e-3 away from the orbit in p, q and the period
    guess = np.array([0.0300965218, 0.0390844784, R0, 0.6, 0.0, 0.8])
    orbit = shoot(MODEL, guess, 0.70418806)
    e = np.array(orbit.residuals)
    assert e[-1] < 1e-13
    # quadratic convergence: C_k = e_{k+1}/e_k² stays bounded while e_k falls by orders of magnitude
    # (linear convergence would make C_k grow like 1/e_k)
    # (steps starting above the rounding floor; one that lands on the floor only makes C_k smaller)
    start = np.flatnonzero(e[:-1] > 1e-12)
    C = e[start + 1] / e[start] ** 2
    assert len(C) >= 3
    assert e[start[-1]] / e[start[-2]] < 1e-2  # the step before gained at least two digits
    assert C[-1] / C[-2] < 3, C
    assert C[-1] < 1e4
    np.testing.assert_allclose(orbit.y0[:2], [0.0310965218, 0.0380844784], atol=2e-9)
    assert abs(orbit.period - 0.70318806) < 1e-8


def test_floquet_multipliers_of_a_conservative_orbit():
    orbit = shoot(MODEL, np.array([0.0310965218, 0.0380844784, R0, 0.6, 0.0, 0.8]), 0.70318806)
    m = orbit.multipliers
    # three first integrals and the flow direction give multipliers 1; the product is det Φ = 1 (volume)
    assert abs(np.prod(m) - 1) < 1e-8
    assert np.sum(np.abs(m - 1) < 1e-5) >= 4
    # symplectic pairing: the set is closed under λ → 1/λ
    for lam in m:
        assert np.min(np.abs(m - 1 / lam)) < 1e-6


def test_monodromy_against_finite_differences():
    y0 = np.array([0.0310965218, 0.0380844784, R0, 0.6, 0.0, 0.8])
    _, phi = MODEL.flow(y0, 0.5)
    h = 1e-6
    fd = np.column_stack([(MODEL.flow(y0 + h * e, 0.5)[0] - MODEL.flow(y0 - h * e, 0.5)[0]) / (2 * h)
                          for e in np.eye(6)])
    np.testing.assert_allclose(phi, fd, atol=1e-6 * np.abs(fd).max())
