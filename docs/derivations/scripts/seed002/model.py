"""Satellite-gyrostat on a circular orbit: gravity-gradient + magnetic torques.

Reference model for Yehia & El-kenani, J. Appl. Comput. Mech. 7(4) 2021
("Effect of the gravity and magnetic field to find regular precessions of a
satellite-gyrostat with principal axes on a circular orbit").

Pure numpy.  All vectors are BODY components (principal axes e1, e2, e3).

Conventions (see docs/derivations/seed002_gyrostat.md)
------------------------------------------------------
* Orbital frame: alpha = radial (Earth -> satellite), beta = along-track,
  gamma = orbit normal; it rotates with constant rate Omega about gamma.
* Euler angles (psi, theta, phi) of the body w.r.t. the orbital frame,
  z-x-z convention: R = Rz(psi) Rx(theta) Rz(phi) maps body -> orbital
  components; alpha, beta, gamma are the rows of R (paper eq. 1).
* omega_rel = omega' = angular velocity relative to the orbital frame;
  absolute angular velocity omega = omega' + Omega*gamma.
* Potential (paper eq. 3, sign kept as printed):
      V = 3/2 Omega^2 alpha.I alpha + mu.(h1 alpha + h3 gamma)
  The magnetic part is +mu.H; the physical dipole energy is -mu.H, so the
  paper's (h1, h3) are MINUS the physical field components.  Nothing below
  depends on that choice except the sign of h1, h3.
* Lagrangian (paper eq. 2): L = 1/2 omega.I omega + omega.k - V.

Equations of motion (vector form), state y = [omega, alpha, beta, gamma]:
      I domega/dt + omega x (I omega + k) = M,
      M = 3 Omega^2 alpha x I alpha + h1 alpha x mu + h3 gamma x mu,
      d alpha/dt = alpha x omega',  d beta/dt = beta x omega',
      d gamma/dt = gamma x omega',  omega' = omega - Omega gamma.
Jacobi integral:
      H = 1/2 omega.I omega - Omega gamma.(I omega + k) + V.
"""
import numpy as np

# ----------------------------------------------------------------------------
# parameters
# ----------------------------------------------------------------------------


def make_params(A, B, C, k=(0.0, 0.0, 0.0), mu=(0.0, 0.0, 0.0), h1=0.0,
                h3=0.0, Omega=1.0):
    """Return a parameter dict with numpy arrays for k and mu."""
    return dict(A=float(A), B=float(B), C=float(C),
                k=np.asarray(k, dtype=float), mu=np.asarray(mu, dtype=float),
                h1=float(h1), h3=float(h3), Omega=float(Omega))


def inertia(p):
    return np.array([p['A'], p['B'], p['C']])


# ----------------------------------------------------------------------------
# kinematics (paper eq. 1)
# ----------------------------------------------------------------------------


def frames_from_euler(psi, theta, phi):
    """alpha, beta, gamma (body components) from the Euler angles, eq. (1)."""
    sps, cps = np.sin(psi), np.cos(psi)
    sth, cth = np.sin(theta), np.cos(theta)
    sph, cph = np.sin(phi), np.cos(phi)
    alpha = np.array([cps * cph - cth * sph * sps,
                      -cps * sph - cth * cph * sps,
                      sth * sps])
    beta = np.array([sps * cph + cth * sph * cps,
                     -sps * sph + cth * cph * cps,
                     -sth * cps])
    gamma = np.array([sth * sph, sth * cph, cth])
    return alpha, beta, gamma


def kin_matrix(theta, phi):
    """J(q) with omega' = J(q) qdot, qdot = (dpsi, dtheta, dphi), eq. (1)."""
    sth, cth = np.sin(theta), np.cos(theta)
    sph, cph = np.sin(phi), np.cos(phi)
    return np.array([[sth * sph, cph, 0.0],
                     [sth * cph, -sph, 0.0],
                     [cth, 0.0, 1.0]])


def omega_rel(q, qd):
    """omega' (relative to the orbital frame), eq. (1)."""
    return kin_matrix(q[1], q[2]) @ np.asarray(qd, dtype=float)


def state_from_euler(q, qd, p):
    """State y = [omega(abs), alpha, beta, gamma] from Euler angles and rates."""
    al, be, ga = frames_from_euler(*q)
    w = omega_rel(q, qd) + p['Omega'] * ga
    return np.concatenate([w, al, be, ga])


def euler_from_state(y):
    """(psi, theta, phi) from a state; theta computed with atan2 (robust at 0, pi)."""
    al, be, ga = y[3:6], y[6:9], y[9:12]
    theta = np.arctan2(np.hypot(ga[0], ga[1]), ga[2])
    phi = np.arctan2(ga[0], ga[1])
    psi = np.arctan2(al[2], -be[2])
    return psi, theta, phi


def theta_of_state(y):
    ga = y[9:12]
    return np.arctan2(np.hypot(ga[0], ga[1]), ga[2])


# ----------------------------------------------------------------------------
# vector form
# ----------------------------------------------------------------------------


def potential(alpha, gamma, p):
    I = inertia(p)
    return (1.5 * p['Omega'] ** 2 * alpha @ (I * alpha)
            + p['mu'] @ (p['h1'] * alpha + p['h3'] * gamma))


def torque(alpha, gamma, p):
    """M = alpha x dV/dalpha + gamma x dV/dgamma (body components)."""
    I = inertia(p)
    mu = p['mu']
    return (3.0 * p['Omega'] ** 2 * np.cross(alpha, I * alpha)
            + p['h1'] * np.cross(alpha, mu) + p['h3'] * np.cross(gamma, mu))


def rhs_vector(t, y, p):
    """Right-hand side of the vector equations; y = [omega, alpha, beta, gamma]."""
    I = inertia(p)
    w, al, be, ga = y[0:3], y[3:6], y[6:9], y[9:12]
    G = I * w + p['k']
    wd = (torque(al, ga, p) - np.cross(w, G)) / I
    wr = w - p['Omega'] * ga
    return np.concatenate([wd, np.cross(al, wr), np.cross(be, wr),
                           np.cross(ga, wr)])


def jacobi(y, p):
    """Jacobi integral H = 1/2 w.Iw - Omega gamma.(Iw + k) + V."""
    I = inertia(p)
    w, al, ga = y[0:3], y[3:6], y[9:12]
    return (0.5 * w @ (I * w) - p['Omega'] * ga @ (I * w + p['k'])
            + potential(al, ga, p))


def vector_residual(q, qd, qdd, p):
    """Residual R = I dw/dt + w x (I w + k) - M of the Euler equations for a
    motion prescribed through Euler angles q(t) with rates qd, accelerations qdd
    (Poisson equations then hold identically).  Body components."""
    psi, th, ph = q
    dps, dth, dph = qd
    I = inertia(p)
    al, be, ga = frames_from_euler(psi, th, ph)
    J = kin_matrix(th, ph)
    sth, cth, sph, cph = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    # dJ/dt
    Jd = np.array([[cth * sph * dth + sth * cph * dph, -sph * dph, 0.0],
                   [cth * cph * dth - sth * sph * dph, -cph * dph, 0.0],
                   [-sth * dth, 0.0, 0.0]])
    wr = J @ qd
    w = wr + p['Omega'] * ga
    wrd = J @ qdd + Jd @ qd
    gad = np.cross(ga, wr)
    wd = wrd + p['Omega'] * gad
    return I * wd + np.cross(w, I * w + p['k']) - torque(al, ga, p)


# ----------------------------------------------------------------------------
# Euler-angle (Lagrange) form, derived with sympy (derive_euler_lagrange.py)
# E_q = d/dt dL/dqdot - dL/dq = Mass(q) qdd + gyro(q, qd) + dV/dq
# ----------------------------------------------------------------------------


def mass_matrix(q, p):
    A, B, C = p['A'], p['B'], p['C']
    _, th, ph = q
    sth, cth = np.sin(th), np.cos(th)
    s2p = np.sin(2 * ph)
    a = A * np.sin(ph) ** 2 + B * np.cos(ph) ** 2
    b = A * np.cos(ph) ** 2 + B * np.sin(ph) ** 2
    m12 = 0.5 * (A - B) * s2p * sth
    return np.array([[a * sth ** 2 + C * cth ** 2, m12, C * cth],
                     [m12, b, 0.0],
                     [C * cth, 0.0, C]])


def potential_gradient(q, p):
    """dV/d(psi, theta, phi) using dalpha/dpsi=-beta, dalpha/dtheta=sin(psi)gamma,
    dalpha/dphi=(a2,-a1,0), dgamma/dtheta=(cth sph, cth cph, -sth),
    dgamma/dphi=(g2,-g1,0) (partial derivatives of eq. 1)."""
    psi, th, ph = q
    I = inertia(p)
    al, be, ga = frames_from_euler(psi, th, ph)
    Va = 3.0 * p['Omega'] ** 2 * I * al + p['h1'] * p['mu']   # dV/dalpha
    Vg = p['h3'] * p['mu']                                     # dV/dgamma
    dga_dth = np.array([np.cos(th) * np.sin(ph), np.cos(th) * np.cos(ph),
                        -np.sin(th)])
    V_psi = -Va @ be
    V_th = np.sin(psi) * (Va @ ga) + Vg @ dga_dth
    V_ph = Va @ np.array([al[1], -al[0], 0.0]) + Vg @ np.array([ga[1], -ga[0], 0.0])
    return np.array([V_psi, V_th, V_ph])


def gyro_terms(q, qd, p):
    """Velocity-dependent part of the Lagrange equations (no accelerations,
    no potential): quadratic, Coriolis-type (Omega) and gyrostat (k) terms."""
    A, B, C, W = p['A'], p['B'], p['C'], p['Omega']
    k1, k2, k3 = p['k']
    _, th, ph = q
    dps, dth, dph = qd
    sth, cth = np.sin(th), np.cos(th)
    sph, cph = np.sin(ph), np.cos(ph)
    s2p, c2p, s2t = np.sin(2 * ph), np.cos(2 * ph), np.sin(2 * th)
    D = A - B
    a = A * sph ** 2 + B * cph ** 2
    P = dps + W                      # psi-dot plus orbital rate
    kc = k1 * sph + k2 * cph
    ks = k1 * cph - k2 * sph
    E_psi = (0.5 * D * s2p * cth * dth ** 2
             + dth * ((D * c2p - C) * sth * dph + (a - C) * s2t * P
                      + cth * kc - k3 * sth)
             + dph * sth * (D * s2p * sth * P + ks))
    E_th = (-(a - C) * sth * cth * P ** 2
            + P * ((D * c2p + C) * sth * dph - cth * kc + k3 * sth)
            - D * s2p * dph * dth - kc * dph)
    E_ph = (0.5 * D * s2p * dth ** 2
            + dth * (-(D * c2p + C) * sth * P + kc)
            - 0.5 * D * s2p * sth ** 2 * P ** 2
            - sth * ks * P)
    return np.array([E_psi, E_th, E_ph])


def euler_angle_eqs(q, qd, qdd, p):
    """Lagrange equations E(q, qd, qdd) (=0 on motions), derived from eq. (2)."""
    return (mass_matrix(q, p) @ np.asarray(qdd, dtype=float)
            + gyro_terms(q, qd, p) + potential_gradient(q, p))


def rhs_euler(t, x, p):
    """First-order ODE in Euler angles, x = [psi, theta, phi, dpsi, dtheta, dphi]
    (singular at sin(theta) = 0)."""
    q, qd = x[:3], x[3:]
    f = gyro_terms(q, qd, p) + potential_gradient(q, p)
    qdd = np.linalg.solve(mass_matrix(q, p), -f)
    return np.concatenate([qd, qdd])


# ----------------------------------------------------------------------------
# regular precession psi = n t + psi0, theta = theta0, phi = m t
# ----------------------------------------------------------------------------


def precession_q(t, n, m, psi0, theta0):
    return np.array([n * t + psi0, theta0, m * t]), np.array([n, 0.0, m])


def precession_residual(p, n, m, psi0, theta0, t):
    """max over times t of |R| (vector Euler equations) along the precession."""
    out = 0.0
    for ti in np.atleast_1d(t):
        q, qd = precession_q(ti, n, m, psi0, theta0)
        out = max(out, np.linalg.norm(vector_residual(q, qd, np.zeros(3), p)))
    return out


# ----------------------------------------------------------------------------
# case catalogue (one concrete parameter set per printed condition set)
# ----------------------------------------------------------------------------
# Omega = 1 throughout.  Common numbers: asymmetric body A,B,C = 1.0,1.4,1.9;
# symmetric body A = B = 1.2, C = 2.0; generic mu = (0.4,-0.5,0.6),
# h1 = 0.5, h3 = 0.3, k3 = 0.4, spin m = 1.3, precession n = 0.8.

_S3 = np.sqrt(3.0)


def _case(label, section, printed, motion, params, note=''):
    return dict(label=label, section=section, printed=printed,
                motion=motion, params=params, note=note)


def build_cases():
    """Return the list of cases.  Each entry: label (paper equation number,
    '.j' = j-th set), printed condition (text), motion dict (n, m, psi0,
    theta0) and a parameter dict satisfying the PRINTED conditions.  Labels
    ending in 'c' are corrected sets (see report); '19.1L' is the literal
    reading of the garbled printed k3 in (19.1)."""
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
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('14.1c', '4.1.1 I a', '14.1 plus h1*mu3=0 (here h1=0)',
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), 0.0, h3, W)))
    mo2 = dict(n=0.0, m=-W, psi0=0.0, theta0=0.0)
    cases.append(_case('14.2', '4.1.1 I a', 'theta0=0, mu1=mu2=0, m=-Omega (k1,k2 free)',
                       mo2, make_params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('14.2c', '4.1.1 I a', '14.2 plus h1*mu3=0 (here mu3=0)',
                       mo2, make_params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0), h1, h3, W)))
    cases.append(_case('14.3', '4.1.1 I a',
                       'theta0=0, h1=0, k1=h3 mu1/(m+Omega), k2=h3 mu2/(m+Omega)', mo,
                       make_params(As, As, Cs, (h3 * mu[0] / (m_sp + W), h3 * mu[1] / (m_sp + W), k3),
                                   mu, 0.0, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=0.0, theta0=th)
    cases.append(_case('17.1', '4.1.1 I b',
                       'h1=0, mu1=mu2=0, k1=k2=0, k3=(Omega^2(B-C)cos th0 - m Omega C + mu3 h3)/Omega',
                       mo, make_params(As, As, Cs,
                                       (0, 0, (W ** 2 * (As - Cs) * np.cos(th) - m_sp * W * Cs + 0.6 * h3) / W),
                                       (0, 0, 0.6), 0.0, h3, W)))
    cases.append(_case('17.2', '4.1.1 I b', 'mu=0, k1=k2=0, k3=cos th0 (B-C) Omega - C m',
                       mo, make_params(As, As, Cs, (0, 0, np.cos(th) * (As - Cs) * W - Cs * m_sp),
                                       (0, 0, 0), h1, h3, W)))
    # ---- 4.1.1 Case II : n = 0, psi0 = pi/2 ---------------------------------
    mo = dict(n=0.0, m=-W, psi0=np.pi / 2, theta0=np.pi / 3)
    k3_191 = (-0.6 * h1 + _S3 * (W ** 2 * (Aa + Ba - Ca) + 0.6 * h3)) / (_S3 * W)
    cases.append(_case('19.1', '4.1.1 II A!=B',
                       'cos th0=1/2, m=-Omega, mu1=mu2=0, k1=k2=0, '
                       'k3=(-mu3 h1 + sqrt3(Omega^2(A+B-C)+mu3 h3))/(sqrt3 Omega) [reading]',
                       mo, make_params(Aa, Ba, Ca, (0, 0, k3_191), (0, 0, 0.6), h1, h3, W)))
    k3_191L = -0.6 * h1 * _S3 * (W ** 2 * (Aa + Ba - Ca) + 0.6 * h3) / (_S3 * W)
    cases.append(_case('19.1L', '4.1.1 II A!=B',
                       'as 19.1 but k3 read literally: -mu3 h1 sqrt3 (Omega^2(A+B-C)+mu3 h3)/(sqrt3 Omega)',
                       mo, make_params(Aa, Ba, Ca, (0, 0, k3_191L), (0, 0, 0.6), h1, h3, W)))
    h1_192 = -_S3 * h3
    cases.append(_case('19.2', '4.1.1 II A!=B',
                       'cos th0=1/2, m=-Omega, h1=-sqrt3 h3, k1=2 mu1 h3/Omega, k2=2 mu2 h3/Omega, '
                       'k3=(Omega^2(A+B-C)+2 mu3 h3)/Omega',
                       mo, make_params(Aa, Ba, Ca, (2 * mu[0] * h3 / W, 2 * mu[1] * h3 / W,
                                                    (W ** 2 * (Aa + Ba - Ca) + 2 * mu[2] * h3) / W),
                                       mu, h1_192, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=np.pi / 2, theta0=0.0)
    cases.append(_case('22', '4.1.1 II A=B', 'theta0=0, mu=0, k1=k2=0',
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    cases.append(_case('23', '4.1.1 II A=B', 'theta0=0, h1=0, k1=mu1 h3/(m+Omega), k2=mu2 h3/(m+Omega)',
                       mo, make_params(As, As, Cs, (h3 * mu[0] / (m_sp + W), h3 * mu[1] / (m_sp + W), k3),
                                       mu, 0.0, h3, W)))
    mo = dict(n=0.0, m=m_sp, psi0=np.pi / 2, theta0=th)
    s, c = np.sin(th), np.cos(th)
    k3_24 = (s * (4 * c * (As - Cs) * W ** 2 - Cs * W * m_sp + 0.6 * h3) - 0.6 * h1 * c) / (W * s)
    cases.append(_case('24', '4.1.1 II A=B',
                       'k1=k2=0, mu1=mu2=0, k3=[sin th0(4 cos th0 (B-C) Omega^2 - C Omega m + mu3 h3)'
                       ' - mu3 h1 cos th0]/(Omega sin th0)',
                       mo, make_params(As, As, Cs, (0, 0, k3_24), (0, 0, 0.6), h1, h3, W)))
    # ---- 4.1.2 : n != 0 ------------------------------------------------------
    psi0 = 0.6
    mo = dict(n=n_pr, m=n_pr, psi0=psi0, theta0=np.pi)
    sp0, cp0 = np.sin(psi0), np.cos(psi0)
    h1_27 = -1.5 * W ** 2 * (Aa - Ba) * np.sin(2 * psi0) / (mu[0] * sp0 - mu[1] * cp0)
    cases.append(_case('27', '4.1.2 (1)',
                       'theta0=pi, m=n, k1=(mu3 h1 cos psi0 + mu1 h3)/Omega, '
                       'k2=(mu3 h1 sin psi0 + mu2 h3)/Omega, h1=-3/2 Omega^2(A-B) sin2psi0/(mu1 sin psi0 - mu2 cos psi0)',
                       mo, make_params(Aa, Ba, Ca, ((mu[2] * h1_27 * cp0 + mu[0] * h3) / W,
                                                    (mu[2] * h1_27 * sp0 + mu[1] * h3) / W, k3),
                                       mu, h1_27, h3, W)))
    mo = dict(n=n_pr, m=n_pr, psi0=psi0, theta0=0.0)
    cases.append(_case('29.1', '4.1.2 (2)',
                       'A=B, theta0=0, m=n, mu1=mu2=0, k1=mu3 h1 cos psi0/(Omega+2n), k2=mu3 h1 sin psi0/(Omega+2n)',
                       mo, make_params(As, As, Cs, (0.6 * h1 * cp0 / (W + 2 * n_pr), 0.6 * h1 * sp0 / (W + 2 * n_pr), k3),
                                       (0, 0, 0.6), h1, h3, W)))
    cases.append(_case('29.1c', '4.1.2 (2)',
                       'corrected: A=B, theta0=0, h1*mu=0, (Omega+n+m)k_i = h3 mu_i (i=1,2); here mu=(0,0,0.6), h1=0, k1=k2=0',
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0.6), 0.0, h3, W)))
    cases.append(_case('29.2', '4.1.2 (2)',
                       'A=B, theta0=0, m=n, h1=0, k1=mu1 h3/(Omega+2n), k2=mu2 h3/(Omega+2n)',
                       mo, make_params(As, As, Cs, (mu[0] * h3 / (W + 2 * n_pr), mu[1] * h3 / (W + 2 * n_pr), k3),
                                       mu, 0.0, h3, W)))
    mo = dict(n=n_pr, m=2 * n_pr, psi0=psi0, theta0=np.pi)
    cases.append(_case('31.1', '4.1.2 (3)',
                       'A=B, theta0=pi, m=2n, h1=0, k1=-mu1 h3/(n-Omega), k2=-mu2 h3/(n-Omega)',
                       mo, make_params(As, As, Cs, (-mu[0] * h3 / (n_pr - W), -mu[1] * h3 / (n_pr - W), k3),
                                       mu, 0.0, h3, W)))
    cases.append(_case('31.2a', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, k1=k2=0',
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    mo = dict(n=W, m=2 * W, psi0=psi0, theta0=np.pi)
    cases.append(_case('31.2b', '4.1.2 (3)', 'A=B, theta0=pi, m=2n, mu=0, n=Omega (k1,k2 free)',
                       mo, make_params(As, As, Cs, (0.3, -0.2, k3), (0, 0, 0), h1, h3, W)))
    # ---- 4.2 : irrational n/m (theta0 = 0) ------------------------------------
    n_ir, m_ir = 0.7, 0.9 * np.sqrt(2.0)
    mo = dict(n=n_ir, m=m_ir, psi0=psi0, theta0=0.0)
    kk = (0.3, -0.2, k3)
    wsum = W + m_ir + n_ir
    cases.append(_case('44.1', '4.2', 'A=B, theta0=0, h1=0, mu1=(Omega+m+n)k1/h3, mu2=(Omega+m+n)k2/h3',
                       mo, make_params(As, As, Cs, kk, (wsum * kk[0] / h3, wsum * kk[1] / h3, 0.6), 0.0, h3, W)))
    cases.append(_case('44.2', '4.2', 'A=B, theta0=0, mu=0, k1=k2=0',
                       mo, make_params(As, As, Cs, (0, 0, k3), (0, 0, 0), h1, h3, W)))
    mo = dict(n=n_ir, m=-(W + n_ir), psi0=psi0, theta0=0.0)
    cases.append(_case('44.3', '4.2', 'A=B, theta0=0, mu=0, n+m+Omega=0 (k1,k2 free)',
                       mo, make_params(As, As, Cs, kk, (0, 0, 0), h1, h3, W)))
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
                       make_params(As, As, Cs, (0, 0, k3N), (0, 0, 0.6), h1N, h3, W)))
    cases.append(_case('N2', 'new, n=0 A!=B',
                       'mirror of 19.2: cos th0 = -1/2, m = +Omega, h1 = +sqrt3 h3, k1 = 2 mu1 h3/Omega, '
                       'k2 = 2 mu2 h3/Omega, k3 = -Omega(A+B-C) + 2 mu3 h3/Omega',
                       dict(n=0.0, m=W, psi0=np.pi / 2, theta0=2 * np.pi / 3),
                       make_params(Aa, Ba, Ca, (2 * mu[0] * h3 / W, 2 * mu[1] * h3 / W,
                                                -W * (Aa + Ba - Ca) + 2 * mu[2] * h3 / W),
                                   mu, _S3 * h3, h3, W)))
    return cases


CASES = build_cases()
