"""small_parameter across its excluded resonances ω → 1, 2: the error grows toward them, the refusal band is where it is large.

Every error is the analytic solution's distance to the exact periodic orbit of the full model (Newton
shooting, pipeline/periodic.py) over one period, relative to c (p, q), r0 (r) and the period; ω is set through
the body's a at fixed b = 0.6, c/r0 = 0.05, Γ = 0.5 (conf/experiment/regime_validity.yaml).
"""

import numpy as np
import pytest

from pipeline.config import compose_config
from pipeline.experiments.regime_validity import a_for_omega, resonance_point
from plugins.regimes.small_parameter import REFUSE_DISTANCE, WARN_DISTANCE

TOL = 1e-2  # a relative error the regime should not exceed where it accepts a scene
DISTANCES = (0.1, 0.05, 0.03, REFUSE_DISTANCE)


@pytest.fixture(scope="module")
def cfg():
    return compose_config(["experiment=regime_validity"])


@pytest.fixture(scope="module")
def sweep(cfg):
    out = {}
    for n in (1.0, 2.0):
        for side in (-1, 1):
            for d in DISTANCES:
                out[n, side, d] = resonance_point(cfg, n + side * d)
            out[n, side, "inside"] = resonance_point(cfg, n + side * REFUSE_DISTANCE / 2, check=False)
    return out


def test_a_for_omega_gives_the_natural_frequency():
    for w in (0.5, 1.0, 2.0, 3.0):
        a, b = a_for_omega(w, 0.6), 0.6
        assert (a - 1) * (b - 1) / (a * b) == pytest.approx(w * w, rel=1e-12)
    assert a_for_omega(3.0, 1 / 7) == pytest.approx(0.4)  # seed 001's body B1 (ω = 3)


@pytest.mark.parametrize("n", [1.0, 2.0])
@pytest.mark.parametrize("side", [-1, 1])
def test_error_grows_toward_the_resonance(sweep, n, side):
    errs = [max(sweep[n, side, d][1].values()) for d in DISTANCES]
    assert all(sweep[n, side, d][0] == "ok" for d in DISTANCES)
    assert np.all(np.diff(errs) > 0), errs  # monotone as |ω − n| decreases
    assert errs[-1] > 4 * errs[0]  # ≥ 4× from |ω − n| = 0.1 to the refusal edge 0.02 (measured 4.6–17×)


def test_growth_near_omega_2_is_one_power_of_the_small_divisor(sweep):
    # p, q carry 1/(4 − ω²) once: error ∝ |4 − ω²|^−1 (γ, γ' have no such divisor)
    for side in (-1, 1):
        d = np.array(DISTANCES)
        e = [sweep[2.0, side, x][1]["pq"] for x in DISTANCES]
        s = -np.polyfit(np.log(np.abs(4 - (2 + side * d) ** 2)), np.log(e), 1)[0]
        assert s == pytest.approx(1.0, abs=0.15)
    # near ω = 1 the growth is steeper (fitted s ≈ 1.5 over the sweep, with γ's ∝ |1 − ω²|^−2)
    e1 = [max(sweep[1.0, 1, x][1].values()) for x in (0.05, REFUSE_DISTANCE)]
    assert np.log(e1[1] / e1[0]) / np.log(np.abs(1 - 1.05**2) / np.abs(1 - 1.02**2)) > 1.2


@pytest.mark.parametrize("n", [1.0, 2.0])
def test_refusal_threshold_is_consistent_with_the_error(cfg, sweep, n):
    for side in (-1, 1):
        # the plugin refuses inside REFUSE_DISTANCE ...
        status, _ = resonance_point(cfg, n + side * REFUSE_DISTANCE / 2)
        assert status.startswith("refused") and f"resonance ω = {n:g}" in status
        # ... where, forced, the exact orbit is missed by more than TOL or shooting fails (no nearby orbit)
        status, e = sweep[n, side, "inside"]
        edge = max(sweep[n, side, REFUSE_DISTANCE][1].values())
        assert status.startswith("failed") or max(e.values()) > max(TOL, edge)
        # it accepts from 0.03 on, where the error is below TOL, and below TOL/5 from the warning distance
        assert max(sweep[n, side, 0.03][1].values()) < TOL
        assert max(sweep[n, side, WARN_DISTANCE][1].values()) < TOL / 5
        # at the refusal edge itself the error is of the order of TOL (measured 0.8–1.7 TOL at c/r0 = 0.05)
        assert 0.5 * TOL < edge < 2.5 * TOL
