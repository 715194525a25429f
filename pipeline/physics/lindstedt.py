"""Numeric Poincaré–Lindstedt: the fast-spin periodic orbit of the heavy body as a series in ε = c/r0, any order.

The heavy body about a fixed point, with a torque U × γ + N γ × Iγ (uniform gravity, a vertical uniform magnetic
field, the Newtonian centre: every force with a compiled form that is symmetric about the vertical), in the
scaled variables of Ismail (2021) (``gyrolab.plugins.regimes.ismail2021``; p = c p1, q = c q1, r = r0 r1, τ = r0 t,
c² = |U|/C, a = A/C, b = B/C, (x0', y0', z0') = U/|U|, k = N/c²):

    ṗ1 = −A1 q1 r1 + ε[(γ''y0' − γ'z0')/a + kA1γ'γ''],    q̇1 = −B1 p1 r1 + ε[(γz0' − γ''x0')/b + kB1γ''γ],
    ṙ1 = ε²(−C1 p1 q1 + γ'x0' − γy0' + kC1γγ'),          γ̇ = r1γ' − εq1γ'',  γ̇' = εp1γ'' − r1γ,  γ̇'' = ε(q1γ − p1γ').

The periodic orbit through r1(0) = 1, γ'(0) = 0, γ''(0) = γ0''(ε) = g + Γε (``g`` a fixed tilt, or Γ the seed's
scaling γ0'' = Γ/μ, eq. 28) is sought as Y = Σ ε^k Y_k(s), s = Ωτ, Ω = Σ ε^k Ω_k, each Y_k a trigonometric
polynomial held by its samples on a uniform grid in s (products are exact: the grid resolves twice the highest
harmonic). No computer algebra: every coefficient is a number.

Order k is linear in Y_k around the generating motion Y_0 = (0, 0, 1, ρ cos s, −ρ sin s, g), ρ = √(1 − g²)::

    (p, q):  p_k' + A1 q_k = R_p,  q_k' + B1 p_k = R_q   → harmonic n: p_n = (A1 R_q,n − in R_p,n)/(n² − ω²)
    r, γ'':  r_k' = R_r,  γ''_k' = R_γ''                  (integrated; constants from r1(0) = 1, γ''(0) = γ0'')
    γ-mode:  z = γ_k + iγ'_k,  z' + iz = F + iρΩ_k e^{−is} → Ω_k from the resonant harmonic e^{−is}; its free
             amplitude from γ'(0) = 0 and |γ(0)| = 1.

The small divisors n² − ω² of the p-mode (n = 0 … k + 1 at order k) appear explicitly; ``small_divisors``
lists them. The solvability conditions left over (mean of R_r, mean of R_γ'', the real part of the resonant
γ-harmonic) are not imposed: the three first integrals (energy, area, |γ| = 1) satisfy them, and their residuals
(``consistency``) are a check of every order (round-off when the series is right).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from gyrolab.errors import ConfigError


@dataclass(frozen=True)
class Body:
    """The nondimensional body and field: a = A/C, b = B/C, unit U/|U| = (x0, y0, z0), k = N/c²."""

    a: float
    b: float
    x0: float
    y0: float
    z0: float
    k: float

    @property
    def coefficients(self) -> tuple[float, float, float]:
        """(A1, B1, C1) = ((1 − b)/a, (a − 1)/b, b − a) of Ismail's (2021) eq. (1); ω² = −A1B1."""
        return (1 - self.b) / self.a, (self.a - 1) / self.b, self.b - self.a


def _cauchy(u: np.ndarray, v: np.ndarray, k: int) -> np.ndarray:
    """ε^k coefficient of the product of two series held as (order, grid) arrays (entries above k ignored)."""
    return np.einsum("jm,jm->m", u[: k + 1], v[k::-1]) if k >= 0 else np.zeros(u.shape[1])


@dataclass
class LindstedtSeries:
    """Coefficients of the fast-spin orbit: ``fourier[k, i, m]`` (component i of Y_k, harmonic m) and ``omega[k]``."""

    body: Body
    tilt: tuple[float, float]  # γ0''(ε) = tilt[0] + tilt[1] ε
    fourier: np.ndarray
    omega: np.ndarray
    consistency: np.ndarray  # per order: max residual of the conditions the integrals must satisfy
    small_divisors: dict[int, float] = field(default_factory=dict)

    @property
    def max_order(self) -> int:
        return len(self.omega) - 1

    def _check(self, order: int | None) -> int:
        order = self.max_order if order is None else order
        if not 0 <= order <= self.max_order:
            raise ConfigError(f"series order {order} is not available; computed through {self.max_order}")
        return order

    def frequency(self, eps: complex, order: int | None = None):
        """Ω(ε) = Σ_{k ≤ order} Ω_k ε^k (τ-frequency: the τ-period is 2π/Ω)."""
        order = self._check(order)
        return np.polyval(self.omega[: order + 1][::-1], eps)

    def scaled(self, eps: complex, tau: np.ndarray, order: int | None = None) -> np.ndarray:
        """(p1, q1, r1, γ, γ', γ'') at times τ = r0 t, series through ε^order, shape (n, 6) (complex ε: complex)."""
        order = self._check(order)
        s = self.frequency(eps, order) * np.asarray(tau, dtype=float)  # complex for a complex ε
        harmonics = np.fft.fftfreq(self.fourier.shape[2], 1.0 / self.fourier.shape[2])
        # einsum, not tensordot: a BLAS call on arrays this small costs 10x more (and spins BLAS threads)
        summed = np.einsum("k,kim->im", eps ** np.arange(order + 1), self.fourier[: order + 1])
        out = np.exp(1j * np.outer(s, harmonics)) @ summed.T
        return np.real(out) if np.isrealobj(eps) else out  # a complex ε: the analytic continuation

    def norms(self) -> np.ndarray:
        """Max-norm of each Y_k over s and components (its size, as the radius estimates use it)."""
        return np.abs(self.fourier).sum(axis=2).max(axis=1)

    def radius(self) -> dict[str, float]:
        """Radius of convergence in ε, three ways (each from the coefficients only).

        ``root``: least-squares slope of log‖Y_k‖ over the upper half of the orders (Cauchy–Hadamard);
        ``domb_sykes``: the ratios |Ω_k/Ω_{k−2}|^½ extrapolated linearly in 1/k to 1/k = 0 (``domb_sykes_norm``:
        the same with ‖Y_k‖); ``pade``: the smallest |pole| of the diagonal Padé approximant of Ω (in ε², when Ω is
        even in ε as at a fixed tilt). Their accuracy on the Lagrange top: docs/regimes.md, "Radius of convergence".
        """
        n = self.norms()
        ks = np.arange(len(n))
        upper = ks >= max(2, len(n) // 2)
        good = upper & (n > 0)
        root = float(np.exp(-np.polyfit(ks[good], np.log(n[good]), 1)[0])) if good.sum() >= 2 else np.nan
        pade = np.nan
        w = self.omega
        even = bool(np.all(np.abs(w[1::2]) <= 1e-14 * np.max(np.abs(w))))
        coeffs, power = (w[::2], 2) if even else (w, 1)
        m = (len(coeffs) - 1) // 2
        if m >= 1:
            from scipy.interpolate import pade as pade_fit  # start-up: scipy.interpolate only for a Padé fit

            try:
                with warnings.catch_warnings():  # an ill-conditioned Padé system is expected near resonances
                    warnings.simplefilter("ignore")
                    _, q = pade_fit(list(coeffs[: 2 * m + 1]), m)
                poles = np.roots(q.coeffs)
                poles = poles[np.isfinite(poles)]
                pade = float(np.min(np.abs(poles)) ** (1 / power)) if poles.size else np.nan
            except (np.linalg.LinAlgError, ValueError):
                pade = np.nan
        # Domb–Sykes by ratios two orders apart: with a fixed tilt p, q carry the odd powers and r, γ the even ones
        # and Ω is even ((ε, p1, q1) → (−ε, −p1, −q1) symmetry), so consecutive ratios alternate
        return {"root": root, "domb_sykes": _domb_sykes(self.omega), "domb_sykes_norm": _domb_sykes(n), "pade": pade}

    def radius_of_convergence(self) -> float:
        """The median of the root-test, Domb–Sykes (Ω) and Padé estimates: robust to one of them failing.

        Far from resonances Domb–Sykes is the sharpest and the root test biased low (the k^(−3/2) of a square-root
        branch point); near ω = n the Domb–Sykes ratios oscillate, and Padé alone sometimes returns a spurious pole
        (a Froissart doublet): measured in docs/regimes.md, "Radius of convergence".
        """
        cached = self.__dict__.get("_radius_of_convergence")  # coefficients never change; auto asks every run
        if cached is None:
            r = self.radius()
            finite = [v for v in (r["root"], r["domb_sykes"], r["pade"]) if np.isfinite(v)]
            cached = self.__dict__["_radius_of_convergence"] = float(np.median(finite)) if finite else float("nan")
        return cached

    def error_estimate(self, eps: float, order: int, weights=(1.0, 1.0, 1.0, 1.0, 1.0, 1.0)) -> float:
        """Predicted max error of the order-``order`` series over one period: the first omitted term's size.

        max_i w_i ε^(N+1)‖Y_(N+1),i‖ plus the phase drift of one period, 2π ε^(N+1)|Ω_(N+1)| · max_i w_i‖Y_0,i'‖
        (``weights`` scale the components to the units wanted, e.g. (c, c, c/ε, 1, 1, 1) for model units).
        Needs order < max_order.
        """
        if order >= self.max_order:
            raise ConfigError(f"the error of order {order} needs the series through order {order + 1}")
        nxt = order + 1
        w = np.asarray(weights, dtype=float)
        term = np.abs(self.fourier[nxt]).sum(axis=1)
        harmonics = np.fft.fftfreq(self.fourier.shape[2], 1.0 / self.fourier.shape[2])
        speed = np.abs(self.fourier[0] * harmonics).sum(axis=1)
        return float(eps**nxt * (np.max(w * term) + 2 * np.pi * abs(self.omega[nxt]) * np.max(w * speed)))


def _domb_sykes(c: np.ndarray) -> float:
    """1/R from (|c_k/c_(k−2)|)^½ over the upper half of the orders, extrapolated linearly in 1/k to 1/k = 0."""
    ks, ratios = [], []
    for k in range(max(4, len(c) // 2), len(c)):
        if abs(c[k - 2]) > 1e-300 and abs(c[k]) > 1e-300:
            ks.append(1.0 / k)
            ratios.append(np.sqrt(abs(c[k] / c[k - 2])))
    if len(ratios) < 2:
        return float("nan")
    intercept = np.polyfit(ks, ratios, 1)[1]
    return float(1.0 / intercept) if intercept > 0 else float("nan")


def _integrate(values: np.ndarray, harmonics: np.ndarray) -> tuple[np.ndarray, float]:
    """Mean-free antiderivative (as a spectrum) of a grid function, and its mean (which must vanish)."""
    spec = np.fft.fft(values) / len(values)
    mean = float(abs(spec[0]))
    out = np.zeros_like(spec)
    nz = harmonics != 0
    out[nz] = spec[nz] / (1j * harmonics[nz])
    return out, mean


def series(body: Body, order: int, *, tilt: float = 0.0, tilt_slope: float = 0.0, grid: int | None = None,
           divisor_floor: float = 1e-10) -> LindstedtSeries:
    """The fast-spin periodic orbit's series through ε^order for γ0''(ε) = tilt + tilt_slope·ε."""
    if isinstance(order, bool) or not isinstance(order, (int, np.integer)) or order < 0:
        raise ConfigError(f"series order {order!r} must be a non-negative integer")
    if not -1 < tilt < 1:
        raise ConfigError(f"the fast-spin series needs a tilted axis, |γ0''| < 1, got γ0''={tilt:g}")
    A1, B1, C1 = body.coefficients
    if abs(A1) < 1e-14:
        raise ConfigError(f"the fast-spin series needs B ≠ C (b = {body.b:g})")
    M = grid or max(32, 4 * (order + 4))
    harmonics = np.fft.fftfreq(M, 1.0 / M)
    s = 2 * np.pi * np.arange(M) / M
    w2 = -A1 * B1
    divisors = harmonics**2 - w2
    needed = np.abs(harmonics) <= order + 2
    if np.any(np.abs(divisors[needed]) < divisor_floor):
        n = int(abs(harmonics[needed][np.argmin(np.abs(divisors[needed]))]))
        raise ConfigError(f"the fast-spin series is singular at the resonance ω = {n}: ω² = {w2:.12g}")
    a, b, x, y, z, kk = body.a, body.b, body.x0, body.y0, body.z0, body.k
    rho = np.sqrt(1 - tilt**2)
    Y = np.zeros((order + 2, 6, M))  # one spare row so that every Cauchy product can read index k
    Y[0] = [np.zeros(M), np.zeros(M), np.ones(M), rho * np.cos(s), -rho * np.sin(s), np.full(M, tilt)]
    D = np.zeros((order + 2, 6, M))  # d/ds of each Y_k
    D[0, 3], D[0, 4] = -rho * np.sin(s), -rho * np.cos(s)
    omega = np.zeros(order + 1)
    omega[0] = 1.0
    consistency = np.zeros(order + 1)
    g0 = np.array([tilt, tilt_slope] + [0.0] * order)
    for k in range(1, order + 1):
        p, q, r, g1, g2, g3 = (Y[:, i] for i in range(6))
        R = np.zeros((6, M))
        R[0] = -A1 * _cauchy(q, r, k)
        R[1] = -B1 * _cauchy(p, r, k)
        R[3] = _cauchy(r, g2, k)
        R[4] = -_cauchy(r, g1, k)
        j = k - 1
        R[0] += (g3[j] * y - g2[j] * z) / a + kk * A1 * _cauchy(g2, g3, j)
        R[1] += (g1[j] * z - g3[j] * x) / b + kk * B1 * _cauchy(g3, g1, j)
        R[3] -= _cauchy(q, g3, j)
        R[4] += _cauchy(p, g3, j)
        R[5] += _cauchy(q, g1, j) - _cauchy(p, g2, j)
        if k >= 2:
            j = k - 2
            R[2] += -C1 * _cauchy(p, q, j) + x * g2[j] - y * g1[j] + kk * C1 * _cauchy(g1, g2, j)
        for jj in range(1, k):
            R -= omega[jj] * D[k - jj]
        # (p, q): non-resonant, solved harmonic by harmonic; the small divisors n² − ω² appear here
        Rp, Rq = np.fft.fft(R[0]) / M, np.fft.fft(R[1]) / M
        pn = (A1 * Rq - 1j * harmonics * Rp) / divisors
        qn = (Rp - 1j * harmonics * pn) / A1
        # r, γ'': integrated; constants from r1(0) = 1 and γ''(0) = γ0''(ε)
        rn, mean_r = _integrate(R[2], harmonics)
        rn[0] = -rn.sum()
        g3n, mean_g3 = _integrate(R[5], harmonics)
        g3n[0] = g0[k] - g3n.sum()
        rk = np.real(np.fft.ifft(rn) * M)
        # γ-mode: z' + iz = F + iρΩ_k e^{−is}
        F = np.fft.fft(R[3] + rk * Y[0, 4] + 1j * (R[4] - rk * Y[0, 3])) / M
        res = harmonics == -1
        G = F[res][0]
        omega[k] = -G.imag / rho
        zn = np.zeros(M, dtype=complex)
        other = ~res
        zn[other] = F[other] / (1j * (harmonics[other] + 1))
        # free amplitude C of e^{−is}: γ'_k(0) = 0 and |γ(0)|² = 1 at order k
        g3k0 = float(np.real(g3n.sum()))
        lower = sum(Y[j, 3, 0] * Y[k - j, 3, 0] + Y[j, 4, 0] * Y[k - j, 4, 0] + Y[j, 5, 0] * Y[k - j, 5, 0]
                    for j in range(1, k))
        target = -(lower + 2 * tilt * g3k0) / (2 * rho)
        Z = zn.sum()
        zn[res] = (target - Z.real) - 1j * Z.imag
        consistency[k] = max(mean_r, mean_g3, abs(G.real) / rho)
        for i, spec in ((0, pn), (1, qn), (2, rn), (5, g3n)):
            Y[k, i] = np.real(np.fft.ifft(spec) * M)
            D[k, i] = np.real(np.fft.ifft(1j * harmonics * spec) * M)
        zt = np.fft.ifft(zn) * M
        dzt = np.fft.ifft(1j * harmonics * zn) * M
        Y[k, 3], Y[k, 4], D[k, 3], D[k, 4] = zt.real, zt.imag, dzt.real, dzt.imag
    fourier = np.fft.fft(Y[: order + 1], axis=2) / M
    fourier[np.abs(fourier) < 1e-300] = 0.0
    shown = {n: float(n * n - w2) for n in range(min(order + 2, M // 2))}
    return LindstedtSeries(body=body, tilt=(float(tilt), float(tilt_slope)), fourier=fourier, omega=omega,
                           consistency=consistency, small_divisors=shown)
