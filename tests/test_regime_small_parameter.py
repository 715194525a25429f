"""small_parameter (seed 000, corrected fast-spin reading): error orders against exact orbits, errata of seed 000.

Orders expected: the Lindstedt–Poincaré theory (report docs/derivations/seed000_large_parameter.md §5.1):
p, q O(ε³); r, γ, γ', γ'', period O(ε⁴) with ε = c/r0. The printed formulas' orders are those the report
measured with an independent DOP853 shooting (§5.3, §6).
"""

import numpy as np
import pytest

from pipeline.config import compose_config
from pipeline.errors import ConfigError
from pipeline.experiments.regime_run import errors, prepare
from plugins.regimes import ismail2021 as paper
from tests.test_regime_helpers import GAMMA_000, overrides_000, run_case, slope

MUS = (16.0, 32.0, 64.0)


@pytest.fixture(scope="module")
def cases():
    return {mu: run_case(overrides_000(mu)) for mu in MUS}


def _fit(cases, key):
    return slope([1 / mu for mu in MUS], [errors(cases[mu][3])[key] for mu in MUS])


@pytest.mark.parametrize("key,order", [("pq", 3), ("r", 4), ("gamma", 4), ("gamma3", 4), ("period", 4)])
def test_error_order_against_the_exact_orbit(cases, key, order):
    # errors in model units: r, period scale with r0 = μ c and 1/r0 — relative errors have the theory's order
    scale = {"r": lambda mu: 1 / mu, "period": lambda mu: mu}.get(key, lambda mu: 1.0)
    errs = [errors(cases[mu][3])[key] * scale(mu) for mu in MUS]
    assert slope([1 / mu for mu in MUS], errs) == pytest.approx(order, abs=0.2)


def _scaled_errors(mu, evaluate):
    """Max error, over one exact period, of a scaled-solution evaluator against the exact orbit (state in c units)."""
    scene, regime, t, result = run_case(overrides_000(mu))
    P = regime.params(regime.scene(scene.system))
    exact = result["states"]["orbit"]
    S = evaluate(mu * t, P)
    approx = paper.scaled_to_model(S, P)
    return np.abs(approx - exact).max(axis=0) / np.array([1, 1, mu, 1, 1, 1])


def test_erratum_000_r1_y0_coefficient():
    # (35) r1: "+ y0' sin τ" printed, "+ 4y0' sin τ" corrected; printed formula read in strained time
    strained = lambda tau, P: paper.printed_scaled(paper.frequency(P) * tau, P)
    printed = [_scaled_errors(mu, strained)[2] for mu in (32.0, 64.0)]
    corrected = [_scaled_errors(mu, paper.scaled)[2] for mu in (32.0, 64.0)]
    assert slope([1 / 32, 1 / 64], printed) == pytest.approx(2, abs=0.2)
    assert slope([1 / 32, 1 / 64], corrected) == pytest.approx(4, abs=0.2)


def test_erratum_000_gamma_second_order_terms():
    # (35) γ, γ': the O(μ⁻²) correction is incomplete as printed (report §5.2)
    strained = lambda tau, P: paper.printed_scaled(paper.frequency(P) * tau, P)
    printed = [_scaled_errors(mu, strained)[3:5].max() for mu in (32.0, 64.0)]
    corrected = [_scaled_errors(mu, paper.scaled)[3:5].max() for mu in (32.0, 64.0)]
    assert slope([1 / 32, 1 / 64], printed) == pytest.approx(2, abs=0.2)
    assert slope([1 / 32, 1 / 64], corrected) == pytest.approx(4, abs=0.2)


def test_erratum_000_period_36(cases):
    # (36): printed C1 coefficient 1/16 and spurious B1 term; exact α from shooting
    alpha = {mu: cases[mu][3]["orbit"].period * mu - 2 * np.pi for mu in MUS}
    P = {mu: cases[mu][1].params(cases[mu][1].scene(cases[mu][0].system)) for mu in MUS}
    printed = [abs(paper.printed_period_correction(P[mu]) - alpha[mu]) for mu in MUS]
    corrected = [abs(2 * np.pi / paper.frequency(P[mu]) - 2 * np.pi - alpha[mu]) for mu in MUS]
    inv = [1 / mu for mu in MUS]
    assert slope(inv, printed) < 2.3
    assert slope(inv, corrected) == pytest.approx(4, abs=0.2)
    # report §5.2: μ²α/(2π) → x0' + kC1/4 = 0.4625 (printed: x0' + kC1/16 = 0.49063)
    assert alpha[64.0] * 64**2 / (2 * np.pi) == pytest.approx(0.5 + 0.3 * (-0.5) / 4, abs=0.01)


def test_erratum_000_euler_angles_38_39():
    # (38)-(39): r0⁻¹t → r0t, '+ sin' → '× sin', μ⁻¹c → μ⁻², θ sign, −0.667k → +0.5k (report §6)
    scene, regime, t, result = run_case([*overrides_000(64.0), "regime.periods=1"])
    P = regime.params(regime.scene(scene.system))
    exact = result["angles"]["orbit"]
    printed, corrected = paper.printed_euler(t, P), paper.euler(t, P)
    for name in ("theta", "psi", "phi"):
        e_p = np.abs(printed[name] - exact[name]).max()
        e_c = np.abs(corrected[name] - exact[name]).max()
        assert e_c < 1e-5 and e_p > 10 * e_c, (name, e_p, e_c)
    assert np.abs(printed["phi"] - exact["phi"]).max() > 6  # the printed rate r0⁻¹ loses 2π per period


def test_printed_formula_is_selectable_and_worse():
    _, _, _, printed = run_case(overrides_000(32.0, "printed"))
    _, _, _, corrected = run_case(overrides_000(32.0))
    assert errors(printed)["gamma"] > 100 * errors(corrected)["gamma"]


def test_slow_spin_is_refused():
    cfg = compose_config([*overrides_000(16.0)[:-2], "initial.r0=0.5", "initial.theta0=1.5"])
    with pytest.raises(ConfigError, match=r"needs fast spin, 0 < c/r0 < 1, but initial.r0 gives c/r0=2"):
        prepare(cfg)


def test_resonance_omega_one_is_refused():
    # a = b = 0.505: ω = (1 − a)/a = 0.9802, within 0.02 of ω = 1 (a near-flat disc, the paper's Table body)
    cfg = compose_config(["regime=small_parameter", "body.a=0.505", "body.b=0.505", "initial.r0=20"])
    with pytest.raises(ConfigError, match=r"excludes the resonance ω = 1: the body has ω = 0.98"):
        prepare(cfg)


def test_edge_of_domain_is_warned():
    _, _, warnings = prepare(compose_config([*overrides_000(4.0)]))
    assert any("c/r0 = 0.25 > 0.2" in w for w in warnings)


def test_unknown_formula_is_refused():
    with pytest.raises(ConfigError, match=r"regime.formula='typo' is not valid; valid choices: corrected, printed"):
        prepare(compose_config([*overrides_000(16.0), "regime.formula=typo"]))
