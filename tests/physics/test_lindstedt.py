"""The numeric Poincaré–Lindstedt series (gyrolab.physics.lindstedt) against independent truths.

Truths: the corrected closed forms of seed 000 (report docs/derivations/seed000_large_parameter.md §5, derived by
hand and checked against exact orbits in tests/plugins/regimes/test_small_parameter.py), the exact periodic orbits of
the full model (Newton shooting, gyrolab.analysis.periodic), and the Lagrange top's steady precession, whose frequency
is known in closed form: aγ0''ψ̇² ∓ r0ψ̇ + 1 = 0 (c = 1), so Ω(ε) has its branch point at ε = 1/(2√(aγ0'')).
"""

import numpy as np
import pytest
from gyrolab.errors import ConfigError
from gyrolab.analysis.lindstedt_check import error_ladder, exact_orbit, series_error
from gyrolab.physics.lindstedt import Body, series
from gyrolab.plugins.regimes import ismail2021 as paper

from tests.helpers.regimes import slope, taylor_coefficients

Z0 = float(np.sqrt(1 - 0.34))
BODY_I = Body(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=Z0, k=0.3)  # report 000's body I
GAMMA = 0.5  # seed 000's scaling γ0'' = Γε (eq. 28), Γ of report 000


def test_orders_three_and_four_reproduce_the_corrected_closed_forms():
    # In seed 000's scaling (γ0'' = Γε) the Taylor coefficients in ε, at fixed τ, of the series and of the
    # corrected (35)-(36) agree through the closed forms' order: ε⁰…ε² in p1, q1 (error O(ε³)), ε⁰…ε³ in r1 and
    # the γ's (error O(ε⁴)), Ω through ε³ (period O(ε⁴)).
    sol = series(BODY_I, 6, tilt=0.0, tilt_slope=GAMMA)
    tau = np.linspace(0.0, 2 * np.pi, 7)

    def closed(eps):
        P = paper.Params(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=Z0, k=0.3, mu=1 / eps, g0=GAMMA * eps)
        S = paper.scaled(tau, P)
        return np.stack([S[k] for k in ("p1", "q1", "r1", "g1", "g2", "g3")], axis=-1)

    ours = taylor_coefficients(lambda e: sol.scaled(e, tau, 4), 4)
    theirs = taylor_coefficients(closed, 4)
    for k in range(4):
        columns = slice(0, 6) if k < 3 else slice(2, 6)
        assert np.max(np.abs(ours[k][:, columns] - theirs[k][:, columns])) < 1e-10, k
    x, kc = 0.5, 0.3 * (1.5 - 2.0)
    assert sol.omega[:4] == pytest.approx([1.0, 0.0, -(x + kc / 4), Z0 * GAMMA], abs=1e-13)


@pytest.mark.parametrize("body,tilt", [
    (BODY_I, 0.3),
    (Body(a=0.4, b=0.3, x0=0.6, y0=-0.48, z0=0.64, k=1.0), -0.5),  # ω² = 3.5 (non-physical: A + B < C)
    (Body(a=0.9, b=1.7, x0=0.0, y0=0.6, z0=0.8, k=-0.7), 0.8),
])
def test_the_conditions_the_integrals_imply_hold_at_every_order(body, tilt):
    # The mean of ṙ, of γ̇'' and one real part of the resonant γ-harmonic are not imposed; energy, area and
    # |γ| = 1 make them vanish. Their residual is round-off relative to the coefficients' size at each order.
    sol = series(body, 16, tilt=tilt)
    assert np.all(sol.consistency <= 1e-13 * np.maximum(1.0, sol.norms()))


@pytest.fixture(scope="module")
def ladder():
    """The series of body I at γ0'' = 0.3 through order 12 and the exact orbits at three ε a factor √2 apart."""
    sol = series(BODY_I, 12, tilt=0.3)
    eps = (0.14, 0.1, 0.07)
    return sol, eps, [exact_orbit(BODY_I, e, 0.3, sol) for e in eps]


@pytest.mark.parametrize("order", [4, 7, 10])
def test_error_against_the_exact_orbit_falls_as_eps_to_the_order_plus_one(ladder, order):
    sol, eps, orbits = ladder
    errs = [series_error(sol, o, e, order) for o, e in zip(orbits, eps)]
    assert slope(eps, [e["state"] for e in errs]) == pytest.approx(order + 1, abs=0.3)
    # Ω is even in ε at a fixed tilt: the period's error is ε^(N+1) for odd N, ε^(N+2) for even N
    assert slope(eps, [e["period"] for e in errs]) == pytest.approx(order + 1 + (order + 1) % 2, abs=0.3)


@pytest.mark.parametrize("a,tilt", [(0.8, 0.5), (0.8, 0.2), (1.5, 0.5)])
def test_radius_of_convergence_is_the_lagrange_tops_branch_point(a, tilt):
    sol = series(Body(a=a, b=a, x0=0.0, y0=0.0, z0=1.0, k=0.0), 32, tilt=tilt)
    exact = 1 / (2 * np.sqrt(a * tilt))
    assert sol.radius()["domb_sykes"] == pytest.approx(exact, rel=0.01)
    assert sol.radius_of_convergence() == pytest.approx(exact, rel=0.03)  # the median the regime reports
    # and Ω itself: Ω = 1 ± (1 − √(1 − 4aγ0''ε²))/(2a): ε² coefficient ±γ0'', ε⁴ coefficient −aγ0''²
    assert abs(sol.omega[2]) == pytest.approx(tilt, abs=1e-13)
    assert sol.omega[4] == pytest.approx(-a * tilt**2, abs=1e-13)


def test_error_ladder_measures_the_order_at_the_radius_it_estimates():
    sol = series(BODY_I, 32, tilt=0.3)
    result = error_ladder(sol, 6, 0.3, points=3)
    assert result["slope"] == pytest.approx(7, abs=0.3)
    assert np.all(result["state"] > 1e-12) and np.all(result["eps"] < sol.radius_of_convergence() / 3)


def test_small_divisor_is_explicit_and_a_resonance_is_refused():
    # ω² = (1 − a)(1 − b)/(ab): a = b = 1/3 gives ω = 2 exactly; the p-mode divisor 4 − ω² vanishes
    with pytest.raises(ConfigError, match="resonance ω = 2"):
        series(Body(a=1 / 3, b=1 / 3, x0=0.6, y0=0.0, z0=0.8, k=0.0), 4, tilt=0.3)
    sol = series(BODY_I, 4, tilt=0.3)
    w2 = (1 - 2.0) * (1 - 1.5) / (2.0 * 1.5)
    assert sol.small_divisors[2] == pytest.approx(4 - w2, abs=1e-15)


@pytest.mark.parametrize("a,b,tilt", [(2.0, 1.5, 0.3), (3.0, 1.2, 0.5), (0.5, 0.7, -0.6), (1.2, 1.2, 0.8)])
def test_finite_tilt_frequency_is_the_series_eps2_coefficient(a, b, tilt):
    # small_parameter's closed finite-tilt Ω (fitted from the series' ε² coefficient) holds exactly in γ0''
    from gyrolab.plugins.regimes.small_parameter import finite_tilt_frequency

    body = Body(a=a, b=b, x0=0.48, y0=-0.36, z0=0.8, k=0.7)
    P = paper.Params(a=a, b=b, x0=0.48, y0=-0.36, z0=0.8, k=0.7, mu=1.0, g0=tilt)
    assert series(body, 3, tilt=tilt).omega[2] == pytest.approx(finite_tilt_frequency(P) - 1, abs=1e-13)
