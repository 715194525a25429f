"""The extended-precision reference (``gyrolab.physics.reference``) carrying the fixed X axis α beside (ω, γ)."""

import numpy as np

from gyrolab.physics.reference import fixed_point_reference

INERTIA, WEIGHT, N = [2.0, 1.5, 1.0], [0.3, 0.2, 0.9327379053088815], 0.5


def test_alpha_rotates_rigidly_with_gamma_and_leaves_omega_gamma_unchanged():
    theta = 1.0
    gamma0 = [np.sin(theta), 0.0, np.cos(theta)]
    alpha0 = [np.cos(theta), 0.0, -np.sin(theta)]  # orthogonal to γ0, unit
    times = np.linspace(0.0, 20.0, 41)
    without = fixed_point_reference(INERTIA, WEIGHT, N, [0.1, -0.05, 5.0, *gamma0], times)
    with_alpha = fixed_point_reference(INERTIA, WEIGHT, N, [0.1, -0.05, 5.0, *gamma0, *alpha0], times)
    # α is read by no torque: (ω, γ) bit for bit, the same steps
    np.testing.assert_array_equal(with_alpha[:, :6], without)
    gamma, alpha = with_alpha[:, 3:6], with_alpha[:, 6:9]
    # the body sees a rigid rotation of the fixed frame: |α| = 1 and α·γ = 0 are kept (to extended precision)
    assert np.max(np.abs(np.sum(alpha * alpha, axis=1) - 1)) < 1e-16
    assert np.max(np.abs(np.sum(alpha * gamma, axis=1))) < 1e-16
    assert np.ptp(alpha[:, 0]) > 0.1  # (it moves)
