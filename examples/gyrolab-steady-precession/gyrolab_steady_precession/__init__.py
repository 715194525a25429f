"""The Lagrange top's regular (steady) precession, an exact periodic solution (a gyrolab regime plugin).

A heavy symmetric body (A = B, centre of mass on the symmetry axis e3, weight moment M g ℓ e3 = m e3)
turning as ω = n γ + σ e3 — a rotation n about the fixed vertical Z (γ in body axes) plus a spin σ
about e3 — keeps its nutation θ (γ·e3 = cos θ) and its spin r = ω·e3 = n cos θ + σ: γ̇ = γ × ω = σ γ × e3
turns γ about e3 at the rate −σ. Euler's equation I ω̇ = (Iω) × ω + m e3 × γ then reads, with I = A + (C − A) e3 e3ᵀ,

    −A n σ (e3 × γ) = n (C − A) r (e3 × γ) + m (e3 × γ),    i.e.    A cos θ n² − C r n − m = 0

(Z points along the weight, so θ = 0 hangs). For each r0 and θ0 with C² r0² + 4 A m cos θ0 ≥ 0 there are two
precession rates n, a slow one (n ≈ −m/(C r0) for a fast top) and a fast one (n ≈ C r0/(A cos θ0)); the body-frame
motion has the period 2π/|σ|, σ = r0 − n cos θ0. The tests check this against the full model at rtol = 1e-12.
"""

import numpy as np

from gyrolab.errors import ConfigError, choices
from gyrolab.plugins.regimes.base import FixedPointRegime

BRANCHES = ("slow", "fast")
#: A − B, the centre of mass off the axis, or a Newtonian k above this is not a Lagrange top
SYMMETRY_TOLERANCE = 1e-12


class SteadyPrecession(FixedPointRegime):
    name = "steady_precession"
    systems = ("fixed_point",)
    parameter = "mu"
    parameter_long_name = "gyroscopic parameter A M g l / (C r0)^2 (small: a fast top)"
    order = {}                           # an exact solution: no truncation error

    def __init__(self, *, branch="slow", formula="corrected", periods=3, samples_per_period=200):
        super().__init__(formula=formula, periods=periods, samples_per_period=samples_per_period)
        if branch not in BRANCHES:
            raise ConfigError(f"regime.branch={branch!r} is not valid; valid choices: {choices(BRANCHES)}")
        self.branch = branch

    # -- the precession rate, in the papers' units (time 1/c, rates c, C = 1, A = a, m = z0 = ±1) --------------
    def rates(self, s):
        """(n, σ): the precession rate about the vertical and the spin about e3; ConfigError if there is none."""
        cos = np.cos(s.theta0)
        disc = s.r0 ** 2 + 4.0 * s.a * s.z0 * cos
        if disc < 0:
            raise ConfigError(f"initial.r0={s.r0 * s.c:g} is too slow for a regular precession at theta0="
                              f"{s.theta0:g} (r0² + 4 a cos θ0 = {disc:.3g} < 0); give |r0| ≥ "
                              f"{np.sqrt(4 * s.a * abs(cos)) * s.c:.6g}")
        q = 0.5 * (s.r0 + np.copysign(np.sqrt(disc), s.r0))   # the two roots are −z0/q and q/(a cos θ0), without cancellation
        if self.branch == "slow":
            n = -s.z0 / q
        elif abs(cos) > 0:
            n = q / (s.a * cos)
        else:
            raise ConfigError("regime.branch=fast has no precession at theta0=π/2 (the fast rate is infinite); "
                              "valid choices there: slow")
        return n, s.r0 - n * cos

    # -- the Regime contract -------------------------------------------------------------------------------------
    def parameter_value(self, system):
        s = self.scene(system)
        return s.a / s.r0 ** 2 if s.r0 != 0 else float("inf")

    def check_domain(self, system):
        s = self.scene(system)
        if abs(s.a - s.b) > SYMMETRY_TOLERANCE:
            raise ConfigError(f"regime steady_precession needs a symmetric body A = B, got a={s.a:g}, b={s.b:g}; "
                              "valid choice: body=lagrange_top (or body.a = body.b)")
        if abs(s.x0) > SYMMETRY_TOLERANCE or abs(s.y0) > SYMMETRY_TOLERANCE:
            raise ConfigError(f"regime steady_precession needs the centre of mass on the symmetry axis, got "
                              f"com_direction=({s.x0:.3g}, {s.y0:.3g}, {s.z0:.3g}); valid: [0, 0, ±1]")
        if s.k != 0:
            raise ConfigError(f"regime steady_precession is derived for force=[uniform_gravity], got newtonian with "
                              f"k={s.k:g}; valid choice: force=[uniform_gravity]")
        if s.r0 == 0:
            raise ConfigError("initial.r0=0 has no regular precession; give a spin r0 ≠ 0")
        _, sigma = self.rates(s)
        if sigma == 0:
            raise ConfigError("the regular precession at this r0 and theta0 has no spin about the axis (σ = 0), so "
                              "no finite period; change initial.r0 or initial.theta0")
        warnings = self.reseat_warnings(system)
        if abs(np.sin(s.theta0)) < 1e-6:
            warnings.append(f"theta0={s.theta0:g} puts the axis on the vertical, where every precession rate is "
                            "the same motion (a sleeping top)")
        return warnings

    def _state(self, s, tau):
        n, sigma = self.rates(s)
        phi = np.pi / 2 + sigma * tau                          # γ(0) = (sin θ0, 0, cos θ0), as the built-ins start
        gamma = np.stack([np.sin(s.theta0) * np.sin(phi), np.sin(s.theta0) * np.cos(phi),
                          np.full_like(phi, np.cos(s.theta0))], axis=1)
        omega = n * gamma
        omega[:, 2] = s.r0                                     # n cos θ0 + σ
        return np.concatenate([omega, gamma], axis=1)

    def _period(self, s):
        return 2 * np.pi / abs(self.rates(s)[1])

    def _euler(self, s, tau):
        n, sigma = self.rates(s)
        return {"psi": n * tau, "theta": np.full_like(tau, s.theta0), "phi": np.pi / 2 + sigma * tau}

    def attributes(self):
        return {**super().attributes(), "regime_branch": self.branch}
