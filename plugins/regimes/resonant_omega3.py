"""The resonant case ω = 3 (Shaker, El-Barki & Ismail), branches (i)-(iv) of eq. (23), corrected or printed.

Fast spin with μ = c√(cos θ0)/r0 ≪ 1; ω = 3 requires A + B < C, so the scene must admit a non-physical body
(``body.allow_nonphysical=true``; ``docs/derivations/seed001_resonant_omega3.md`` §3). The branches and their
measured orders: docs/regimes.md, "resonant_omega3"; (ii) and (iv) run only as printed (erratum 001-6). Theory
orders in μ (report §6): p, q 3; r, γ's, period 4; printed: p, q 1 (wrong ℓ1), γ's and period 2.
"""

from __future__ import annotations

import numpy as np

from gyrolab.errors import ConfigError, as_number
from gyrolab.plugins.regimes import shaker_omega3 as paper
from gyrolab.plugins.regimes.base import FixedPointRegime, NondimensionalScene

OMEGA_TOLERANCE = 1e-6
BRANCHES = ("i", "ii", "iii", "iv")
BRANCH_ORDER = {"pq": 1.0, "r": 2.0, "gamma": 2.0, "gamma3": 2.0, "period": 2.0}


class ResonantOmega3(FixedPointRegime):
    name = "resonant_omega3"
    parameter = "mu"
    parameter_long_name = "Shaker et al.'s small parameter μ = c√(cos θ0)/r0"
    order = {"pq": 3.0, "r": 4.0, "gamma": 4.0, "gamma3": 4.0, "period": 4.0}

    def __init__(self, *, formula: str = "corrected", periods: int = 3, samples_per_period: int = 200,
                 branch: str = "i", sign: int = 1, phase_deg: float = 45.0) -> None:
        super().__init__(formula=formula, periods=periods, samples_per_period=samples_per_period)
        branch = str(branch)
        if branch not in BRANCHES:
            raise ConfigError(f"regime.branch={branch!r} is not a branch of Shaker et al.'s eq. (23); valid choices: "
                              f"{', '.join(BRANCHES)}")
        if formula == "corrected" and branch in ("ii", "iv"):
            raise ConfigError(f"regime.branch={branch} is not a periodic solution: the resonant forcing M3³L310 locks "
                              "the p-mode phase to branch iii (erratum 001-6, docs/errata.md); valid choices: i, iii "
                              "(or regime.formula=printed to reproduce the paper's claim)")
        if sign not in (1, -1) or isinstance(sign, bool):
            raise ConfigError(f"regime.sign={sign!r} must be 1 or -1 (the ± of eq. 23)")
        phase = as_number(phase_deg, "regime.phase_deg")
        if branch == "iv" and not (0.0 < phase % 90.0):
            raise ConfigError(f"regime.phase_deg={phase_deg!r} puts branch iv on branch ii or iii; choose a phase that "
                              "is not a multiple of 90 degrees")
        self.branch, self.sign, self.phase_deg = branch, int(sign), phase
        if branch != "i":
            self.order = BRANCH_ORDER

    def constants(self, s: NondimensionalScene) -> paper.Constants:
        C = paper.Constants(a=s.a, b=s.b, x0=s.x0, y0=s.y0, z0=s.z0, k_gt=s.k, theta0=s.theta0)
        C = C.as_printed() if self.formula == "printed" else C
        return C.on_branch(self.branch, self.sign, np.radians(self.phase_deg))

    def parameter_value(self, system) -> float:
        s = self.scene(system)
        return paper.mu_of(s.r0, s.theta0) if s.gamma0pp > 0 and s.r0 > 0 else np.inf

    def check_domain(self, system) -> list[str]:
        s = self.scene(system)
        w = np.sqrt(max(s.omega2, 0.0))
        if abs(w - 3.0) > OMEGA_TOLERANCE:
            raise ConfigError(f"regime resonant_omega3 needs ω = 3 but the body has ω = {w:.6g} "
                              f"(ω² = (C−A)(C−B)/(AB)); choose b = (1−a)/(1+8a) = {paper.omega3_b(s.a):.10g} "
                              "for a = A/C, which is non-physical (A + B < C)")
        if not system.body.source.get("allow_nonphysical", False):
            raise ConfigError("regime resonant_omega3 describes a non-physical body (ω = 3 requires A + B < C); "
                              "set body.allow_nonphysical=true to study it anyway")
        if not 0 < s.theta0 < np.pi / 2:
            raise ConfigError(f"regime resonant_omega3 needs 0 < θ0 < π/2 (μ = c√cos θ0/r0 and M3 = tan θ0), "
                              f"got θ0={s.theta0:.4g}")
        mu = paper.mu_of(s.r0, s.theta0) if s.r0 > 0 else np.inf
        if not mu < 1:
            raise ConfigError(f"regime resonant_omega3 needs fast spin, μ = c√(cos θ0)/r0 < 1, but the scene "
                              f"gives μ={mu:.4g}; increase initial.r0")
        C = self.constants(s)
        if self.branch != "i" and not C.a2 / C.a1 > 0:
            raise ConfigError(f"regime.branch={self.branch} needs a2/a1 > 0 (eq. 24: the amplitude is √(a2/a1)), but "
                              f"this body has a2 = {C.a2:.4g}, a1 = {C.a1:.4g}; valid choices for it: branch i")
        warnings = ["non-physical body (A + B < C, ω = 3): admitted by body.allow_nonphysical=true"]
        if self.branch in ("ii", "iv"):
            warnings.append(f"branch {self.branch} as printed: not a periodic solution (L310 = {C.L310:.3g} ≠ 0 "
                            "locks the p-mode phase to branch iii, erratum 001-6); expect no exact orbit near it")
        if mu > 0.2:
            warnings.append(f"μ = {mu:.3g} > 0.2: near the edge of the fast-spin domain, expect errors of order "
                            f"μ² ≈ {mu**2:.2g}")
        if self.branch == "i" and (abs(C.a2) < 0.05 or abs(C.l1) * mu > 0.5):
            warnings.append(f"a2 = {C.a2:.3g} is near 0 (ℓ1 = M3³L310/a2 = {C.l1:.3g}): secondary resonance, "
                            "the case (i) series degrades")
        return warnings + self.reseat_warnings(system)

    def attributes(self) -> dict:
        out = {**super().attributes(), "regime_branch": self.branch}
        if self.branch != "i":
            out["regime_branch_sign"] = self.sign
        if self.branch == "iv":
            out["regime_branch_phase_deg"] = self.phase_deg
        return out

    def reduced_rhs(self, system):
        """Shaker et al.'s scaled system (eq. 1 in the variables of eq. 5, an exact rescaling of the full model) for
        this scene: ``(rhs, Y0, to_model)`` as ``SmallParameter.reduced_rhs``, Y = (p1, q1, r1, γ1, γ1', γ1'').
        """
        s = self.scene(system)
        C = self.constants(s)
        mu, g0 = paper.mu_of(s.r0, s.theta0), s.gamma0pp
        y0 = paper.state(np.array([0.0]), s.r0, C)[0]
        Y0 = np.concatenate([y0[:2] / np.sqrt(g0), [y0[2] / s.r0], y0[3:] / g0])

        def rhs(tau, Y):
            return paper.scaled_rhs(tau, Y, mu, C)

        def to_model(Y):
            Y = np.asarray(Y, dtype=float).reshape(6, -1)
            out = np.stack([np.sqrt(g0) * Y[0], np.sqrt(g0) * Y[1], s.r0 * Y[2], g0 * Y[3], g0 * Y[4], g0 * Y[5]], -1)
            out[:, :3] *= s.c
            return out

        return rhs, Y0, to_model

    def _state(self, s, t):
        return paper.state(t, s.r0, self.constants(s))

    def _period(self, s):
        return paper.period(s.r0, self.constants(s))

    def _euler(self, s, t):
        return paper.euler(t, s.r0, self.constants(s))
