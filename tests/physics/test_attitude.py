"""Euler angles from direction cosines: exact round trips, including the degenerate attitudes."""

import numpy as np
import pytest

from gyrolab.physics.attitude import euler_angles, frame_from_angles, gamma_from_angles, unwrap


def _angles_of(psi, theta, phi):
    alpha, _, gamma = frame_from_angles(psi, theta, phi)
    return [float(x[0]) for x in euler_angles(alpha[None], gamma[None])]


@pytest.mark.parametrize("theta", [0.3, 1.0, np.pi / 2, 2.0, 3.0])
def test_round_trip_generic(theta):
    rng = np.random.default_rng(1)
    for psi, phi in rng.uniform(-3.1, 3.1, size=(20, 2)):
        got = _angles_of(psi, theta, phi)
        np.testing.assert_allclose(got, [psi, theta, phi], atol=1e-13)


@pytest.mark.parametrize("theta", [1e-9, 1e-12, np.pi - 1e-9])
def test_near_degenerate_nutation_keeps_all_angles(theta):
    # atan2 on well-conditioned combinations: relative accuracy in θ, absolute in ψ and φ.
    psi, phi = 0.7, -1.2
    got_psi, got_theta, got_phi = _angles_of(psi, theta, phi)
    assert got_theta == pytest.approx(theta, rel=1e-7, abs=1e-15)
    assert got_phi == pytest.approx(phi, abs=1e-6)
    assert got_psi == pytest.approx(psi, abs=1e-6)


def test_exactly_vertical_axis_gives_the_sum_of_the_angles():
    psi, phi = 0.7, 0.4
    got_psi, got_theta, got_phi = _angles_of(psi, 0.0, phi)
    assert got_theta == 0.0
    assert got_psi + got_phi == pytest.approx(psi + phi, abs=1e-14)


def test_unwrapping_follows_a_continuous_rotation():
    t = np.linspace(0, 20, 2001)
    frames = [frame_from_angles(0.3 * s, 0.8, 2.0 * s) for s in t]
    alpha = np.array([f[0] for f in frames])
    gamma = np.array([f[2] for f in frames])
    psi, theta, phi = euler_angles(alpha, gamma)
    np.testing.assert_allclose(psi, 0.3 * t, atol=1e-12)
    np.testing.assert_allclose(phi, 2.0 * t, atol=1e-12)


def test_gamma_convention_of_the_papers():
    # γ = (sin θ sin φ, sin θ cos φ, cos θ) (Leimanis; seeds 000–002)
    np.testing.assert_allclose(gamma_from_angles(np.pi / 2, np.pi / 2), [1.0, 0.0, 0.0], atol=1e-16)


@pytest.mark.parametrize("pole, initial", [(np.pi, "upright"), (0.0, "hanging")])
def test_the_combination_defined_at_a_pole_stays_continuous_through_it(pole, initial):
    # A sleeping top nudged off its pole (issue 22): the trajectory passes close to the pole many times, where φ and
    # ψ each turn by ~π between samples. Only ψ − φ (θ = π) or ψ + φ (θ = 0) is defined there; it must be
    # continuous and equal the angle read directly from the fixed axes (Leimanis: atan2 of α, β components,
    # unwrapped on its own: a smooth angle, so np.unwrap is trustworthy for it).
    from gyrolab import run

    overrides = ["body=lagrange_top", "initial.p0=0.5", "integrator=taylor", "time.end=10", "time.n_output=10001"]
    if initial == "upright":
        overrides.insert(1, "initial=upright")
    else:
        overrides += ["initial.theta0=1e-3", "initial.r0=0.0"]
    ds = run(overrides)
    psi, theta, phi = ds.psi.values, ds.theta.values, ds.phi.values
    assert np.abs(theta - pole).max() < 0.5  # the run stays near the pole the test is about
    alpha, gamma = ds.alpha.values, ds.gamma.values
    beta = np.cross(gamma, alpha)
    if pole == 0.0:
        combination = psi + phi
        direct = np.unwrap(np.arctan2(beta[:, 0] - alpha[:, 1], alpha[:, 0] + beta[:, 1]))
    else:
        combination = psi - phi
        direct = np.unwrap(np.arctan2(beta[:, 0] + alpha[:, 1], alpha[:, 0] - beta[:, 1]))
    offset = combination[0] - direct[0]
    assert abs(offset / (2 * np.pi) - round(offset / (2 * np.pi))) < 1e-9
    np.testing.assert_allclose(combination - offset, direct, atol=1e-9)
    assert np.abs(np.diff(combination)).max() < 0.1


def test_unwrap_is_numpys_bit_for_bit():
    # numpy's np.unwrap is the definition: wrapped rotations at every speed (a step of exactly ±π, where numpy picks
    # the sign by the step's, and steps of many turns among them), no jump at all, one sample
    rng = np.random.default_rng(3)
    for rate in (0.01, 0.5, 3.0, 40.0):
        angle = np.angle(np.exp(1j * np.cumsum(rng.uniform(-rate, rate, 2001))))
        np.testing.assert_array_equal(unwrap(angle), np.unwrap(angle))
    edges = np.array([0.0, np.pi, 0.0, -np.pi, 0.0, 3 * np.pi, -2.5, 2.5, 7.0, -7.0])
    np.testing.assert_array_equal(unwrap(edges), np.unwrap(edges))
    for flat in (np.linspace(0.0, 1.0, 50), np.array([2.0])):
        np.testing.assert_array_equal(unwrap(flat), np.unwrap(flat))
