"""Corrected analytic periodic solution for the resonant case omega = 3
(M. O. Shaker, F. A. El-Barki, A. I. Ismail, "Singular value of the natural
frequency for the motion of rigid body"), case (i) M1 = M2 = 0 of eq. (23).

Pure numpy; verified against the full Euler-Poisson model (see
case_i_convergence.py, euler_angles.py) and against an independent
Lindstedt-Poincare derivation (lp_symbolic.py).

Units (ground-truth nondimensional model):
    inertia I = diag(a, b, 1) (a = A/C, b = B/C), time in 1/c (c^2 = M g l / C),
    angular velocity in c, k_gt = N / c^2 (N = 3 g / R),
    r_c = (x0, y0, z0) unit vector to the centre of mass (body axes),
    gamma = unit vector of the fixed Z axis in body axes.
    I w' = (I w) x w + r_c x gamma + k_gt gamma x (I gamma),  gamma' = gamma x w.

Paper's scaled quantities (eq. (5), (7)):
    gamma0'' = cos(theta0),  M3 = tan(theta0)  (exact, see note on (18), (31)),
    mu = c sqrt(gamma0'') / r0  (= sqrt(cos theta0) / r0 with r0 in units of c),
    k  = k_gt * gamma0''        (the PAPER's k = N gamma0''/c^2),
    tau = r0 t,  p = c sqrt(gamma0'') p1, q = c sqrt(gamma0'') q1, r = r0 r1,
    (gamma, gamma', gamma'') = gamma0'' (gamma1, gamma1', gamma1'').

Solution normalisation (t = 0 is the paper's instant t0 = 0):
    r(0) = r0, gamma''(0) = gamma0'', gamma'(0) = 0 (phi(0) = pi/2), psi(0) = psi0.
Phase: th = Omega * r0 * t with Omega = 2 pi / T_tau = 1 - alpha/(2 pi).

Accuracy (measured, case_i_convergence.py): p, q: O(mu^3) (relative to
c sqrt(gamma0'')), r/r0, gamma-components/gamma0'': O(mu^4), period: O(mu^4),
Euler angles over one period: O(mu^4).
"""
import numpy as np


def omega3_b(a):
    """b = B/C that makes omega^2 = (C-A)(C-B)/(AB) = 9 for given a = A/C."""
    return (1.0 - a) / (1.0 + 8.0 * a)


def natural_frequency_sq(a, b):
    """omega^2 = -A1 B1 = (1-a)(1-b)/(a b)."""
    return (1.0 - a) * (1.0 - b) / (a * b)


def constants(a, b, x0, y0, z0, k_gt, theta0, check=True):
    """All constants of the omega = 3 solution (paper (7), (21), (26), (28), corrected).

    Returns a dict.  Requires A1*B1 = -9 (omega = 3), which is only possible for
    NON-PHYSICAL inertia (a + b < 1, violates A + B >= C); see admissibility.py.
    """
    A1 = (1.0 - b) / a
    B1 = (a - 1.0) / b
    C1 = b - a
    if check and abs(A1 * B1 + 9.0) > 1e-10:
        raise ValueError(f'omega != 3: A1*B1 = {A1 * B1}')
    g0 = np.cos(theta0)
    M = np.tan(theta0)
    k = k_gt * g0                                   # paper's k
    e = x0 * A1 / (9.0 * b)                         # = x0/(1-a)
    e1 = (k * (9.0 - A1) + z0 * (1.0 / a - A1 / b)) / 8.0
    nu = -(1.0 + B1) / 8.0
    e2 = e1 + z0 / a - k * A1
    nu2 = nu - 1.0 / A1
    a1 = (a - 1.0) * (a + b - 2.0) / (2.0 * b)
    # CORRECTED (printed: 18k[1-(a+b)+ b M3^2/2])
    a2 = z0 / (a * b) * (3.0 * (a + b) - 2.0 * (2.0 * a * b + 1.0)) \
        + 18.0 * k * (1.0 - (a + b) + 0.25 * (a + b) * M ** 2)
    # CORRECTED resonant coefficient (printed L310 of (21) is wrong)
    L310 = k * z0 * C1 * (4.0 * b - 1.0) / (16.0 * a * b)
    l1 = M ** 3 * L310 / a2
    # CORRECTED period correction: alpha = alpha2 mu^2 (printed has k M3^2 (b-a))
    alpha2 = np.pi * (2.0 * M * x0 - 8.0 * nu * e1 - z0 / b
                      + k * (0.5 * M ** 2 * (b - a) - B1))
    return dict(a=a, b=b, x0=x0, y0=y0, z0=z0, k_gt=k_gt, theta0=theta0,
                A1=A1, B1=B1, C1=C1, g0=g0, M=M, k=k, e=e, e1=e1, e2=e2,
                nu=nu, nu2=nu2, a1=a1, a2=a2, L310=L310, l1=l1, alpha2=alpha2)


def mu_of(r0, theta0):
    """small parameter mu = c sqrt(gamma0'')/r0, r0 in units of c."""
    return np.sqrt(np.cos(theta0)) / r0


def period(r0, cst):
    """period of the body-frame motion, in units of 1/c:  T = (2 pi + alpha)/r0."""
    mu = mu_of(r0, cst['theta0'])
    return (2.0 * np.pi + cst['alpha2'] * mu ** 2) / r0


def scaled_series(th, mu, cst):
    """Scaled solution (p1, q1, r1, gamma1, gamma1', gamma1'') at phase th."""
    c = cst
    M, e, e1, e2, l1, A1, C1, k = c['M'], c['e'], c['e1'], c['e2'], c['l1'], c['A1'], c['C1'], c['k']
    a, b, x, y = c['a'], c['b'], c['x0'], c['y0']
    th = np.asarray(th, dtype=float)
    cs, sn = np.cos, np.sin
    p1 = mu * (e + e1 * M * cs(th) + l1 * cs(3 * th))
    q1 = mu / A1 * (y / a + e2 * M * sn(th) + 3.0 * l1 * sn(3 * th))
    r1 = 1.0 - mu ** 2 * M * (x * (1 - cs(th)) + y * sn(th) + 0.25 * k * C1 * M * (1 - cs(2 * th)))
    # O(mu^2) terms of gamma1, gamma1' (the V, W of (27), not printed in the paper)
    yA = y / (a * A1)
    g3 = a * l1 + C1 * k * M ** 3 / 16.0
    G2 = (e - 0.5 * M ** 2 * x) - (e + g3) * cs(th) + (y * M ** 2 - yA) * sn(th) \
        + 0.5 * M ** 2 * x * cs(2 * th) - 0.5 * M ** 2 * y * sn(2 * th) + g3 * cs(3 * th)
    h1 = e + a * l1 - C1 * k * M ** 3 / 16.0 + C1 * M * (c['z0'] / (a * b) - 4.0 * k) / 8.0
    H2 = (yA - 0.5 * y * M ** 2) + (y * M ** 2 - yA) * cs(th) + h1 * sn(th) \
        - 0.5 * M ** 2 * y * cs(2 * th) - 0.5 * M ** 2 * x * sn(2 * th) \
        + (3.0 * b / A1 * l1 - C1 * k * M ** 3 / 16.0) * sn(3 * th)
    K2 = M * (e * (1 - cs(th)) + yA * sn(th)
              + 0.25 * ((e1 + e2 / A1) * M + l1 * (3.0 / A1 - 1.0)) * (1 - cs(2 * th))
              + 0.125 * l1 * (1.0 + 3.0 / A1) * (1 - cs(4 * th)))
    g1 = M * cs(th) + mu ** 2 * G2
    g1p = -M * sn(th) + mu ** 2 * H2
    g1pp = 1.0 + mu ** 2 * K2
    return p1, q1, r1, g1, g1p, g1pp


def body_solution(t, r0, cst):
    """Angular velocity (p, q, r) [units c] and gamma-components at times t [1/c].
    Returns array shape (6, len(t)): p, q, r, gamma, gamma', gamma''."""
    mu = mu_of(r0, cst['theta0'])
    Om = 1.0 - cst['alpha2'] * mu ** 2 / (2.0 * np.pi)
    th = Om * r0 * np.asarray(t, dtype=float)
    p1, q1, r1, g1, g1p, g1pp = scaled_series(th, mu, cst)
    s = np.sqrt(cst['g0'])
    return np.array([s * p1, s * q1, r0 * r1, cst['g0'] * g1, cst['g0'] * g1p, cst['g0'] * g1pp])


def euler_angles(t, r0, cst, psi0=0.0):
    """Euler angles (theta, psi, phi) of the corrected eqs. (32)-(33), t0 = 0,
    phi0 = pi/2, Z-axis convention of (29): cos(theta) = gamma'',
    tan(phi) = gamma/gamma', psi' = (p gamma + q gamma')/(1 - gamma''^2)."""
    c = cst
    mu = mu_of(r0, c['theta0'])
    Om = 1.0 - c['alpha2'] * mu ** 2 / (2.0 * np.pi)
    t = np.asarray(t, dtype=float)
    s = Om * r0 * t
    th0, M, e, e1, e2, l1, A1, C1, k = (c[n] for n in ('theta0', 'M', 'e', 'e1', 'e2', 'l1', 'A1', 'C1', 'k'))
    x, y, a = c['x0'], c['y0'], c['a']
    yA = y / (a * A1)
    tn, ct = np.tan(th0), 1.0 / np.tan(th0)

    def th2(u):
        return (-e * np.cos(u) + yA * np.sin(u)
                - 0.25 * ((e1 + e2 / A1) * M + l1 * (3.0 / A1 - 1.0)) * np.cos(2 * u)
                - 0.125 * l1 * (1.0 + 3.0 / A1) * np.cos(4 * u))

    def ps2(u):
        return (e * np.sin(u) + yA * np.cos(u)
                + 0.25 * ((e1 + e2 / A1) * tn + l1 * (1.0 - 3.0 / A1)) * np.sin(2 * u)
                + 0.125 * l1 * (1.0 + 3.0 / A1) * np.sin(4 * u))

    def ph2(u):
        return ((x * tn - e * ct) * np.sin(u) + y * (tn - ct / (a * A1)) * np.cos(u)
                + 0.25 * (0.5 * k * C1 * tn ** 2 - e1 - e2 / A1 - l1 * ct + 3.0 * l1 * ct / A1) * np.sin(2 * u)
                - 0.125 * (1.0 + 3.0 / A1) * l1 * ct * np.sin(4 * u))

    theta = th0 - mu ** 2 * (th2(s) - th2(0.0))
    psi = psi0 + 0.5 / r0 * (e1 - e2 / A1) * t + mu ** 2 / np.sin(th0) * (ps2(s) - ps2(0.0))
    rate = r0 - (1.0 / r0) * (0.5 * np.cos(th0) * (e1 - e2 / A1) + np.sin(th0) * (x + 0.25 * k * C1 * tn))
    phi = 0.5 * np.pi + rate * t + mu ** 2 * (ph2(s) - ph2(0.0))
    return theta, psi, phi


def initial_state(r0, cst):
    """Initial condition (omega, gamma) at t = 0 of the periodic orbit, from the series
    (accurate to O(mu^3) in p, q)."""
    return body_solution(np.array([0.0]), r0, cst)[:, 0]


# Suggested figure body (documented in seed001_resonant_omega3.md)
FIGURE_BODY = dict(a=0.4, b=1.0 / 7.0, x0=0.48, y0=0.36, z0=0.8, k_gt=1.0,
                   theta0=float(np.arctan(0.75)))
FIGURE_R0 = float(np.sqrt(0.8) / 0.1)      # mu = 0.1


if __name__ == '__main__':
    cst = constants(**FIGURE_BODY)
    for kk in ('A1', 'B1', 'C1', 'M', 'k', 'e', 'e1', 'e2', 'nu', 'a1', 'a2', 'L310', 'l1', 'alpha2'):
        print(f'{kk:7s} = {cst[kk]: .12g}')
    print('T(mu=0.1) =', period(FIGURE_R0, cst))
