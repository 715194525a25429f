"""Seed 002: numerical test of every regular-precession case of the paper.

Run:  python check_cases.py        (about 30-60 s)

For each entry of model.CASES (parameters chosen to satisfy the PRINTED
conditions) this prints
  res     max |R(t)| of the vector Euler equations along the precession
          psi = n t + psi0, theta = theta0, phi = m t, over 5 orbits (1001 pts)
  dth1    max |theta(t) - theta0| over 1 orbit, full vector equations
          integrated from the precession's initial state (DOP853,
          rtol = atol = 1e-12)
  dth5    the same over 5 orbits
  dH      Jacobi-integral drift of that integration (sanity)
  verdict holds  if res < 1e-10 and dth1 < 1e-6
          fails  if res > 1e-6
          (a holding case whose dth5 grows large is an exact but unstable
          solution: the deviation then starts from round-off, see t_1e-6)
  t_1e-6  first time (in orbits) at which |theta - theta0| exceeds 1e-6
  rate    for holding cases that drift: exponential growth rate of
          |theta - theta0| (fit of log deviation between 1e-9 and 1e-3)
and the classification (definitions in the report):
  orbital-frame motion, inertial-frame motion, geometric type of the
  proper-rotation axis e3 (cylindrical / conical / hyperboloidal).
"""
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import model  # noqa: E402

ORBIT = 2 * np.pi      # Omega = 1 in all cases
NORB = 5


def theta_dev(case):
    p, mo = case['params'], case['motion']
    q0, qd0 = model.precession_q(0.0, mo['n'], mo['m'], mo['psi0'], mo['theta0'])
    y0 = model.state_from_euler(q0, qd0, p)
    te = np.linspace(0, NORB * ORBIT, 2001)
    sol = solve_ivp(model.rhs_vector, (0, te[-1]), y0, method='DOP853', rtol=1e-12, atol=1e-12,
                    args=(p,), t_eval=te)
    th = np.array([model.theta_of_state(y) for y in sol.y.T])
    dev = np.abs(th - mo['theta0'])
    H = np.array([model.jacobi(y, p) for y in sol.y.T])
    one = te <= ORBIT + 1e-12
    over = np.nonzero(dev > 1e-6)[0]
    t_exc = te[over[0]] / ORBIT if len(over) else np.inf
    # exponential growth rate of the deviation (fit of log dev in 1e-9..1e-3)
    sel = (dev > 1e-9) & (dev < 1e-3)
    rate = np.polyfit(te[sel], np.log(dev[sel]), 1)[0] if sel.sum() > 20 and np.isfinite(t_exc) else np.nan
    return dev[one].max(), dev.max(), np.max(np.abs(H - H[0])), t_exc, rate


def classify(case):
    """Frame-wise classification (see report, section 'Classification')."""
    mo, W = case['motion'], case['params']['Omega']
    n, m, psi0, th0 = mo['n'], mo['m'], mo['psi0'], mo['theta0']
    al, be, ga = model.frames_from_euler(psi0, th0, 0.0)
    e3 = np.array([al[2], be[2], ga[2]])          # body axis 3 in orbital comps
    g = np.array([0.0, 0.0, 1.0])
    tol = 1e-12
    axis_along_g = np.hypot(e3[0], e3[1]) < tol

    def kind(prec_rate):
        w = prec_rate * g + m * e3
        if np.linalg.norm(w) < tol:
            return 'rest'
        if axis_along_g or abs(prec_rate) < tol or abs(m) < tol:
            return 'perm.rot(|w|=%.3g)' % np.linalg.norm(w)
        return 'reg.prec(%.3g|%.3g)' % (prec_rate, m)

    orb = kind(n)
    ine = kind(n + W)
    if axis_along_g:
        geo = 'cylindrical'
    elif abs(n) > tol:
        geo = 'axis moves in orbital frame'
    elif abs(e3[0]) < tol:
        geo = 'hyperboloidal (e3 _|_ radius)'
    elif abs(e3[1]) < tol:
        geo = 'conical (e3 in radial-normal plane)'
    else:
        geo = 'hyperboloidal (general)'
    return orb, ine, geo


def main():
    print('%-6s %-12s %8s %8s %8s %8s %7s %6s  %-8s | %-20s %-20s %s' % (
        'case', 'section', 'res', 'dth1', 'dth5', 'dH', 't_1e-6', 'rate', 'verdict',
        'orbital frame', 'inertial frame', 'axis type'))
    tw = np.linspace(0, NORB * ORBIT, 1001)
    for case in model.CASES:
        mo = case['motion']
        res = model.precession_residual(case['params'], mo['n'], mo['m'], mo['psi0'], mo['theta0'], tw)
        d1, d5, dH, texc, rate = theta_dev(case)
        if res < 1e-10 and d1 < 1e-6:
            verdict = 'holds'
        elif res > 1e-6:
            verdict = 'fails'
        else:
            verdict = 'unclear'
        orb, ine, geo = classify(case)
        print('%-6s %-12s %8.1e %8.1e %8.1e %8.1e %7.2f %6.2f  %-8s | %-20s %-20s %s' % (
            case['label'], case['section'].replace(' ', ''), res, d1, d5, dH, texc, rate, verdict,
            orb, ine, geo))
    print('\nparameter sets (Omega = 1):')
    for case in model.CASES:
        p, mo = case['params'], case['motion']
        print('  %-6s A,B,C=%.3g,%.3g,%.3g k=(%.6g, %.6g, %.6g) mu=(%.6g, %.6g, %.6g) h1=%.6g h3=%.6g | '
              'n=%.6g m=%.6g psi0=%.6g theta0=%.6g' % (
                  case['label'], p['A'], p['B'], p['C'], *p['k'], *p['mu'], p['h1'], p['h3'],
                  mo['n'], mo['m'], mo['psi0'], mo['theta0']))


if __name__ == '__main__':
    main()
