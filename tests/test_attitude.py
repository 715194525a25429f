"""Euler angles from direction cosines: exact round trips, including the degenerate attitudes."""

import numpy as np
import pytest

from gyrolab.physics.attitude import euler_angles, frame_from_angles, gamma_from_angles


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
