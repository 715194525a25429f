"""The full equations of motion against physics: first integrals, closed forms, similarity.

Every expected number here comes from a physical law or a closed-form
solution (Euler–Poinsot in Jacobi elliptic functions, the Lagrange top's
steady precession from its Lagrangian), never from gyrolab itself.
"""

import numpy as np
import pytest
from scipy.special import ellipj

from gyrolab import run

TIGHT = ["integrator=dop853", "integrator.rtol=1e-12", "integrator.atol=1e-12"]


def test_invariants_conserved_to_ten_times_the_tolerance():
    ds = run([*TIGHT, "time.end=20", "time.n_output=401"])
    monitored = ds.attrs["monitored_invariants"].split()
    assert {"energy", "area_integral", "gamma_norm"} <= set(monitored)
    for name in monitored:
        scale = max(1.0, abs(float(ds[name][0])))
        assert ds[name].attrs["max_abs_drift"] / scale < 1e-11, name


def test_euler_poinsot_matches_jacobi_elliptic_closed_form():
    # Landau & Lifshitz, Mechanics §37: I1 < I2 < I3, M² > 2 E I2.
    I1, I2, I3 = 0.5, 0.8, 1.0
    p0, r0 = 1.0, 1.0
    E = 0.5 * (I1 * p0**2 + I3 * r0**2)
    M2 = (I1 * p0) ** 2 + (I3 * r0) ** 2
    assert M2 > 2 * E * I2
    ds = run([*TIGHT, "force=[]", "body.a=0.5", "body.b=0.8", "initial.p0=1", "initial.q0=0", "initial.r0=1",
              "time.end=30", "time.n_output=301"])
    t = ds.time.values
    rate = np.sqrt((I3 - I2) * (M2 - 2 * E * I1) / (I1 * I2 * I3))
    m = (I2 - I1) * (2 * E * I3 - M2) / ((I3 - I2) * (M2 - 2 * E * I1))
    sn, cn, dn, _ = ellipj(rate * t, m)
    expected = np.stack([
        np.sqrt((2 * E * I3 - M2) / (I1 * (I3 - I1))) * cn,
        np.sqrt((2 * E * I3 - M2) / (I2 * (I3 - I2))) * sn,
        np.sqrt((M2 - 2 * E * I1) / (I3 * (I3 - I1))) * dn,
    ], axis=1)
    assert np.max(np.abs(ds.omega.values - expected)) < 1e-9
    assert "energy" in ds.attrs["monitored_invariants"]  # no force: kinetic energy alone


@pytest.mark.parametrize("branch", [-1, +1])
def test_lagrange_top_steady_precession_rate(branch):
    # Symmetric top A = B, centre of mass on the axis, plus the Newtonian term N γ × Iγ.
    # From L = A(θ̇² + ψ̇² sin²θ)/2 + C ω3²/2 + Mgl cos θ − N(A sin²θ + C cos²θ)/2, θ = θ0 is
    # steady when A cos θ0 ψ̇² − C ω3 ψ̇ − (Mgl + N (A − C) cos θ0) = 0 (nondimensional: C = Mgl = 1).
    a, k, theta0, spin = 0.8, 0.5, 0.6, 4.0
    coeffs = [a * np.cos(theta0), -spin, -(1.0 + k * (a - 1.0) * np.cos(theta0))]
    rate = float(sorted(np.roots(coeffs).real)[0 if branch < 0 else 1])
    q0 = float(rate * np.sin(theta0))  # φ0 = 0: ω = ψ̇ γ + φ̇ e3
    ds = run([*TIGHT, "body=lagrange_top", f"force.newtonian.k={k}", "initial.p0=0", f"initial.q0={q0!r}",
              f"initial.r0={spin}", f"initial.theta0={theta0}", "initial.phi0=0", "time.end=20",
              "time.n_output=201"])
    assert np.max(np.abs(ds.theta.values - theta0)) < 1e-9
    assert np.max(np.abs(ds.psi.values - rate * ds.time.values)) < 1e-8 * max(1.0, abs(rate) * 20)


def test_si_run_equals_nondimensional_run_after_rescaling():
    c = float(np.sqrt(9.81 * 1.0 * 0.01 / 0.01))  # c² = M g l / C of body si_gyroscope
    common = [*TIGHT, "time.n_output=101", "force.newtonian.k=0.5"]
    nondim = run([*common, "time.end=10"])
    si = run([*common, "body=si_gyroscope", f"time.end={10 / c!r}", f"initial.p0={0.1 * c!r}",
              f"initial.q0={-0.05 * c!r}", f"initial.r0={5.0 * c!r}"])
    np.testing.assert_allclose(si.time.values * c, nondim.time.values, rtol=1e-14)
    np.testing.assert_allclose(si.omega.values / c, nondim.omega.values, atol=1e-9)
    np.testing.assert_allclose(si.gamma.values, nondim.gamma.values, atol=1e-9)
    assert si.attrs["body_nondim_a"] == pytest.approx(2.0)
    assert si.attrs["body_nondim_c2"] == pytest.approx(9.81)
    assert si.time.attrs["units"] == "s" and si.omega.attrs["units"] == "rad s-1"


def test_vertical_magnetic_field_is_a_weight_along_the_dipole():
    # m × (B γ) = (B m) × γ: a vertical field acts like gravity on a centre of mass along m.
    m = [0.3, 0.2, 0.9327379053088815]
    magnetic = run([*TIGHT, "force=[magnetic]", f"force.magnetic.moment={m}", "force.magnetic.field=1.0",
                    "time.end=10", "time.n_output=51"])
    gravity = run([*TIGHT, "force=[uniform_gravity]", "time.end=10", "time.n_output=51"])
    np.testing.assert_allclose(magnetic.omega.values, gravity.omega.values, atol=1e-9)
    assert magnetic.attrs["state_size"] == 9  # Euler angles requested; no extra state for the field


def test_horizontal_magnetic_field_conserves_momentum_about_the_field():
    # A field along X is symmetric about X: energy and L·X = Iω·α are conserved, Iω·γ is not.
    ds = run([*TIGHT, "force=[magnetic]", "force.magnetic.field=2.0", "force.magnetic.direction=[1,0,0]",
              "output.euler_angles=false", "time.end=20", "time.n_output=201"])
    assert ds.attrs["state_size"] == 9  # the field direction needs the fixed X axis, and only it
    assert ds.attrs["monitored_invariants"].split()[:1] == ["energy"]
    assert "area_integral" not in ds
    inertia = np.array([2.0, 1.5, 1.0])
    momentum_x = np.sum(inertia * ds.omega.values * ds.alpha.values, axis=1)
    assert np.ptp(momentum_x) < 1e-10
    momentum_z = np.sum(inertia * ds.omega.values * ds.gamma.values, axis=1)
    assert np.ptp(momentum_z) > 1e-2  # the vertical component really changes
