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


def _case(label, section, printed, motion, params):
    return Case(label, section, printed, Precession(*(float(motion[k]) for k in ("n", "m", "psi0", "theta0"))), params)


_S3 = np.sqrt(3.0)


def normal_rest(inertia, mu, h3, Omega, theta0: float, chi: float, k3: float = 0.0, h1: float | None = None,
                N: float | None = None) -> GyrostatParameters:
    """Parameters that make θ0 ∈ {0, π}, n ± m = 0 (rest in the orbital frame, ω = Ωγ) a solution at χ = ψ0 − σφ0:
    h1 μ·β = −(N/2)(A − B) sin 2χ, and k1, k2 from the components ⊥ γ; where μ·β = 0, ``h1`` is free and must be
    given (derivation and branches: docs/gyrostat.md, "Rest on the orbit normal")."""
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


W = 1.0
MU = (0.4, -0.5, 0.6)
H1, H3, K3 = 0.5, 0.3, 0.4
M_SP, N_PR = 1.3, 0.8
AA, BA, CA = 1.0, 1.4, 1.9          # asymmetric
AS, CS = 1.2, 2.0                   # symmetric A = B = AS
TH = 0.7
PSI0 = 0.6
N_IR, M_IR = 0.7, 0.9 * np.sqrt(2.0)  # an irrational n/m (4.2)
KK = (0.3, -0.2, K3)
PSI_N, TH_N = 0.9, 0.7                # family N1

# the printed or corrected conditions' values that are not a common number
_K3_191 = (-0.6 * H1 + _S3 * (W ** 2 * (AA + BA - CA) + 0.6 * H3)) / (_S3 * W)
_K3_191L = -0.6 * H1 * _S3 * (W ** 2 * (AA + BA - CA) + 0.6 * H3) / (_S3 * W)
_K3_24 = (np.sin(TH) * (4 * np.cos(TH) * (AS - CS) * W ** 2 - CS * W * M_SP + 0.6 * H3)
          - 0.6 * H1 * np.cos(TH)) / (W * np.sin(TH))
_H1_27 = -1.5 * W ** 2 * (AA - BA) * np.sin(2 * PSI0) / (MU[0] * np.sin(PSI0) - MU[1] * np.cos(PSI0))
_WSUM = W + M_IR + N_IR
_H1_N = 3 * W ** 2 * (AS - CS) * np.sin(PSI_N) * np.sin(TH_N) / 0.6
_K3_N = ((H3 * 0.6 - W * M_SP * CS - W ** 2 * (CS - AS) * np.cos(TH_N) * (3 * np.sin(PSI_N) ** 2 + 1)) / W
         - _H1_N * 0.6 * np.sin(PSI_N) * np.cos(TH_N) / (W * np.sin(TH_N)))

# the motions (n, m, ψ0, θ0) the cases share
_I = dict(n=0.0, m=M_SP, psi0=0.0, theta0=0.0)
_I_M = dict(n=0.0, m=-W, psi0=0.0, theta0=0.0)
_I_B = dict(n=0.0, m=M_SP, psi0=0.0, theta0=TH)
_II = dict(n=0.0, m=-W, psi0=np.pi / 2, theta0=np.pi / 3)
_II_AB = dict(n=0.0, m=M_SP, psi0=np.pi / 2, theta0=0.0)
_II_24 = dict(n=0.0, m=M_SP, psi0=np.pi / 2, theta0=TH)
_N_PI = dict(n=N_PR, m=N_PR, psi0=PSI0, theta0=np.pi)
_N_0 = dict(n=N_PR, m=N_PR, psi0=PSI0, theta0=0.0)
_N_31 = dict(n=N_PR, m=2 * N_PR, psi0=PSI0, theta0=np.pi)
_IR = dict(n=N_IR, m=M_IR, psi0=PSI0, theta0=0.0)

#: every case, with parameters satisfying its (printed or corrected) conditions (a data table: label, section,
#: condition, motion, parameters)
CASES: list[Case] = [
    # ---- 4.1.1 Case I : n = 0, psi0 = 0, A = B ------------------------------
    _case('14.1', '4.1.1 I a', 'theta0=0, mu1=mu2=0, k1=k2=0',
          _I, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0.6), H1, H3, W)),
    _case('14.1c', '4.1.1 I a', '14.1 plus h1*mu3=0 (here h1=0)',
          _I, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0.6), 0.0, H3, W)),
    _case('14.2', '4.1.1 I a', 'theta0=0, mu1=mu2=0, m=-Omega (k1,k2 free)',
          _I_M, _params(AS, AS, CS, (0.3, -0.2, K3), (0, 0, 0.6), H1, H3, W)),
    _case('14.2c', '4.1.1 I a', '14.2 plus h1*mu3=0 (here mu3=0)',
          _I_M, _params(AS, AS, CS, (0.3, -0.2, K3), (0, 0, 0), H1, H3, W)),
    _case('14.3', '4.1.1 I a', 'theta0=0, h1=0, k1=h3 mu1/(m+Omega), k2=h3 mu2/(m+Omega)',
          _I, _params(AS, AS, CS, (H3 * MU[0] / (M_SP + W), H3 * MU[1] / (M_SP + W), K3), MU, 0.0, H3, W)),
    _case('17.1', '4.1.1 I b', 'h1=0, mu1=mu2=0, k1=k2=0, k3=(Omega^2(B-C)cos th0 - m Omega C + mu3 h3)/Omega',
          _I_B, _params(AS, AS, CS, (0, 0, (W ** 2 * (AS - CS) * np.cos(TH) - M_SP * W * CS + 0.6 * H3) / W),
                        (0, 0, 0.6), 0.0, H3, W)),
    _case('17.2', '4.1.1 I b', 'mu=0, k1=k2=0, k3=cos th0 (B-C) Omega - C m',
          _I_B, _params(AS, AS, CS, (0, 0, np.cos(TH) * (AS - CS) * W - CS * M_SP), (0, 0, 0), H1, H3, W)),
    # ---- 4.1.1 Case II : n = 0, psi0 = pi/2 ---------------------------------
    _case('19.1', '4.1.1 II A!=B', 'cos th0=1/2, m=-Omega, mu1=mu2=0, k1=k2=0, '
          'k3=(-mu3 h1 + sqrt3(Omega^2(A+B-C)+mu3 h3))/(sqrt3 Omega) [reading]',
          _II, _params(AA, BA, CA, (0, 0, _K3_191), (0, 0, 0.6), H1, H3, W)),
    _case('19.1L', '4.1.1 II A!=B',
          'as 19.1 but k3 read literally: -mu3 h1 sqrt3 (Omega^2(A+B-C)+mu3 h3)/(sqrt3 Omega)',
          _II, _params(AA, BA, CA, (0, 0, _K3_191L), (0, 0, 0.6), H1, H3, W)),
    _case('19.2', '4.1.1 II A!=B', 'cos th0=1/2, m=-Omega, h1=-sqrt3 h3, k1=2 mu1 h3/Omega, k2=2 mu2 h3/Omega, '
          'k3=(Omega^2(A+B-C)+2 mu3 h3)/Omega',
          _II, _params(AA, BA, CA, (2 * MU[0] * H3 / W, 2 * MU[1] * H3 / W,
                                    (W ** 2 * (AA + BA - CA) + 2 * MU[2] * H3) / W), MU, -_S3 * H3, H3, W)),
    _case('22', '4.1.1 II A=B', 'theta0=0, mu=0, k1=k2=0',
          _II_AB, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0), H1, H3, W)),
    _case('23', '4.1.1 II A=B', 'theta0=0, h1=0, k1=mu1 h3/(m+Omega), k2=mu2 h3/(m+Omega)',
          _II_AB, _params(AS, AS, CS, (H3 * MU[0] / (M_SP + W), H3 * MU[1] / (M_SP + W), K3), MU, 0.0, H3, W)),
    _case('24', '4.1.1 II A=B', 'k1=k2=0, mu1=mu2=0, k3=[sin th0(4 cos th0 (B-C) Omega^2 - C Omega m + mu3 h3)'
          ' - mu3 h1 cos th0]/(Omega sin th0)',
          _II_24, _params(AS, AS, CS, (0, 0, _K3_24), (0, 0, 0.6), H1, H3, W)),
    # ---- 4.1.2 : n != 0 ------------------------------------------------------
    _case('27', '4.1.2 (1)', 'theta0=pi, m=n, k1=(mu3 h1 cos psi0 + mu1 h3)/Omega, '
          'k2=(mu3 h1 sin psi0 + mu2 h3)/Omega, h1=-3/2 Omega^2(A-B) sin2psi0/(mu1 sin psi0 - mu2 cos psi0)',
          _N_PI, _params(AA, BA, CA, ((MU[2] * _H1_27 * np.cos(PSI0) + MU[0] * H3) / W,
                                      (MU[2] * _H1_27 * np.sin(PSI0) + MU[1] * H3) / W, K3), MU, _H1_27, H3, W)),
    _case('29.1', '4.1.2 (2)',
          'A=B, theta0=0, m=n, mu1=mu2=0, k1=mu3 h1 cos psi0/(Omega+2n), k2=mu3 h1 sin psi0/(Omega+2n)',
          _N_0, _params(AS, AS, CS, (0.6 * H1 * np.cos(PSI0) / (W + 2 * N_PR), 0.6 * H1 * np.sin(PSI0) / (W + 2 * N_PR),
                                     K3), (0, 0, 0.6), H1, H3, W)),
    _case('29.1c', '4.1.2 (2)', 'corrected: A=B, theta0=0, h1*mu=0, (Omega+n+m)k_i = h3 mu_i (i=1,2); '
          'here mu=(0,0,0.6), h1=0, k1=k2=0',
          _N_0, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0.6), 0.0, H3, W)),
    _case('29.2', '4.1.2 (2)', 'A=B, theta0=0, m=n, h1=0, k1=mu1 h3/(Omega+2n), k2=mu2 h3/(Omega+2n)',
          _N_0, _params(AS, AS, CS, (MU[0] * H3 / (W + 2 * N_PR), MU[1] * H3 / (W + 2 * N_PR), K3), MU, 0.0, H3, W)),
    _case('31.1', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, h1=0, k1=-mu1 h3/(n-Omega), k2=-mu2 h3/(n-Omega)',
          _N_31, _params(AS, AS, CS, (-MU[0] * H3 / (N_PR - W), -MU[1] * H3 / (N_PR - W), K3), MU, 0.0, H3, W)),
    _case('31.2a', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, k1=k2=0',
          _N_31, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0), H1, H3, W)),
    _case('31.2b', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, n=Omega (k1,k2 free)',
          dict(n=W, m=2 * W, psi0=PSI0, theta0=np.pi), _params(AS, AS, CS, (0.3, -0.2, K3), (0, 0, 0), H1, H3, W)),
    # ---- 4.2 : irrational n/m (theta0 = 0) ------------------------------------
    _case('44.1', '4.2', 'A=B, theta0=0, h1=0, mu1=(Omega+m+n)k1/h3, mu2=(Omega+m+n)k2/h3',
          _IR, _params(AS, AS, CS, KK, (_WSUM * KK[0] / H3, _WSUM * KK[1] / H3, 0.6), 0.0, H3, W)),
    _case('44.2', '4.2', 'A=B, theta0=0, mu=0, k1=k2=0',
          _IR, _params(AS, AS, CS, (0, 0, K3), (0, 0, 0), H1, H3, W)),
    _case('44.3', '4.2', 'A=B, theta0=0, mu=0, n+m+Omega=0 (k1,k2 free)',
          dict(n=N_IR, m=-(W + N_IR), psi0=PSI0, theta0=0.0), _params(AS, AS, CS, KK, (0, 0, 0), H1, H3, W)),
    # ---- families found in the re-derivation but not listed in the paper -----
    _case('N1', 'new, n=0 A=B', 'A=B, n=0, general psi0: mu1=mu2=k1=k2=0, h1 mu3 = 3 Omega^2 (A-C) sin psi0 sin th0, '
          'k3 = [h3 mu3 - Omega m C - Omega^2 (C-A) cos th0 (3 sin^2 psi0 + 1)]/Omega '
          '- h1 mu3 sin psi0 cos th0/(Omega sin th0)',
          dict(n=0.0, m=M_SP, psi0=PSI_N, theta0=TH_N), _params(AS, AS, CS, (0, 0, _K3_N), (0, 0, 0.6), _H1_N, H3, W)),
    _case('N2', 'new, n=0 A!=B', 'mirror of 19.2: cos th0 = -1/2, m = +Omega, h1 = +sqrt3 h3, k1 = 2 mu1 h3/Omega, '
          'k2 = 2 mu2 h3/Omega, k3 = -Omega(A+B-C) + 2 mu3 h3/Omega',
          dict(n=0.0, m=W, psi0=np.pi / 2, theta0=2 * np.pi / 3),
          _params(AA, BA, CA, (2 * MU[0] * H3 / W, 2 * MU[1] * H3 / W, -W * (AA + BA - CA) + 2 * MU[2] * H3 / W),
                  MU, _S3 * H3, H3, W)),
    # body at rest in the orbital frame with e3 on the orbit normal (n ± m = 0): A != B allowed, against (26)
    _case('N3', 'new, theta0=0 rest', 'theta0=0, m=-n, A!=B: h1 (mu1 sin psi0 + mu2 cos psi0) = -3/2 Omega^2 (A-B) '
          'sin 2psi0, k1 = (mu1 h3 - mu3 h1 cos psi0)/Omega, k2 = (mu2 h3 + mu3 h1 sin psi0)/Omega',
          dict(n=N_PR, m=-N_PR, psi0=PSI0, theta0=0.0), normal_rest((AA, BA, CA), MU, H3, W, 0.0, PSI0, K3)),
    _case('N4', 'new, theta0=0 rest', 'theta0=0, m=-n, A!=B, principal axes on the orbital axes (sin 2psi0 = 0): '
          'h1 = 0, k1 = mu1 h3/Omega, k2 = mu2 h3/Omega',
          dict(n=N_PR, m=-N_PR, psi0=0.0, theta0=0.0), normal_rest((AA, BA, CA), MU, H3, W, 0.0, 0.0, K3)),
    _case('N5', 'new, theta0=pi rest', 'theta0=pi, m=n, A!=B, psi0=pi/2, mu1=0 (mu.beta = 0, where (27) is 0/0): '
          'h1 free, k1 = (mu1 h3 + mu3 h1 cos psi0)/Omega, k2 = (mu2 h3 + mu3 h1 sin psi0)/Omega',
          dict(n=N_PR, m=N_PR, psi0=np.pi / 2, theta0=np.pi),
          normal_rest((AA, BA, CA), (0.0, -0.5, 0.6), H3, W, np.pi, np.pi / 2, K3, h1=H1)),
]
BY_LABEL = {case.label: case for case in CASES}
