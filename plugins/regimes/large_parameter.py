"""Seed 000's "large parameter" μ = c/r0 ≫ 1 (slow spin, the paper's "new domain"): refused, with the evidence.

The paper (Ismail 2021) prints μ = c/r0 in eq. (4), but its own equations
(1)-(2) hold only for μ = r0/c (unique solution of the coefficient matching,
``docs/derivations/seed000_large_parameter.md`` §3). Read as printed, the
formulas describe a nearly non-spinning body that in fact falls over: the
error of γ'' is 0.87-1.0 for μ = 4…256 (test
``tests/test_regime_large_parameter.py::test_printed_reading_fails_at_order_one``).
So there is no consistent expansion for small r0; the consistent reading is
the fast-spin expansion, ``regime=small_parameter``. This plugin exists so
that the paper's name is recognised and refused with that explanation.
"""

from __future__ import annotations

import numpy as np

from gyrolab.errors import ConfigError
from gyrolab.plugins.regimes import ismail2021 as paper
from gyrolab.plugins.regimes.base import FixedPointRegime

REFUSAL = ("regime large_parameter (seed 000's μ = c/r0 ≫ 1, slow spin) has no consistent expansion: the "
           "paper's eq. (4) contradicts its eqs. (1)-(2), whose only consistent scaling is μ = r0/c, and read "
           "as printed the formulas miss the full model by O(1) (docs/regimes.md); use regime=small_parameter, "
           "the corrected fast-spin reading with ε = c/r0")


class LargeParameter(FixedPointRegime):
    name = "large_parameter"
    parameter = "c/r0"
    parameter_long_name = "seed 000's printed large parameter μ = c/r0 (eq. 4; inconsistent)"

    def parameter_value(self, system) -> float:
        s = self.scene(system)
        return 1.0 / s.r0 if s.r0 != 0 else np.inf

    def check_domain(self, system) -> list[str]:
        raise ConfigError(REFUSAL)

    def _state(self, s, t):
        raise ConfigError(REFUSAL)

    def _period(self, s):
        raise ConfigError(REFUSAL)

    def _euler(self, s, t):
        raise ConfigError(REFUSAL)


def printed_reading_state(t: np.ndarray, s) -> np.ndarray:
    """Evidence only: printed (35) under the paper's own reading μ = c/r0 (τ = r0 t, p = c p1, r = r0 r1).

    ``s`` is a ``NondimensionalScene``; returns (n, 6) in units of c at times t (1/c).
    """
    mu = 1.0 / s.r0
    P = paper.Params(a=s.a, b=s.b, x0=s.x0, y0=s.y0, z0=s.z0, k=s.k, mu=mu, g0=s.gamma0pp)
    S = paper.printed_scaled(s.r0 * np.asarray(t, dtype=float), P)
    return np.stack([S["p1"], S["q1"], s.r0 * S["r1"], S["g1"], S["g2"], S["g3"]], axis=-1)
