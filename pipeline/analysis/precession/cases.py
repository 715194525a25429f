"""The catalogue of Yehia & El-kenani's (2021) regular precessions: one concrete parameter set per printed condition set.

Lifted from docs/derivations/scripts/seed002/model.py (``build_cases``). Ω = 1; common numbers:
asymmetric body (A, B, C) = (1.0, 1.4, 1.9), symmetric A = B = 1.2, C = 2.0; μ = (0.4, −0.5, 0.6),
h1 = 0.5, h3 = 0.3, k3 = 0.4 where free; spin m = 1.3 (n = 0), n = 0.8, ψ0 = 0.6 (n ≠ 0).
Labels: the paper's equation and set number; ``c`` = corrected set (the printed one fails),
``19.1L`` = the literal reading of the garbled k3 of (19.1) (printed), ``19.1`` = its bracket reading,
``31.2a``/``31.2b`` = the two alternatives of (31.2), ``N1``…``N5`` = families not in the paper
(``N3``…``N5``: the body at rest in the orbital frame with its z axis on the orbit normal, ``normal_rest``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gyrolab.analysis.precession.motion import Precession
from gyrolab.physics.gyrostat_euler import GyrostatParameters


@dataclass(frozen=True)
class Case:
    label: str
    section: str
    condition: str
    motion: Precession
    params: GyrostatParameters
    note: str = ""

    @property
    def case(self) -> str:
        """The paper's label without the correction/reading suffix."""
        return {"19.1L": "19.1"}.get(self.label, self.label.rstrip("c"))

    @property
    def formula(self) -> str:
        if self.label.startswith("N"):
            return "new"
        if self.label.endswith("c") or self.label == "19.1":
            return "corrected"
        return "printed"


def _params(A, B, C, k=(0.0, 0.0, 0.0), mu=(0.0, 0.0, 0.0), h1=0.0, h3=0.0, Omega=1.0):
    return GyrostatParameters((float(A), float(B), float(C)), tuple(float(x) for x in k),
                              tuple(float(x) for x in mu), (float(h1), 0.0, float(h3)), float(Omega))


def _case(label, section, printed, motion, params, note=""):
    return Case(label, section, printed, Precession(float(motion["n"]), float(motion["m"]), float(motion["psi0"]),
                                                     float(motion["theta0"])), params, note)


_S3 = np.sqrt(3.0)


def normal_rest(inertia, mu, h3, Omega, theta0: float, chi: float, k3: float = 0.0, h1: float | None = None,
                N: float | None = None) -> GyrostatParameters:
    """Parameters that make θ0 ∈ {0, π}, n ± m = 0 (rest in the orbital frame, ω = Ωγ) a solution.

    σ = cos θ0 = ±1, χ = ψ0 − σφ0 (only ψ ± φ matters): α = (cos χ, −σ sin χ, 0), β = (sin χ, σ cos χ, 0),
    γ = (0, 0, σ). The residual is constant; its γ-component does not contain k and gives
        h1 (μ1 sin χ + σ μ2 cos χ) = −(3/2) N/3 (A − B) sin 2χ          (μ·β h1 = −(N/2)(A − B) sin 2χ),
    its components ⊥ γ give k1 = (μ1 h3 − σ μ3 h1 cos χ)/Ω, k2 = (μ2 h3 + μ3 h1 sin χ)/Ω; C, k3, μ3, h3 free.
    Branches: μ·β ≠ 0 → h1 from the first equation (any A, B); μ·β = 0 → needs (A − B) sin 2χ = 0, h1 free
    (``h1`` must then be given). Derivation in docs/gyrostat.md; verified by the vector residual (tests)."""
    A, B, C = map(float, inertia)
    sigma = float(np.sign(np.cos(theta0)))
    s, c = np.sin(chi), np.cos(chi)
    gradient = 3.0 * Omega ** 2 if N is None else float(N)
    mu_beta = mu[0] * s + sigma * mu[1] * c
    rhs = -0.5 * gradient * (A - B) * np.sin(2 * chi)
    if h1 is None:
        if abs(mu_beta) < 1e-14:
            raise ValueError("normal_rest: μ·β = 0 at this χ, so h1 is free: give it")
        h1 = rhs / mu_beta
    elif abs(h1 * mu_beta - rhs) > 1e-12 * max(1.0, abs(rhs)):
        raise ValueError(f"normal_rest: h1 = {h1:g} violates h1 μ·β = −(N/2)(A − B) sin 2χ")
    k = ((mu[0] * h3 - sigma * mu[2] * h1 * c) / Omega, (mu[1] * h3 + mu[2] * h1 * s) / Omega, k3)
    params = _params(A, B, C, k, mu, h1, h3, Omega)
    return params if N is None else GyrostatParameters(params.inertia, params.k, params.mu, params.h, params.Omega, N)


def build_cases():
    """Every case, with parameters satisfying its (printed or corrected) conditions."""
    W = 1.0
    mu = (0.4, -0.5, 0.6)
    h1, h3, k3 = 0.5, 0.3, 0.4
    m_sp, n_pr = 1.3, 0.8
    Aa, Ba, Ca = 1.0, 1.4, 1.9          # asymmetric
    As, Cs = 1.2, 2.0                   # symmetric A = B = As
    th = 0.7                            # generic nutation angle
    cases = []
    # ---- 4.1.1 Case I : n = 0, psi0 = 0, A = B ------------------------------
    mo = dict(n=0.0, m=m_sp, psi0=0.0, theta0=0.0)
    cases.append(_case('14.1', '4.1.1 I a', 'theta0=0, mu1=mu2=0, k1=k2=0',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('14.1c', '4.1.1 I a', '14.1 plus h1*mu3=0 (here h1=0)',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), 0.0, h3, W)))
    mo2 = dict(n=0.0, m=-W, psi0=0.0, theta0=0.0)
    cases.append(_case('14.2', '4.1.1 I a', 'theta0=0, mu1=mu2=0, m=-Omega (k1,k2 free)',
                       mo2, _params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('14.2c', '4.1.1 I a', '14.2 plus h1*mu3=0 (here mu3=0)',
                       mo2, _params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0), h1, h3, W)))
    cases.append(_case('14.3', '4.1.1 I a',
                       'theta0=0, h1=0, k1=h3 mu1/(m+Omega), k2=h3 mu2/(m+Omega)', mo,
                       _params(As, As, Cs, (h3 * mu[0] / (m_sp + W), h3 * mu[1] / (m_sp + W), k3),
                                   mu, 0.0, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=0.0, theta0=th)
    cases.append(_case('17.1', '4.1.1 I b',
                       'h1=0, mu1=mu2=0, k1=k2=0, k3=(Omega^2(B-C)cos th0 - m Omega C + mu3 h3)/Omega',
                       mo, _params(As, As, Cs,
                                       (0, 0, (W ** 2 * (As - Cs) * np.cos(th) - m_sp * W * Cs + 0.6 * h3) / W),
                                       (0, 0, 0.6), 0.0, h3, W)))
    cases.append(_case('17.2', '4.1.1 I b', 'mu=0, k1=k2=0, k3=cos th0 (B-C) Omega - C m',
                       mo, _params(As, As, Cs, (0, 0, np.cos(th) * (As - Cs) * W - Cs * m_sp),
                                       (0, 0, 0), h1, h3, W)))
    # ---- 4.1.1 Case II : n = 0, psi0 = pi/2 ---------------------------------
    mo = dict(n=0.0, m=-W, psi0=np.pi / 2, theta0=np.pi / 3)
    k3_191 = (-0.6 * h1 + _S3 * (W ** 2 * (Aa + Ba - Ca) + 0.6 * h3)) / (_S3 * W)
    cases.append(_case('19.1', '4.1.1 II A!=B',
                       'cos th0=1/2, m=-Omega, mu1=mu2=0, k1=k2=0, '
                       'k3=(-mu3 h1 + sqrt3(Omega^2(A+B-C)+mu3 h3))/(sqrt3 Omega) [reading]',
                       mo, _params(Aa, Ba, Ca, (0, 0, k3_191), (0, 0, 0.6), h1, h3, W)))
    k3_191L = -0.6 * h1 * _S3 * (W ** 2 * (Aa + Ba - Ca) + 0.6 * h3) / (_S3 * W)
    cases.append(_case('19.1L', '4.1.1 II A!=B',
                       'as 19.1 but k3 read literally: -mu3 h1 sqrt3 (Omega^2(A+B-C)+mu3 h3)/(sqrt3 Omega)',
                       mo, _params(Aa, Ba, Ca, (0, 0, k3_191L), (0, 0, 0.6), h1, h3, W)))
    h1_192 = -_S3 * h3
    cases.append(_case('19.2', '4.1.1 II A!=B',
                       'cos th0=1/2, m=-Omega, h1=-sqrt3 h3, k1=2 mu1 h3/Omega, k2=2 mu2 h3/Omega, '
                       'k3=(Omega^2(A+B-C)+2 mu3 h3)/Omega',
                       mo, _params(Aa, Ba, Ca, (2 * mu[0] * h3 / W, 2 * mu[1] * h3 / W,
                                                    (W ** 2 * (Aa + Ba - Ca) + 2 * mu[2] * h3) / W),
                                       mu, h1_192, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=np.pi / 2, theta0=0.0)
    cases.append(_case('22', '4.1.1 II A=B', 'theta0=0, mu=0, k1=k2=0',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    cases.append(_case('23', '4.1.1 II A=B', 'theta0=0, h1=0, k1=mu1 h3/(m+Omega), k2=mu2 h3/(m+Omega)',
                       mo, _params(As, As, Cs, (h3 * mu[0] / (m_sp + W), h3 * mu[1] / (m_sp + W), k3),
                                       mu, 0.0, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=np.pi / 2, theta0=th)
    s, c = np.sin(th), np.cos(th)
    k3_24 = (s * (4 * c * (As - Cs) * W ** 2 - Cs * W * m_sp + 0.6 * h3) - 0.6 * h1 * c) / (W * s)
    cases.append(_case('24', '4.1.1 II A=B',
                       'k1=k2=0, mu1=mu2=0, k3=[sin th0(4 cos th0 (B-C) Omega^2 - C Omega m + mu3 h3)'
                       ' - mu3 h1 cos th0]/(Omega sin th0)',
                       mo, _params(As, As, Cs, (0, 0, k3_24), (0, 0, 0.6), h1, h3, W)))
    # ---- 4.1.2 : n != 0 ------------------------------------------------------
    psi0 = 0.6
    mo = dict(n=n_pr, m=n_pr, psi0=psi0, theta0=np.pi)
    sp0, cp0 = np.sin(psi0), np.cos(psi0)
    h1_27 = -1.5 * W ** 2 * (Aa - Ba) * np.sin(2 * psi0) / (mu[0] * sp0 - mu[1] * cp0)
    cases.append(_case('27', '4.1.2 (1)',
                       'theta0=pi, m=n, k1=(mu3 h1 cos psi0 + mu1 h3)/Omega, '
                       'k2=(mu3 h1 sin psi0 + mu2 h3)/Omega, h1=-3/2 Omega^2(A-B) sin2psi0/(mu1 sin psi0 - mu2 cos psi0)',
                       mo, _params(Aa, Ba, Ca, ((mu[2] * h1_27 * cp0 + mu[0] * h3) / W,
                                                    (mu[2] * h1_27 * sp0 + mu[1] * h3) / W, k3),
                                       mu, h1_27, h3, W)))
    mo = dict(n=n_pr, m=n_pr, psi0=psi0, theta0=0.0)
    cases.append(_case('29.1', '4.1.2 (2)',
                       'A=B, theta0=0, m=n, mu1=mu2=0, k1=mu3 h1 cos psi0/(Omega+2n), k2=mu3 h1 sin psi0/(Omega+2n)',
                       mo, _params(As, As, Cs, (0.6 * h1 * cp0 / (W + 2 * n_pr), 0.6 * h1 * sp0 / (W + 2 * n_pr), k3),
                                       (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('29.1c', '4.1.2 (2)',
                       'corrected: A=B, theta0=0, h1*mu=0, (Omega+n+m)k_i = h3 mu_i (i=1,2); here mu=(0,0,0.6), h1=0, k1=k2=0',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), 0.0, h3, W)))
    cases.append(_case('29.2', '4.1.2 (2)',
                       'A=B, theta0=0, m=n, h1=0, k1=mu1 h3/(Omega+2n), k2=mu2 h3/(Omega+2n)',
                       mo, _params(As, As, Cs, (mu[0] * h3 / (W + 2 * n_pr), mu[1] * h3 / (W + 2 * n_pr), k3),
                                       mu, 0.0, h3, W)))
    mo = dict(n=n_pr, m=2 * n_pr, psi0=psi0, theta0=np.pi)
    cases.append(_case('31.1', '4.1.2 (3)',
                       'A=B, theta0=pi, m=2n, h1=0, k1=-mu1 h3/(n-Omega), k2=-mu2 h3/(n-Omega)',
                       mo, _params(As, As, Cs, (-mu[0] * h3 / (n_pr - W), -mu[1] * h3 / (n_pr - W), k3),
                                       mu, 0.0, h3, W)))
    cases.append(_case('31.2a', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, k1=k2=0',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    mo = dict(n=W, m=2 * W, psi0=psi0, theta0=np.pi)
    cases.append(_case('31.2b', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, n=Omega (k1,k2 free)',
                       mo, _params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0), h1, h3, W)))
    # ---- 4.2 : irrational n/m (theta0 = 0) ------------------------------------
    n_ir, m_ir = 0.7, 0.9 * np.sqrt(2.0)
    mo = dict(n=n_ir, m=m_ir, psi0=psi0, theta0=0.0)
    kk = (0.3, -0.2, k3)
    wsum = W + m_ir + n_ir
    cases.append(_case('44.1', '4.2', 'A=B, theta0=0, h1=0, mu1=(Omega+m+n)k1/h3, mu2=(Omega+m+n)k2/h3',
                       mo, _params(As, As, Cs, kk, (wsum * kk[0] / h3, wsum * kk[1] / h3, 0.6), 0.0, h3, W)))
    cases.append(_case('44.2', '4.2', 'A=B, theta0=0, mu=0, k1=k2=0',
                       mo, _params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    mo = dict(n=n_ir, m=-(W + n_ir), psi0=psi0, theta0=0.0)
    cases.append(_case('44.3', '4.2', 'A=B, theta0=0, mu=0, n+m+Omega=0 (k1,k2 free)',
                       mo, _params(As, As, Cs, kk, (0, 0, 0), h1, h3, W)))
    # ---- families found in the re-derivation but not listed in the paper -----
    psiN, thN = 0.9, 0.7
    h1N = 3 * W ** 2 * (As - Cs) * np.sin(psiN) * np.sin(thN) / 0.6
    k3N = ((h3 * 0.6 - W * m_sp * Cs - W ** 2 * (Cs - As) * np.cos(thN) * (3 * np.sin(psiN) ** 2 + 1)) / W
           - h1N * 0.6 * np.sin(psiN) * np.cos(thN) / (W * np.sin(thN)))
    cases.append(_case('N1', 'new, n=0 A=B',
                       'A=B, n=0, general psi0: mu1=mu2=k1=k2=0, h1 mu3 = 3 Omega^2 (A-C) sin psi0 sin th0, '
                       'k3 = [h3 mu3 - Omega m C - Omega^2 (C-A) cos th0 (3 sin^2 psi0 + 1)]/Omega '
                       '- h1 mu3 sin psi0 cos th0/(Omega sin th0)',
                       dict(n=0.0, m=m_sp, psi0=psiN, theta0=thN),
                       _params(As, As, Cs, (0, 0, k3N), (0, 0, 0.6), h1N, h3, W)))
    cases.append(_case('N2', 'new, n=0 A!=B',
                       'mirror of 19.2: cos th0 = -1/2, m = +Omega, h1 = +sqrt3 h3, k1 = 2 mu1 h3/Omega, '
                       'k2 = 2 mu2 h3/Omega, k3 = -Omega(A+B-C) + 2 mu3 h3/Omega',
                       dict(n=0.0, m=W, psi0=np.pi / 2, theta0=2 * np.pi / 3),
                       _params(Aa, Ba, Ca, (2 * mu[0] * h3 / W, 2 * mu[1] * h3 / W,
                                                -W * (Aa + Ba - Ca) + 2 * mu[2] * h3 / W),
                                   mu, _S3 * h3, h3, W)))
    # body at rest in the orbital frame with e3 on the orbit normal (n ± m = 0): A != B allowed, against (26)
    mo = dict(n=n_pr, m=-n_pr, psi0=psi0, theta0=0.0)
    cases.append(_case('N3', 'new, theta0=0 rest',
                       'theta0=0, m=-n, A!=B: h1 (mu1 sin psi0 + mu2 cos psi0) = -3/2 Omega^2 (A-B) sin 2psi0, '
                       'k1 = (mu1 h3 - mu3 h1 cos psi0)/Omega, k2 = (mu2 h3 + mu3 h1 sin psi0)/Omega',
                       mo, normal_rest((Aa, Ba, Ca), mu, h3, W, 0.0, psi0, k3)))
    mo = dict(n=n_pr, m=-n_pr, psi0=0.0, theta0=0.0)
    cases.append(_case('N4', 'new, theta0=0 rest',
                       'theta0=0, m=-n, A!=B, principal axes on the orbital axes (sin 2psi0 = 0): h1 = 0, '
                       'k1 = mu1 h3/Omega, k2 = mu2 h3/Omega',
                       mo, normal_rest((Aa, Ba, Ca), mu, h3, W, 0.0, 0.0, k3)))
    mu5 = (0.0, -0.5, 0.6)
    mo = dict(n=n_pr, m=n_pr, psi0=np.pi / 2, theta0=np.pi)
    cases.append(_case('N5', 'new, theta0=pi rest',
                       'theta0=pi, m=n, A!=B, psi0=pi/2, mu1=0 (mu.beta = 0, where (27) is 0/0): h1 free, '
                       'k1 = (mu1 h3 + mu3 h1 cos psi0)/Omega, k2 = (mu2 h3 + mu3 h1 sin psi0)/Omega',
                       mo, normal_rest((Aa, Ba, Ca), mu5, h3, W, np.pi, np.pi / 2, k3, h1=h1)))
    return cases


CASES: list[Case] = build_cases()
BY_LABEL = {case.label: case for case in CASES}
