"""resonant_omega3 (seed 001, ω = 3): error orders against exact orbits, errata of seed 001, refusals.

Theory (Lindstedt–Poincaré, report docs/derivations/seed001_resonant_omega3.md §4, §6): p, q O(μ³)
relative to c√γ0''; r/r0, γ/γ0'' O(μ⁴); period O(μ⁴); Euler angles O(μ⁴). Printed orders and the
numerical ℓ1 are the report's independent measurements.
"""

import numpy as np
import pytest

from gyrolab.engine.config import compose_config
from gyrolab.errors import ConfigError
from gyrolab.experiments.regime_run import errors, prepare
from gyrolab.plugins.regimes import shaker_omega3 as paper
from tests.helpers.regimes import B1, B2, overrides_001, run_case, slope

MUS = (0.05, 0.035, 0.025)


@pytest.fixture(scope="module")
def b1():
    return {f: {mu: run_case(overrides_001(B1, mu, f)) for mu in MUS} for f in ("corrected", "printed")}


def _errs(cases, key):
    out = []
    for mu in MUS:
        scene, regime, t, result = cases[mu]
        s = regime.scene(scene.system)
        scale = {"pq": np.sqrt(s.gamma0pp), "r": s.r0, "gamma": s.gamma0pp, "gamma3": s.gamma0pp,
                 "period": 1 / s.r0}[key]
        out.append(errors(result)[key] / scale)
    return out


@pytest.mark.parametrize("key,order", [("pq", 3), ("r", 4), ("gamma", 4), ("gamma3", 4), ("period", 4)])
def test_error_order_against_the_exact_orbit(b1, key, order):
    assert slope(MUS, _errs(b1["corrected"], key)) == pytest.approx(order, abs=0.2)


def test_erratum_001_l1_a2_L310_change_p_q(b1):
    # (21) a2, L310 and (26) ℓ1: printed p, q error order ≈ 1 (report: 0.94), corrected 3
    assert slope(MUS, _errs(b1["printed"], "pq")) == pytest.approx(1, abs=0.3)
    assert slope(MUS, _errs(b1["corrected"], "pq")) == pytest.approx(3, abs=0.2)


def test_erratum_001_l1_against_the_orbits_fourier_coefficient():
    # ℓ1 = (cos 3th coefficient of p1)/μ of the exact orbit; report: −0.04502 at μ = 0.0125 (B1)
    mu = 0.0125
    scene, regime, t, result = run_case(overrides_001(B1, mu), samples=512)
    s = regime.scene(scene.system)
    p1 = result["states"]["orbit"][:-1, 0] / np.sqrt(s.gamma0pp)
    th = 2 * np.pi * np.arange(len(p1)) / len(p1)
    l1_exact = 2 * np.mean(p1 * np.cos(3 * th)) / mu
    assert l1_exact == pytest.approx(-0.04502, abs=2e-4)
    C = paper.Constants(B1["a"], B1["b"], *B1["rc"], B1["k"], B1["theta0"])
    assert abs(C.l1 - l1_exact) < 1e-3 < abs(C.as_printed().l1 - l1_exact)


def test_erratum_001_period_alpha(b1):
    # (28): k M3²(b − a) printed, ½ k M3²(b − a) corrected
    assert slope(MUS, _errs(b1["printed"], "period")) == pytest.approx(2, abs=0.2)
    assert slope(MUS, _errs(b1["corrected"], "period")) == pytest.approx(4, abs=0.2)


def test_erratum_001_phi2():
    # (33) φ2: "r0⁻¹kC1tan²θ0" → "½kC1tan²θ0", drop "−¼(1+3/A1) r0⁻¹cos 4r0t"; body B2, ℓ1 corrected
    mus = (0.035, 0.025)
    printed, corrected = [], []
    for mu in mus:
        scene, regime, t, result = run_case(overrides_001(B2, mu, periods=3), samples=240)
        s = regime.scene(scene.system)
        C = regime.constants(s)
        exact = result["angles"]["orbit"]["phi"]
        printed.append(np.abs(paper.euler(t, s.r0, C, printed_phi2=True)["phi"] - exact).max())
        corrected.append(np.abs(paper.euler(t, s.r0, C)["phi"] - exact).max())
    assert slope(mus, printed) < 2.8  # report: 2.47
    assert slope(mus, corrected) == pytest.approx(4, abs=0.2)


def test_omega3_without_allow_nonphysical_is_refused():
    # an ω = 3 body without body.allow_nonphysical=true: one sentence, before anything runs
    with pytest.raises(ConfigError, match="allow_nonphysical"):
        prepare(compose_config([o for o in overrides_001(B1, 0.05) if "allow_nonphysical" not in o]))


def test_regime_refuses_a_body_without_omega3():
    cfg = compose_config(["regime=resonant_omega3", "initial.r0=20"])
    with pytest.raises(ConfigError, match=r"needs ω = 3 but the body has ω = 0.4082"):
        prepare(cfg)


def test_nonphysical_flag_is_required_by_the_regime():
    # ω = 3 body given explicitly; allow_nonphysical is what the regime checks
    from gyrolab.plugins.regimes.resonant_omega3 import ResonantOmega3
    from gyrolab.engine.scene import Scene

    scene = Scene.from_config(compose_config(overrides_001(B1, 0.05)))
    scene.system.body.source["allow_nonphysical"] = False
    with pytest.raises(ConfigError, match=r"set body.allow_nonphysical=true"):
        ResonantOmega3().check_domain(scene.system)


def test_constants_match_the_report():
    # report §5: B1 corrected ℓ1 = −0.045336, a2 = −0.717857, α/μ² = 0.715834; printed −0.016391, −1.23857, 0.534071
    C = paper.Constants(B1["a"], B1["b"], *B1["rc"], B1["k"], B1["theta0"])
    assert (C.l1, C.a2, C.alpha2) == pytest.approx((-0.045336, -0.717857, 0.715834), abs=2e-6)
    P = C.as_printed()
    assert (P.l1, P.a2, P.alpha2) == pytest.approx((-0.016391, -1.23857, 0.534071), abs=2e-5)


def test_reduced_rhs_001_eq1_is_the_full_model_rescaled():
    # seed 001 eq. (1)/(5): d/dτ of the scaled variables equals the Euler–Poisson right-hand side rescaled
    # (p = c√γ0'' p1, r = r0 r1, γ = γ0'' γ1, τ = r0 t, k = k_gt γ0''); c = 1 here
    from gyrolab.analysis.periodic import FixedPointModel

    C = paper.Constants(B1["a"], B1["b"], *B1["rc"], B1["k"], B1["theta0"])
    model = FixedPointModel(np.array([C.a, C.b, 1.0]), np.array([C.x0, C.y0, C.z0]), C.k_gt)
    g0, r0 = C.g0, 25.0
    mu = paper.mu_of(r0, C.theta0)
    scale = np.array([np.sqrt(g0), np.sqrt(g0), r0, g0, g0, g0])
    for Y in np.random.default_rng(0).uniform(-1, 1, (5, 6)):
        expected = model.rhs(scale * Y) / scale / r0
        assert np.allclose(paper.scaled_rhs(0.0, Y, mu, C), expected, rtol=0, atol=1e-13)


def test_reduced_rhs_is_exposed_and_integrates_to_the_analytic_orbit():
    from scipy.integrate import solve_ivp

    scene, regime, t, result = run_case(overrides_001(B1, 0.05))
    rhs, Y0, to_model = regime.reduced_rhs(scene.system)
    s = regime.scene(scene.system)
    tau = s.r0 * s.c * t
    Y = solve_ivp(rhs, (0, tau[-1]), Y0, method="DOP853", rtol=1e-12, atol=1e-14, t_eval=tau).y
    y = to_model(Y)
    analytic = regime.solution(scene.system, t)
    # the analytic series is O(μ³) in p1 (report §6): 0.05³ ≈ 1.3e-4 relative to c√γ0''
    assert np.max(np.abs(y[:, :2] - analytic[:, :2])) / np.sqrt(s.gamma0pp) < 1e-3
