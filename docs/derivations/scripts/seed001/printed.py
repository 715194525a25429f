"""The paper's PRINTED formulas (seed 001), transcribed as literally as the
garbled PDF text allows, for comparison with the corrected ones (formulas.py).

Only unambiguous typographical garbles are repaired here (each marked 'garble'):
  * (27) 'gamma = gamma'_o {...}'  -> gamma0''  (prefactor of gamma),
  * (27) 'P = c sqrt(gamma'')'     -> c sqrt(gamma0'')  (same for q),
  * (33) '1/2 l cot(theta0)'       -> 1/2 l1 cot(theta0)  (l is not defined there).
Everything else (a2, L310, alpha, the r0^-1 in phi_2) is kept as printed.
Same units / conventions as formulas.py.
"""
import numpy as np
from formulas import mu_of


def constants(a, b, x0, y0, z0, k_gt, theta0):
    A1 = (1.0 - b) / a
    B1 = (a - 1.0) / b
    C1 = b - a
    g0 = np.cos(theta0)
    M = np.tan(theta0)                      # (31)
    k = k_gt * g0                           # (7): k = N gamma0''/c^2
    e = x0 * A1 / (9.0 * b)
    e1 = (k * (9.0 - A1) + z0 * (1.0 / a - A1 / b)) / 8.0
    nu = -(1.0 + B1) / 8.0
    e2 = e1 + z0 / a - k * A1
    a1 = (a - 1.0) * (a + b - 2.0) / (2.0 * b)                                   # (21)
    a2 = z0 / (a * b) * (3.0 * (a + b) - 2.0 * (2.0 * a * b + 1.0)) \
        + 18.0 * k * (1.0 - (a + b) + 0.5 * b * M ** 2)                            # (21)
    L310 = 0.25 * k * (8.0 * e1 * (a - b) - 0.5 * z0 * (1.0 / a - A1 / b) * (a - b)
                       + e2 * (1.0 - C1) + e1 * A1 + (A1 - 9.0) * (a * e1 + b * e2 / A1))  # (21)
    l1 = M ** 3 * L310 / a2                                                        # (26)
    alpha2 = np.pi * (2.0 * M * x0 - 8.0 * nu * e1 - z0 / b + k * (M ** 2 * (b - a) - B1))  # (28)
    return dict(a=a, b=b, x0=x0, y0=y0, z0=z0, k_gt=k_gt, theta0=theta0, A1=A1, B1=B1, C1=C1,
                g0=g0, M=M, k=k, e=e, e1=e1, e2=e2, nu=nu, a1=a1, a2=a2, L310=L310, l1=l1,
                alpha2=alpha2)


def body_solution(t, r0, c, l1=None):
    """(27) with tau = r0 t (no frequency correction, as printed). gamma, gamma':
    only the O(1) terms are printed (V_i, W_i not given).  l1 may be overridden."""
    mu = mu_of(r0, c['theta0'])
    tau = r0 * np.asarray(t, dtype=float)
    cs, sn = np.cos, np.sin
    M, e, e1, e2, A1, C1, k = c['M'], c['e'], c['e1'], c['e2'], c['A1'], c['C1'], c['k']
    a, b, x, y = c['a'], c['b'], c['x0'], c['y0']
    l1 = c['l1'] if l1 is None else l1
    s = np.sqrt(c['g0'])
    p = s * mu * (e + e1 * M * cs(tau) + l1 * cs(3 * tau))
    q = s * mu / A1 * (y / a + e2 * M * sn(tau) + 3 * l1 * sn(3 * tau))
    r = r0 * (1 - mu ** 2 * M * (x * (1 - cs(tau)) + y * sn(tau) + 0.25 * k * C1 * M * (1 - cs(2 * tau))))
    g = c['g0'] * M * cs(tau)
    gp = -c['g0'] * M * sn(tau)
    br = (0.5 * M * (e1 * a + b * e2 / A1) + a * e + x + 0.25 * k * C1 * M + a * l1
          - (x + a * e) * cs(tau) + y * (1 + b / (a * A1)) * sn(tau)
          + 0.5 * (3 * b * l1 / A1 - a * l1 - 0.5 * k * C1 * M - e1 * a * M - e2 * b * M / A1) * cs(2 * tau)
          - 0.5 * l1 * (a + 3 * b / A1) * cs(4 * tau))
    gpp = c['g0'] * (1 + mu ** 2 * M * br)
    return np.array([p, q, r, g, gp, gpp])


def period(r0, c):
    mu = mu_of(r0, c['theta0'])
    return (2 * np.pi + c['alpha2'] * mu ** 2) / r0


def euler_angles(t, r0, c, psi0=0.0, l1=None, half_not_r0inv=False, drop_cos4=False):
    """(32)-(33) with t0 = 0 (phi0 = pi/2), tau = r0 t.
    As printed, phi_2 contains 'r0^-1 k C1 tan^2' and '-1/4(1+3/A1) r0^-1 cos 4 r0 t';
    r0 is taken in units of c.  Flags allow testing the repairs separately."""
    mu = mu_of(r0, c['theta0'])
    t = np.asarray(t, dtype=float)
    u = r0 * t
    th0, e, e1, e2, A1, C1, k = (c[n] for n in ('theta0', 'e', 'e1', 'e2', 'A1', 'C1', 'k'))
    a, b, x, y = c['a'], c['b'], c['x0'], c['y0']
    l1 = c['l1'] if l1 is None else l1
    tn, ct = np.tan(th0), 1 / np.tan(th0)

    def th2(v):
        return (-(x + a * e) * np.cos(v) + y * (1 + b / (a * A1)) * np.sin(v)
                + 0.5 * (l1 * (3 * b / A1 - a) - tn * (0.5 * k * C1 + e1 * a + b * e2 / A1)) * np.cos(2 * v)
                - 0.5 * l1 * (a + 3 * b / A1) * np.cos(4 * v))

    def ps2(v):
        return (e * np.sin(v) + y / (a * A1) * np.cos(v)
                + 0.25 * ((e2 / A1 + e1) * tn + l1 * (1 - 3 / A1)) * np.sin(2 * v)
                + 0.125 * l1 * (1 + 3 / A1) * np.sin(4 * v))

    f = 0.5 if half_not_r0inv else 1.0 / r0

    def ph2(v):
        out = ((x * tn - e * ct) * np.sin(v) + y * (tn - ct / (a * A1)) * np.cos(v)
               + 0.25 * (f * k * C1 * tn ** 2 - e2 / A1 - e1 - l1 * ct + 3 * l1 * ct / A1) * np.sin(2 * v)
               - 0.25 * (1 + 3 / A1) * 0.5 * l1 * ct * np.sin(4 * v))
        if not drop_cos4:
            out = out - 0.25 * (1 + 3 / A1) * (1 / r0) * np.cos(4 * v)
        return out

    theta = th0 - mu ** 2 * (th2(u) - th2(0.0))
    psi = psi0 + 0.5 / r0 * (e1 - e2 / A1) * t + mu ** 2 / np.sin(th0) * (ps2(u) - ps2(0.0))
    rate = r0 - (1 / r0) * (0.5 * np.cos(th0) * (e1 - e2 / A1) + np.sin(th0) * (x + 0.25 * k * C1 * tn))
    phi = 0.5 * np.pi + rate * t + mu ** 2 * (ph2(u) - ph2(0.0))
    return theta, psi, phi
