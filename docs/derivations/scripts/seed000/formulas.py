"""Formulas of seed 000 (A. I. Ismail, "The periodic rotary motions of a rigid body
in a new domain of angular velocity", J. Egypt. Math. Soc. 29:2, 2021), printed and
corrected, as plain numpy functions.  Pure numpy (scipy only in `integrate_full_model`).

Notation (paper's, with the CONSISTENT scaling established in the report):
    a = A/C, b = B/C,   A1 = (1-b)/a, B1 = (a-1)/b, C1 = b-a,  omega^2 = -A1*B1
    (x0, y0, z0) = unit vector of the centre of mass in body axes (paper: x0', y0', z0')
    c^2 = M g l / C,  k = N/c^2 (N = 3g/R),
    mu = r0/c   (LARGE parameter; the paper prints mu = c/r0, which is inconsistent
                 with its own eqs (1)-(2), see report section 2),
    eps = 1/mu,  gamma0'' = Gamma/mu (paper eq. 28),
    p1 = p/c, q1 = q/c, r1 = r/r0, tau = r0 t.
Ground-truth model (time in units 1/c, omega' = omega/c):
    I w' = (I w) x w + r_c x gamma + k gamma x (I gamma),  gamma' = gamma x w,
    I = diag(a, b, 1);   p' = p1, q' = q1, r' = mu r1, t' = tau/mu.

Main entry point for the package:  `large_parameter_solution(t, params)`.
"""
import numpy as np

# --------------------------------------------------------------------------
# parameters
# --------------------------------------------------------------------------
DEFAULT = dict(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=float(np.sqrt(1 - 0.25 - 0.09)),
               k=0.3, mu=20.0, Gamma=0.5, c=1.0)


def derived(P):
    """Constants of the paper: A1, B1, C1, omega^2, chi1, chi2, gamma0'' (eqs. 5, 7, 9, 10)."""
    a, b, x0, y0, z0, k, mu = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu'))
    g0 = P['Gamma'] / mu if 'gamma0pp' not in P else P['gamma0pp']
    A1, B1, C1 = (1 - b) / a, (a - 1) / b, b - a
    w2 = -A1 * B1
    chi1 = (-z0 * (1 / a - A1 / b) + k * g0 * (A1 - w2)) / (1 - w2)
    chi2 = chi1 + z0 / a - k * A1 * g0
    return dict(A1=A1, B1=B1, C1=C1, w2=w2, chi1=chi1, chi2=chi2, g0=g0, eps=1.0 / mu,
                Gam=g0 * mu)


# --------------------------------------------------------------------------
# models
# --------------------------------------------------------------------------
def full_model_rhs(t, X, P):
    """Ground truth, nondimensional (time 1/c): X = (p', q', r', gamma, gamma', gamma'').
    I w' = (I w) x w + r_c x gamma + k gamma x (I gamma),  gamma' = gamma x w,  I = diag(a,b,1)."""
    a, b, k, x, y, z = P['a'], P['b'], P['k'], P['x0'], P['y0'], P['z0']
    p, q, r, g1, g2, g3 = X
    # (I w) x w = (b q r - r q, r p - a p r, a p q - b q p)
    # gamma x (I gamma) = (g2 g3 - b g2 g3 ... ) = ((1-b) g2 g3, (a-1) g1 g3, (b-a) g1 g2)
    return np.array([
        ((b - 1) * q * r + (y * g3 - z * g2) + k * (1 - b) * g2 * g3) / a,
        ((1 - a) * p * r + (z * g1 - x * g3) + k * (a - 1) * g1 * g3) / b,
        (a - b) * p * q + (x * g2 - y * g1) + k * (b - a) * g1 * g2,
        g2 * r - g3 * q,
        g3 * p - g1 * r,
        g1 * q - g2 * p])


def full_model_rhs_vector(t, X, P):
    """Same as full_model_rhs, written literally with cross products (used as a check)."""
    a, b, k = P['a'], P['b'], P['k']
    I = np.array([a, b, 1.0])
    rc = np.array([P['x0'], P['y0'], P['z0']])
    w, g = X[:3], X[3:]
    dw = (np.cross(I * w, w) + np.cross(rc, g) + k * np.cross(g, I * g)) / I
    return np.concatenate([dw, np.cross(g, w)])


def system1_rhs(tau, Y, P):
    """The paper's eq. (1) in tau = r0 t, Y = (p1, q1, r1, gamma, gamma', gamma'')."""
    a, b, x, y, z, k, mu = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu'))
    A1, B1, C1 = (1 - b) / a, (a - 1) / b, b - a
    p, q, r, g1, g2, g3 = Y
    e = 1.0 / mu
    return np.array([
        -A1 * q * r + e / a * (g3 * y - g2 * z + k * a * A1 * g2 * g3),
        -B1 * p * r + e / b * (g1 * z - g3 * x + k * b * B1 * g3 * g1),
        e**2 * (-C1 * p * q + g2 * x - g1 * y + k * C1 * g1 * g2),
        r * g2 - e * q * g3,
        e * p * g3 - r * g1,
        e * (q * g1 - p * g2)])


def scaled_to_full(Y, P):
    """(p1,q1,r1,g,g',g'') -> ground-truth state (p',q',r',g,g',g'') with mu = r0/c."""
    Y = np.asarray(Y, float)
    X = Y.copy()
    X[2] = P['mu'] * Y[2]
    return X


def full_to_scaled(X, P):
    Y = np.asarray(X, float).copy()
    Y[2] = Y[2] / P['mu']
    return Y


def integrate_full_model(P, X0, t_eval, rtol=1e-13, atol=1e-13, extra_psi=False):
    """Integrate the ground-truth model with DOP853.  If extra_psi, also integrate the
    precession angle psi' = (p gamma + q gamma')/(1 - gamma''^2)."""
    from scipy.integrate import solve_ivp
    if extra_psi:
        def f(t, Z):
            d = full_model_rhs(t, Z[:6], P)
            p, q, g1, g2, g3 = Z[0], Z[1], Z[3], Z[4], Z[5]
            return np.concatenate([d, [(p * g1 + q * g2) / (1 - g3**2)]])
        Z0 = np.concatenate([X0, [0.0]])
    else:
        f = lambda t, Z: full_model_rhs(t, Z, P)
        Z0 = X0
    sol = solve_ivp(f, (t_eval[0], t_eval[-1]), Z0, method='DOP853', rtol=rtol, atol=atol,
                    t_eval=t_eval)
    assert sol.success, sol.message
    return sol.y


# --------------------------------------------------------------------------
# the paper's formulas AS PRINTED (all three extractions agree unless noted)
# --------------------------------------------------------------------------
def printed_solution_35(tau, P):
    """Eq. (35) as printed, M3 = 1, tau = r0 t (unstrained)."""
    d = derived(P)
    a, b, x, y, z, k, mu = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu'))
    e, g0, C1, A1, chi1, chi2, Gam = d['eps'], d['g0'], d['C1'], d['A1'], d['chi1'], d['chi2'], d['Gam']
    tau = np.asarray(tau, float)
    ct, st = np.cos(tau), np.sin(tau)
    p1 = e * (x * g0 / (1 - a) + chi1 * ct)
    q1 = e * (y * g0 / (1 - b) + chi2 / A1 * st)
    r1 = 1 - 0.25 * e**2 * (k * C1 + 4 * x * (1 - ct) + y * st - k * C1 * np.cos(2 * tau))
    g1 = ct - 0.5 * e**2 * Gam**2 * ct
    g2 = -st + 0.5 * e**2 * Gam**2 * st
    g3 = g0 + e**2 * (x * g0 / (1 - a) - 0.5 * C1 * (z / (a + b - 1) + 0.5 * k * g0)
                      - x * g0 / (1 - a) * ct + y * g0 / (1 - b) * st
                      + 0.25 * C1 * (2 * z / (a + b - 1) + k * g0) * np.cos(2 * tau))
    return dict(p1=p1, q1=q1, r1=r1, g1=g1, g2=g2, g3=g3)


def printed_period_36(P, n=1):
    """alpha(mu^-1) of eq. (36) as printed in 003/004 (gamma0''^2 in the first k-term;
    extraction 000 reads gamma0'^2 there, which is 0 at tau=0).  T = 2 pi n + alpha."""
    d = derived(P)
    a, b, x, z, k = (P[n_] for n_ in ('a', 'b', 'x0', 'z0', 'k'))
    e, g0, A1, B1, C1 = d['eps'], d['g0'], d['A1'], d['B1'], d['C1']
    M3 = 1.0
    return 2 * e**2 * np.pi * n * (M3 * x - z * g0 - 0.5 * k * (
        g0**2 * (b * B1 - a * A1) + B1 * g0 * (1 - g0) - 0.125 * C1 * M3**2))


def printed_euler_38(t, P, literal=True):
    """Eqs. (38)-(39) as printed, physical time t (units of P['c']), t0 = 0, M3 = 1.
    literal=True: exactly as printed (r0^-1 t in the trigonometric arguments,
    '0.25(chi1+chi2/A1) + sin 2 r0^-1 t', prefactor mu^-1 sqrt(Mgl/C)=mu^-1 c,
    mu = r0/c used for mu^-2).  Returns theta, psi, phi (psi0 = 0, phi0 = pi/2)."""
    d = derived(P)
    a, b, x, y, z, k, mu, c = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu', 'c'))
    g0, C1, A1, chi1, chi2 = d['g0'], d['C1'], d['A1'], d['chi1'], d['chi2']
    r0 = mu * c
    th0 = np.arccos(g0)
    w = 1 / r0 if literal else r0

    def th2(tt):
        return (y * g0 / (1 - b) * np.sin(w * tt) - x * g0 / (1 - a) * np.cos(w * tt)
                + 0.5 * C1 * (z / (a + b - 1) - 0.667 * k * g0) * np.cos(2 * w * tt))

    def ps1(tt):
        return (0.25 * (chi1 + chi2 / A1) + np.sin(2 * w * tt) + y * g0 / (1 - b) * np.cos(w * tt)
                + x * g0 / (1 - a) * np.sin(w * tt))
    t = np.asarray(t, float)
    theta = th0 + mu**-2 / np.sin(th0) * (th2(t) - th2(0.0))
    psi = 0.5 * c**2 / r0 * (chi1 - chi2 / A1) * t + c / mu * (ps1(t) - ps1(0.0))
    phi = np.pi / 2 + (w - 0.5 * c**2 / r0 * g0 * (chi1 - chi2 / A1)) * t
    return dict(theta=theta, psi=psi, phi=phi)


# --------------------------------------------------------------------------
# corrected formulas (derived in lindstedt.py, verified numerically in check_periodic.py)
# --------------------------------------------------------------------------
def corrected_frequency(P):
    """Omega = 2 pi / T (T = period in tau = r0 t):
    Omega = 1 - mu^-2 (x0 + k C1/4 - z0 gamma0'') + O(mu^-4)."""
    d = derived(P)
    e, g0, C1 = d['eps'], d['g0'], d['C1']
    return 1 - e**2 * (P['x0'] + 0.25 * P['k'] * C1 - P['z0'] * g0)


def corrected_period(P, n=1):
    """alpha = T - 2 pi n = 2 pi n mu^-2 (x0 - z0 gamma0'' + k C1/4) + O(mu^-4)."""
    return 2 * np.pi * n / corrected_frequency(P) - 2 * np.pi * n


def corrected_solution_scaled(tau, P):
    """Corrected periodic solution of system (1) in the strained time s = Omega*tau.
    Errors (measured): p1,q1 O(mu^-3); r1,gamma,gamma',gamma'' O(mu^-4)."""
    d = derived(P)
    a, b, x, y, z, k = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k'))
    e, g0, C1, A1, chi1, chi2 = d['eps'], d['g0'], d['C1'], d['A1'], d['chi1'], d['chi2']
    s = corrected_frequency(P) * np.asarray(tau, float)
    cs, ss, c2, s2, c3, s3 = np.cos(s), np.sin(s), np.cos(2 * s), np.sin(2 * s), np.cos(3 * s), np.sin(3 * s)
    kc = k * C1
    p1 = e * (x * g0 / (1 - a) + chi1 * cs)
    q1 = e * (y * g0 / (1 - b) + chi2 / A1 * ss)
    r1 = 1 - e**2 * (x * (1 - cs) + y * ss + 0.25 * kc * (1 - c2))
    g1 = (1 - 0.5 * g0**2) * cs + e**2 * (-kc / 16 * cs + kc / 16 * c3 - 0.5 * x * (1 - c2)
                                         + y * (ss - 0.5 * s2))
    g2 = -(1 - 0.5 * g0**2) * ss + e**2 * (-kc / 16 * ss - kc / 16 * s3 - 0.5 * x * s2
                                          + y * (cs - 0.5 - 0.5 * c2)
                                          - g0 * z * C1 / (a + b - 1) * ss)
    g3 = g0 + e**2 * (-z * C1 / (a + b - 1) * ss**2
                      + g0 * (x / (1 - a) * (1 - cs) + y / (1 - b) * ss - 0.25 * kc * (1 - c2)))
    return dict(p1=p1, q1=q1, r1=r1, g1=g1, g2=g2, g3=g3, s=s)


def corrected_euler(t, P):
    """Corrected Euler angles (gamma = sin th sin ph, gamma' = sin th cos ph, gamma'' = cos th),
    physical time t, psi(0) = 0, phi(0) = pi/2."""
    d = derived(P)
    a, b, x, y, z, k, mu, c = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu', 'c'))
    e, g0, C1, A1, chi1, chi2 = d['eps'], d['g0'], d['C1'], d['A1'], d['chi1'], d['chi2']
    r0 = mu * c
    Om = corrected_frequency(P)
    s = Om * r0 * np.asarray(t, float)
    th0 = np.arccos(g0)

    def th2(s_):  # theta = theta0 - mu^-2 cosec(theta0) [th2(s) - th2(0)]
        return (y * g0 / (1 - b) * np.sin(s_) - x * g0 / (1 - a) * np.cos(s_)
                + 0.5 * C1 * (z / (a + b - 1) + 0.5 * k * g0) * np.cos(2 * s_))

    def ps1(s_):
        return (0.25 * (chi1 + chi2 / A1) * np.sin(2 * s_) + y * g0 / (1 - b) * np.cos(s_)
                + x * g0 / (1 - a) * np.sin(s_))
    theta = th0 - e**2 / np.sin(th0) * (th2(s) - th2(0 * s))
    psi = 0.5 * c**2 / r0 * (chi1 - chi2 / A1) * np.asarray(t, float) + e**2 * (ps1(s) - ps1(0 * s))
    phi = np.pi / 2 + s + e**2 * (x * np.sin(s) + y * (np.cos(s) - 1) + k * C1 / 8 * np.sin(2 * s))
    return dict(theta=theta, psi=psi, phi=phi)


def large_parameter_solution(t, params):
    """Corrected large-parameter (mu = r0/c >> 1, i.e. FAST spin) periodic solution.

    Parameters
    ----------
    t : array, physical time (same units as 1/params['c']).
    params : dict with a=A/C, b=B/C, x0,y0,z0 (unit centre-of-mass direction),
             k = N/c^2, mu = r0/c (>> 1), Gamma = mu*gamma0'' (or gamma0pp directly),
             c = sqrt(Mgl/C) (default 1).
    Returns dict of arrays: p, q, r (physical angular velocity), g1, g2, g3 (direction
    cosines gamma, gamma', gamma'' of the fixed Z axis), theta, psi, phi (Euler angles),
    tau (= r0 t), s (= Omega tau), and the scalar period T (physical time).
    Initial state: gamma'(0) = 0, gamma''(0) = gamma0'', r(0) = r0.
    Accuracy: relative errors O(mu^-3) in p, q and O(mu^-4) in r, gamma's
    (measured in check_periodic.py); valid when omega is not close to 1, 2, 3.
    """
    P = dict(DEFAULT)
    P.update(params)
    c, mu = P['c'], P['mu']
    r0 = mu * c
    t = np.asarray(t, float)
    tau = r0 * t
    S = corrected_solution_scaled(tau, P)
    E = corrected_euler(t, P)
    T = 2 * np.pi / (corrected_frequency(P) * r0)
    return dict(p=c * S['p1'], q=c * S['q1'], r=r0 * S['r1'], g1=S['g1'], g2=S['g2'], g3=S['g3'],
                theta=E['theta'], psi=E['psi'], phi=E['phi'], tau=tau, s=S['s'], T=T)


if __name__ == '__main__':
    P = dict(DEFAULT)
    sol = large_parameter_solution(np.linspace(0, 0.5, 6), P)
    for key in ('p', 'q', 'r', 'g1', 'g2', 'g3', 'theta', 'psi', 'phi'):
        print(key, np.array2string(sol[key], precision=6))
    print('T =', sol['T'], ' printed alpha(36) =', printed_period_36(P), ' corrected alpha =', corrected_period(P))
