"""Seed 002 (Yehia & El-kenani 2021): sympy derivation of the Lagrange equations
in Euler angles and term-by-term comparison with the printed eqs. (4)-(7).

Run:  python derive_euler_lagrange.py      (about 1 minute)

Steps
 1. check that eq. (1) is the z-x-z rotation R = Rz(psi)Rx(theta)Rz(phi)
    (alpha, beta, gamma = rows of R; omega' = vee(R^T dR/dt));
 2. build L of eq. (2)-(3) and compare with the printed Euler-angle form (4);
 3. derive E_q = d/dt dL/dqdot - dL/dq for q = psi, theta, phi;
 4. check the hand-written numpy version in model.py against 3;
 5. compare with the printed (5), (6), (7) monomial by monomial.

Transcription of the printed equations: see PRINTED_* below.  Where the
extracted text lost a bracket, a *reading* was adopted and is listed in
READING_NOTES; everything else is taken literally.
"""
import os
import sys

import numpy as np
import sympy as sp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import model  # noqa: E402

A, B, C, W = sp.symbols('A B C Omega', real=True)
k1, k2, k3, m1, m2, m3, h1, h3 = sp.symbols('k1 k2 k3 mu1 mu2 mu3 h1 h3', real=True)
PARS = [A, B, C, W, k1, k2, k3, m1, m2, m3, h1, h3]
t = sp.Symbol('t', real=True)
psi_f, th_f, ph_f = [sp.Function(nm, real=True)(t) for nm in ('psi', 'theta', 'phi')]
ps, th, ph = sp.symbols('psi theta phi', real=True)
dps, dth, dph = sp.symbols('dpsi dtheta dphi', real=True)
ddps, ddth, ddph = sp.symbols('ddpsi ddtheta ddphi', real=True)
VELS = [ddps, ddth, ddph, dps, dth, dph]
s, c = sp.sin, sp.cos


def frames(p_, t_, f_):
    al = sp.Matrix([c(p_) * c(f_) - c(t_) * s(f_) * s(p_), -c(p_) * s(f_) - c(t_) * c(f_) * s(p_), s(t_) * s(p_)])
    be = sp.Matrix([s(p_) * c(f_) + c(t_) * s(f_) * c(p_), -s(p_) * s(f_) + c(t_) * c(f_) * c(p_), -s(t_) * c(p_)])
    ga = sp.Matrix([s(t_) * s(f_), s(t_) * c(f_), c(t_)])
    return al, be, ga


def to_symbols(e):
    rep = {psi_f.diff(t, 2): ddps, th_f.diff(t, 2): ddth, ph_f.diff(t, 2): ddph}
    e = e.subs(rep)
    e = e.subs({psi_f.diff(t): dps, th_f.diff(t): dth, ph_f.diff(t): dph})
    return e.subs({psi_f: ps, th_f: th, ph_f: ph})


# ---------------------------------------------------------------------------
# 1. kinematics
# ---------------------------------------------------------------------------
def Rz(a):
    return sp.Matrix([[c(a), -s(a), 0], [s(a), c(a), 0], [0, 0, 1]])


def Rx(a):
    return sp.Matrix([[1, 0, 0], [0, c(a), -s(a)], [0, s(a), c(a)]])


def check_kinematics():
    R = Rz(psi_f) * Rx(th_f) * Rz(ph_f)          # body -> orbital components
    al, be, ga = frames(psi_f, th_f, ph_f)
    ok_rows = all(sp.simplify(R[i, :].T - v) == sp.zeros(3, 1) for i, v in enumerate((al, be, ga)))
    Wm = sp.simplify(R.T * R.diff(t))            # skew matrix of omega' (body)
    wvee = sp.Matrix([Wm[2, 1], Wm[0, 2], Wm[1, 0]])
    w_eq1 = sp.Matrix([psi_f.diff(t) * s(th_f) * s(ph_f) + th_f.diff(t) * c(ph_f),
                       psi_f.diff(t) * s(th_f) * c(ph_f) - th_f.diff(t) * s(ph_f),
                       psi_f.diff(t) * c(th_f) + ph_f.diff(t)])
    ok_w = sp.simplify(wvee - w_eq1) == sp.zeros(3, 1)
    print('[1] eq.(1): alpha,beta,gamma are rows of Rz(psi)Rx(theta)Rz(phi):', ok_rows)
    print('    eq.(1): omega\' = vee(R^T dR/dt):', ok_w)
    return w_eq1


# ---------------------------------------------------------------------------
# 2./3. Lagrangian and Lagrange equations
# ---------------------------------------------------------------------------
def lagrangian(wr):
    al, be, ga = frames(psi_f, th_f, ph_f)
    I = sp.diag(A, B, C)
    k = sp.Matrix([k1, k2, k3])
    mu = sp.Matrix([m1, m2, m3])
    w = wr + W * ga
    V = sp.Rational(3, 2) * W ** 2 * (al.T * I * al)[0] + (mu.T * (h1 * al + h3 * ga))[0]
    return (w.T * I * w)[0] / 2 + (w.T * k)[0] - V


def printed_L4():
    """Eq. (4) transcribed literally (psi_f, th_f, ph_f are functions of t)."""
    P_, T_, F_ = psi_f, th_f, ph_f
    dP, dT, dF = P_.diff(t), T_.diff(t), F_.diff(t)
    h = sp.Rational(1, 2)
    L = (h * A * ((dP + W) * s(T_) * s(F_) + dT * c(F_)) ** 2
         + h * B * ((dP + W) * s(T_) * c(F_) - dT * s(F_)) ** 2
         + h * C * (dF + (dP + W) * c(T_)) ** 2
         + k1 * ((dP + W) * s(T_) * s(F_) + dT * c(F_))
         + k2 * ((dP + W) * s(T_) * c(F_) - dT * s(F_))
         + k3 * ((dP + W) * c(T_) + dF)
         - sp.Rational(3, 2) * W ** 2 * (A * (c(P_) * c(F_) - c(T_) * s(F_) * s(P_)) ** 2
                                         - B * (c(P_) * s(F_) + c(T_) * c(F_) * s(P_)) ** 2
                                         + C * s(T_) ** 2 * s(P_) ** 2)
         - m1 * (h1 * (c(P_) * c(F_) - c(T_) * s(F_) * s(P_)) + h3 * s(T_) * s(F_))
         - m2 * (h1 * (c(P_) * s(F_) + c(T_) * c(F_) * s(P_)) + h3 * s(T_) * c(F_))
         - m3 * (h1 * s(T_) * s(P_) + h3 * c(T_)))
    return L


READING_NOTES = [
    "(5): '{... + (k2 cos phi + k1 sin phi) thetadot}' read as '{...} thetadot' (every term "
    "of the brace needs a thetadot factor; the extraction put it inside the brace)",
    "(6): '{... - cos theta (k2 cos phi + k1 sin phi) psidot}' read as '{...} psidot'",
    "(6): '- cos theta (Omega k2 - h3 mu2) cos phi + (Omega k1 - h3 mu1) sin phi' read as "
    "'- cos theta [(Omega k2 - h3 mu2) cos phi + (Omega k1 - h3 mu1) sin phi]'",
    "(7): '{[(B-A)cos2phi - C] sin theta} psidot - ((A-B)cos2phi + C) Omega sin theta + "
    "(k1 sin phi + k2 cos phi) thetadot' read as '{[(B-A)cos2phi - C] sin theta psidot - "
    "((A-B)cos2phi + C) Omega sin theta + (k1 sin phi + k2 cos phi)} thetadot'",
    "(7): '- Omega sin theta sin2phi (A-B) sin theta + (k1 cos phi - k2 sin phi) psidot' read "
    "as '[- Omega (A-B) sin2phi sin^2 theta + (k1 cos phi - k2 sin phi)] psidot' (the first "
    "term has no velocity factor as printed)",
    "(7): '- h1 mu1 sin psi cos phi cos theta + cos psi sin phi' read as "
    "'- h1 mu1 (sin psi cos phi cos theta + cos psi sin phi)'",
]


def printed_eqs():
    """Printed (5), (6), (7) in the reading described by READING_NOTES."""
    h = sp.Rational(1, 2)
    a = A * s(ph) ** 2 + B * c(ph) ** 2
    e5 = (h * (A - B) * s(2 * ph) * s(th) * ddth
          + ((A * s(ph) ** 2 + B * c(ph) ** 2) * s(th) ** 2 + C * c(th) ** 2) * ddps
          + C * c(th) * ddph
          + h * (A - B) * s(2 * ph) * c(th) * dth ** 2
          + (((A - B) * c(2 * ph) - C) * s(th) * dph
             + ((a - C) * s(2 * th)) * dps
             + (2 * W * c(th) * (a - C) - k3) * s(th)
             + (k2 * c(ph) + k1 * s(ph))) * dth
          + ((A - B) * s(2 * ph) * s(th) ** 2 * (dps + W) + s(th) * (k1 * c(ph) - k2 * s(ph))) * dph
          + sp.Rational(3, 2) * W ** 2 * C * s(th) ** 2 * s(2 * ps)
          + m3 * h1 * c(ps) * s(th)
          - sp.Rational(3, 2) * W ** 2 * (-B * c(th) ** 2 + A) * s(2 * ps) * c(ph) ** 2
          + (-3 * W ** 2 * c(2 * ps) * (A - B) * c(th) * s(ph)
             - h1 * (m2 * s(ps) * c(th) + m1 * s(ps))) * c(ph)
          + 3 * s(ph) * (W ** 2 / 2 * s(2 * ps) * (A * c(th) ** 2 - B) * s(ph)
                         - sp.Rational(1, 3) * h1 * (m1 * c(ps) * c(th) - m2 * s(ps))))
    e6 = (h * (A - B) * s(2 * ph) * s(th) * ddps
          + (A * c(ph) ** 2 + B * s(ph) ** 2) * ddth
          + (-h * (a - C) * s(2 * th)) * dps ** 2
          + (((A - B) * c(2 * ph) + C) * s(th) * dph
             + h * (A - B) * s(2 * ph) * c(th) * dth
             + (-2 * W * c(th) * a + 2 * C * W * c(th) + k3) * s(th)
             - c(th) * (k2 * c(ph) + k1 * s(ph))) * dps
          + ((B - A) * s(2 * ph) * dth + ((A - B) * c(2 * ph) + C) * W * s(th)
             - (k2 * c(ph) + k1 * s(ph))) * dph
          + (h * (A - B) * s(2 * ph) * c(th)) * W * dth
          + (-W ** 2 * (B + A - C) * c(th) * (3 * s(ps) ** 2 + 1)
             + sp.Rational(3, 4) * W ** 2 * (A - B) * s(2 * ps) * s(2 * ph)
             + h1 * m2 * s(ps) * c(ph) + h1 * m1 * s(ps) * s(ph) + W * k3 - h3 * m3) * s(th)
          - c(th) * ((W * k2 - h3 * m2) * c(ph) + (W * k1 - h3 * m1) * s(ph))
          - h1 * m3 * s(ps))
    e7 = (C * c(th) * ddph + C * ddph
          + h * (A - B) * s(2 * ph) * dth ** 2
          + (((B - A) * c(2 * ph) - C) * s(th) * dps
             - ((A - B) * c(2 * ph) + C) * W * s(th)
             + (k1 * s(ph) + k2 * c(ph))) * dth
          - (h * (A - B) * s(2 * ph) * s(th) ** 2) * dps ** 2
          + (-W * s(th) * s(2 * ph) * (A - B) * s(th) + (k1 * c(ph) - k2 * s(ph))) * dps
          - h * W ** 2 * (A - B) * s(2 * ph) * s(th) ** 2
          + (-W * (k1 * c(ph) - k2 * s(ph)) + h3 * (m1 * c(ph) - m2 * s(ph))) * s(th)
          - sp.Rational(3, 2) * W ** 2 * (A - B) * (s(2 * ps) * c(th) * c(2 * ph)
                                                   - (c(ps) ** 2 - s(ps) ** 2 * c(th) ** 2) * s(2 * ph))
          - h1 * m1 * (s(ps) * c(ph) * c(th) + c(ps) * s(ph))
          - h1 * m2 * (-s(ps) * s(ph) * c(th) + c(ps) * c(ph)))
    return [e5, e6, e7]


# ---------------------------------------------------------------------------
# comparison helpers
# ---------------------------------------------------------------------------
_rng = np.random.default_rng(1)
_PTS = _rng.uniform(-2.0, 2.0, size=(6, len(PARS) + 9))


def is_zero_trig(e):
    """Numerical zero test (random angles, rates and parameters)."""
    f = sp.lambdify((ps, th, ph, dps, dth, dph, ddps, ddth, ddph) + tuple(PARS), e, 'numpy')
    return all(abs(complex(f(*pt))) < 1e-11 for pt in _PTS)


def split(e, gens):
    e = sp.expand(e)
    P = sp.Poly(e, *gens)
    return {mon: cf for mon, cf in P.terms()}


def mono_str(mon, gens):
    parts = []
    for g, k in zip(gens, mon):
        if k == 1:
            parts.append(str(g))
        elif k > 1:
            parts.append('%s^%d' % (g, k))
    return '*'.join(parts) if parts else '1'


def nice(e):
    """Compact display of a trigonometric coefficient."""
    e = sp.factor(sp.trigsimp(sp.expand_trig(sp.expand(e))))
    alt = sp.factor(sp.trigsimp(sp.expand(e)))
    return min((e, alt), key=lambda x: len(str(x)))


def compare(printed, derived, name, verbose=True):
    """Compare two expressions group by group.  A group = monomial in the
    accelerations/velocities times a monomial in (k, mu, h); the inertia
    parameters A, B, C and Omega stay in the coefficients.  For each group that
    differs print printed, derived and printed - derived."""
    gens = VELS + [k1, k2, k3, m1, m2, m3, h1, h3]
    dp, dd = split(printed, gens), split(derived, gens)
    keys = set(dp) | set(dd)
    ndiff = 0
    lines = []
    for mon in sorted(keys, key=lambda m: (-sum(m[:3]), [-x for x in m])):
        pr, de = dp.get(mon, 0), dd.get(mon, 0)
        diff = pr - de
        if is_zero_trig(diff):
            continue
        ndiff += 1
        vm, pm = mon[:len(VELS)], mon[len(VELS):]
        lines.append('  [%s] x %s :\n      printed: %s\n      derived: %s\n      printed - derived: %s' % (
            mono_str(vm, VELS), mono_str(pm, gens[len(VELS):]), nice(pr), nice(de), nice(diff)))
    print('%s: %d differing groups' % (name, ndiff))
    if verbose:
        for ln in lines:
            print(ln)
    return ndiff


def compact_checks(E):
    """Check the compact forms quoted in the report for the gravity terms."""
    h = sp.Rational(1, 2)
    a = A * s(ph) ** 2 + B * c(ph) ** 2
    al, be, ga = frames(ps, th, ph)
    al1, al2 = al[0], al[1]
    grav = lambda e: sp.expand(e).subs({k1: 0, k2: 0, k3: 0, m1: 0, m2: 0, m3: 0}).subs(
        {dps: 0, dth: 0, dph: 0, ddps: 0, ddth: 0, ddph: 0})
    Pr = printed_eqs()
    claims = [
        ('theta-eq Omega^2 terms, derived = Omega^2 sin th [3/4(A-B) sin2psi sin2phi - cos th (3 sin^2 psi + 1)'
         '(A sin^2 phi + B cos^2 phi - C)]',
         grav(E[1]) - W ** 2 * s(th) * (sp.Rational(3, 4) * (A - B) * s(2 * ps) * s(2 * ph)
                                        - c(th) * (3 * s(ps) ** 2 + 1) * (a - C))),
        ('theta-eq Omega^2 terms, printed = same with (A+B-C) in place of (A sin^2 phi + B cos^2 phi - C)',
         grav(Pr[1]) - W ** 2 * s(th) * (sp.Rational(3, 4) * (A - B) * s(2 * ps) * s(2 * ph)
                                         - c(th) * (3 * s(ps) ** 2 + 1) * (A + B - C))),
        ('phi-eq Omega^2 terms, derived = -1/2 Omega^2 (A-B) sin2phi sin^2 th + 3 Omega^2 (A-B) alpha1 alpha2',
         grav(E[2]) - (-h * W ** 2 * (A - B) * s(2 * ph) * s(th) ** 2 + 3 * W ** 2 * (A - B) * al1 * al2)),
        ('3 alpha1 alpha2 = -3/2 [sin2psi cos th cos2phi + (cos^2 psi - sin^2 psi cos^2 th) sin2phi]',
         3 * al1 * al2 + sp.Rational(3, 2) * (s(2 * ps) * c(th) * c(2 * ph)
                                              + (c(ps) ** 2 - s(ps) ** 2 * c(th) ** 2) * s(2 * ph))),
        ('psi-eq Omega^2 terms, derived = -3 Omega^2 (I alpha).beta',
         grav(E[0]) + 3 * W ** 2 * (A * al[0] * be[0] + B * al[1] * be[1] + C * al[2] * be[2])),
    ]
    for txt, e in claims:
        print('  %-5s %s' % (is_zero_trig(e), txt))


def main():
    w_eq1 = check_kinematics()
    L = lagrangian(w_eq1)
    print('\n[2] Lagrangian (2)+(3) vs printed Euler-angle form (4)')
    compare(to_symbols(printed_L4()), to_symbols(L), 'eq.(4)')

    print('\n[3] Lagrange equations E_q = d/dt dL/dqdot - dL/dq')
    E = []
    for q in (psi_f, th_f, ph_f):
        e = sp.diff(L, q.diff(t)).diff(t) - sp.diff(L, q)
        E.append(sp.expand(to_symbols(e)))
    for name, e in zip(('E_psi', 'E_theta', 'E_phi'), E):
        d = sp.collect(e, [ddps, ddth, ddph, dps, dth, dph], evaluate=False)
        print('  %s: %d collected velocity groups' % (name, len(d)))

    print('\n[4] model.py euler_angle_eqs vs sympy (random states)')
    f = sp.lambdify((ps, th, ph, dps, dth, dph, ddps, ddth, ddph) + tuple(PARS), E, 'numpy')
    rng = np.random.default_rng(7)
    err = 0.0
    for _ in range(200):
        q, qd, qdd = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
        pv = rng.normal(size=12)
        pv[:3] = rng.uniform(0.5, 2.0, 3)
        p = model.make_params(pv[0], pv[1], pv[2], pv[4:7], pv[7:10], pv[10], pv[11], pv[3])
        ref = np.array(f(*q, *qd, *qdd, *pv[:4], *pv[4:7], *pv[7:10], pv[10], pv[11]), dtype=float)
        got = model.euler_angle_eqs(q, qd, qdd, p)
        err = max(err, np.max(np.abs(ref - got)) / (1 + np.max(np.abs(ref))))
    print('  max relative difference over 200 random states: %.2e' % err)

    print('\n[5] printed (5)-(7) vs derived.  Readings adopted for the garbled text:')
    for r in READING_NOTES:
        print('   -', r)
    Pr = printed_eqs()
    # overall normalisation: printed leading coefficient has the sign of E
    for name, pe, de in zip(('eq.(5) [psi]', 'eq.(6) [theta]', 'eq.(7) [phi]'), Pr, E):
        print()
        compare(pe, de, name)
    print('\n[6] compact forms of the gravity terms (True = identity holds)')
    compact_checks(E)


if __name__ == '__main__':
    main()
