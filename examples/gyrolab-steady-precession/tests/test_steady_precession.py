"""The plugin's own tests: gyrolab's contract kit, and the regular precession against the full model."""

import numpy as np
import pytest

from gyrolab import compose_scene
from gyrolab.errors import ConfigError
from gyrolab.testing import check_regime
from gyrolab_steady_precession import SteadyPrecession

LAGRANGE_TOP = ["body=lagrange_top", "force=[uniform_gravity]", "initial.phi0=1.5707963267948966"]
#: the same kind of top in SI units (A = B = 0.02 kg m², C = 0.01 kg m², M g ℓ = 0.0981 N m): c = √(Mgℓ/C) ≠ 1
SI_TOP = ["body=si_gyroscope", "body.inertia=[0.02,0.02,0.01]", "body.com=[0,0,0.01]", "force=[uniform_gravity]",
          "initial.phi0=1.5707963267948966"]


def test_contract():
    check_regime(SteadyPrecession, scene=LAGRANGE_TOP)
    check_regime(SteadyPrecession, scene=[*LAGRANGE_TOP, "initial.theta0=2.5"], branch="fast")


def test_outside_the_domain_is_one_sentence():
    system = compose_scene(["force=[uniform_gravity]"]).system      # the asymmetric top: no regular precession
    with pytest.raises(ConfigError, match=r"^regime steady_precession needs a symmetric body A = B"):
        SteadyPrecession().check_domain(system)
    slow_top = compose_scene([*LAGRANGE_TOP, "initial.theta0=2.5", "initial.r0=0.5"]).system
    with pytest.raises(ConfigError, match=r"^initial.r0=0.5 is too slow for a regular precession"):
        SteadyPrecession().check_domain(slow_top)


@pytest.mark.parametrize("top, branch, theta0, r0", [
    ("lagrange", "slow", 1.0, 5.0), ("lagrange", "fast", 1.0, 5.0), ("lagrange", "slow", 2.5, 3.0),
    ("lagrange", "fast", 2.5, -3.0), ("si", "slow", 0.7, 30.0), ("si", "fast", 2.0, 20.0)])
def test_solution_is_the_full_model(top, branch, theta0, r0):
    # The full Euler–Poisson equations from the regime's own t = 0 state (p0, q0 from it; r0, θ0 the scene's)
    # follow the analytic solution, and its Euler angles, over three periods.
    regime = SteadyPrecession(branch=branch)
    scene = [*(LAGRANGE_TOP if top == "lagrange" else SI_TOP), f"initial.theta0={theta0}", f"initial.r0={r0}"]
    y0 = regime.initial_state(compose_scene(scene).system)
    period = regime.period(compose_scene(scene).system)
    full = compose_scene([*scene, f"initial.p0={float(y0[0])!r}", f"initial.q0={float(y0[1])!r}", "integrator=dop853",
                          "integrator.rtol=1e-12", "integrator.atol=1e-12", f"time.end={3 * float(period)!r}",
                          "time.n_output=301"])
    assert regime.check_domain(full.system) == []                # it starts exactly on the regime's orbit
    ds = full.run()
    t = ds.time.values
    expected = regime.solution(full.system, t)
    np.testing.assert_allclose(ds.omega.values, expected[:, :3], rtol=0, atol=1e-9 * max(1.0, abs(r0)))
    np.testing.assert_allclose(ds.gamma.values, expected[:, 3:], rtol=0, atol=1e-9)
    angles = regime.euler_angles(full.system, t)
    for name in ("psi", "theta", "phi"):
        np.testing.assert_allclose(ds[name].values, angles[name], rtol=0, atol=1e-8, err_msg=name)


def test_fast_top_precesses_slowly_at_the_gyroscopic_rate():
    # For a fast top the slow rate tends to −m/(C r0) (m = 1, C = 1 here): the classical gyroscope.
    system = compose_scene([*LAGRANGE_TOP, "initial.r0=1000"]).system
    n, _ = SteadyPrecession().rates(SteadyPrecession().scene(system))
    assert n == pytest.approx(-1e-3, rel=1e-6)


def test_textbook_condition():
    # Textbook convention: θ from the upward vertical, ψ̇ about it (θ_up = π − θ, ψ̇ = −n). M g ℓ = 1 and C = 1 here.
    system = compose_scene([*LAGRANGE_TOP, "initial.theta0=1.0", "initial.r0=5"]).system
    n, sigma = SteadyPrecession().rates(SteadyPrecession().scene(system))
    a, r0, psi_dot, cos_up = 0.8, 5.0, -n, np.cos(np.pi - 1.0)
    assert psi_dot * (r0 - a * psi_dot * cos_up) == pytest.approx(1.0, rel=1e-14)               # with r0: A
    assert psi_dot * (sigma + (1 - a) * psi_dot * cos_up) == pytest.approx(1.0, rel=1e-14)      # with φ̇ = σ: C − A
    assert psi_dot * (r0 - (1 - a) * psi_dot * cos_up) != pytest.approx(1.0, rel=1e-3)          # the mixed form fails
