"""Task 2: compare the printed periodic solution (35) and period (36) of seed 000 with the
EXACT periodic orbit of the full model, as a function of mu = r0/c; same for the
corrected formulas of formulas.py.  ~40 s on one core.

For each mu the exact periodic orbit through gamma''(0) = Gamma/mu, gamma'(0) = 0,
r(0) = r0 = mu c is found by Newton shooting on the ground-truth equations
(DOP853, rtol = atol = 1e-13); unknowns p(0), q(0), period.  Errors are max-norms
over one period in the scaled variables p1 = p/c, q1 = q/c, r1 = r/r0, gamma's.
Two comparisons for the printed (35): 'tau' = evaluated at tau = r0 t as printed;
the corrected formula uses its own strained time s = Omega tau.
Also: (ii) integrate from the formula's own initial state and compare over one period.
"""
import sys, os, time
import numpy as np
from scipy.optimize import fsolve
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import formulas as F

KEYS = ('p1', 'q1', 'r1', 'g1', 'g2', 'g3')
BODIES = {
    'body I  (A>B>C: a=2.0,b=1.5, omega=0.408)': dict(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=np.sqrt(0.66), k=0.3, Gamma=0.5, c=1.0),
    'body II (A<B<C: a=0.65,b=0.85, omega=0.308)': dict(a=0.65, b=0.85, x0=-0.4, y0=0.6, z0=np.sqrt(1 - 0.52), k=0.8, Gamma=0.7, c=1.0),
}
MUS = [8, 16, 32, 64, 128, 256]


def exact_orbit(P, guess):
    """Return (p10, q10, T_tau) of the exact periodic orbit."""
    mu = P['mu']
    g0 = P['Gamma'] / mu
    X0base = np.array([0.0, 0.0, mu, np.sqrt(1 - g0**2), 0.0, g0])

    def res(u):
        p10, q10, T = u
        X0 = X0base.copy(); X0[0] = p10; X0[1] = q10
        Xe = F.integrate_full_model(P, X0, np.array([0.0, T / mu]))[:, -1]
        return [(Xe[0] - p10) * mu, (Xe[1] - q10) * mu, Xe[4]]
    sol, info, ier, msg = fsolve(res, guess, full_output=True, xtol=1e-13, epsfcn=1e-14)
    return sol, np.max(np.abs(info['fvec']))


def errors_vs_exact(P, u, npts=200):
    mu = P['mu']
    p10, q10, T = u
    g0 = P['Gamma'] / mu
    X0 = np.array([p10, q10, mu, np.sqrt(1 - g0**2), 0.0, g0])
    tau = np.linspace(0, T, npts)
    X = F.integrate_full_model(P, X0, tau / mu)
    ex = dict(zip(KEYS, [X[0], X[1], X[2] / mu, X[3], X[4], X[5]]))
    pr = F.printed_solution_35(tau, P)
    co = F.corrected_solution_scaled(tau, P)
    e_pr = {kk: np.max(np.abs(pr[kk] - ex[kk])) for kk in KEYS}
    e_co = {kk: np.max(np.abs(co[kk] - ex[kk])) for kk in KEYS}
    return e_pr, e_co


def errors_from_own_ic(P, formula, npts=200):
    """Integrate full model from the formula's value at tau=0, compare over one period 2 pi."""
    mu = P['mu']
    tau = np.linspace(0, 2 * np.pi, npts)
    S = formula(tau, P)
    Y0 = np.array([S[kk][0] for kk in KEYS])
    X = F.integrate_full_model(P, F.scaled_to_full(Y0, P), tau / mu)
    ex = dict(zip(KEYS, [X[0], X[1], X[2] / mu, X[3], X[4], X[5]]))
    return {kk: np.max(np.abs(S[kk] - ex[kk])) for kk in KEYS}


def slope(mus, errs):
    mus, errs = np.asarray(mus, float), np.asarray(errs, float)
    ok = errs > 1e-13
    if ok.sum() < 2:
        return float('nan')
    return np.polyfit(np.log(mus[ok]), np.log(errs[ok]), 1)[0]


def main():
    t0 = time.time()
    for name, base in BODIES.items():
        P0 = dict(base)
        d = F.derived(dict(P0, mu=10.0))
        print('=' * 100)
        print(name, ' omega^2 = %.4f' % d['w2'], ' params:', {k_: round(float(v), 4) for k_, v in base.items()})
        rows = []
        for mu in MUS:
            P = dict(P0, mu=float(mu))
            co0 = F.corrected_solution_scaled(np.array([0.0]), P)
            guess = [co0['p1'][0], co0['q1'][0], 2 * np.pi / F.corrected_frequency(P)]
            u, fres = exact_orbit(P, guess)
            e_pr, e_co = errors_vs_exact(P, u)
            e_own_pr = errors_from_own_ic(P, F.printed_solution_35)
            alpha_ex = u[2] - 2 * np.pi
            rows.append(dict(mu=mu, e_pr=e_pr, e_co=e_co, e_own=e_own_pr, alpha_ex=alpha_ex,
                             alpha_pr=F.printed_period_36(P), alpha_co=F.corrected_period(P),
                             ic_dev=(abs(u[0] - co0['p1'][0]), abs(u[1] - co0['q1'][0])), fres=fres))
        # ---------------- tables
        print('\n(a) max error over one period vs the EXACT periodic orbit  [printed (35) at tau | corrected, strained s]')
        print('%6s ' % 'mu' + ' '.join('%21s' % kk for kk in KEYS))
        for r in rows:
            print('%6d ' % r['mu'] + ' '.join('%10.2e|%10.2e' % (r['e_pr'][kk], r['e_co'][kk]) for kk in KEYS))
        print('slope  ' + ' '.join('%10.2f|%10.2f' % (slope(MUS, [r['e_pr'][kk] for r in rows]),
                                                     slope(MUS, [r['e_co'][kk] for r in rows])) for kk in KEYS))
        print('\n(b) printed (35): integrate full model from its own tau=0 state, max error over tau in [0, 2 pi]')
        for r in rows:
            print('%6d ' % r['mu'] + ' '.join('%10.2e' % r['e_own'][kk] for kk in KEYS))
        print('slope  ' + ' '.join('%10.2f' % slope(MUS, [r['e_own'][kk] for r in rows]) for kk in KEYS))
        print('\n(c) period correction alpha = T_tau - 2 pi')
        print('%6s %14s %14s %14s %12s %12s %10s' % ('mu', 'exact', 'printed(36)', 'corrected', 'err printed', 'err corr', 'shoot res'))
        for r in rows:
            print('%6d %14.6e %14.6e %14.6e %12.2e %12.2e %10.1e' % (
                r['mu'], r['alpha_ex'], r['alpha_pr'], r['alpha_co'], abs(r['alpha_pr'] - r['alpha_ex']),
                abs(r['alpha_co'] - r['alpha_ex']), r['fres']))
        print('slope of |alpha error|: printed %.2f, corrected %.2f;  mu^2*alpha_exact at largest mu = %.6f, '
              'formula x0+kC1/4 = %.6f, printed x0+kC1/16 = %.6f' % (
                  slope(MUS, [abs(r['alpha_pr'] - r['alpha_ex']) for r in rows]),
                  slope(MUS, [abs(r['alpha_co'] - r['alpha_ex']) for r in rows]),
                  rows[-1]['mu']**2 * rows[-1]['alpha_ex'] / (2 * np.pi),
                  base['x0'] + base['k'] * (base['b'] - base['a']) / 4,
                  base['x0'] + base['k'] * (base['b'] - base['a']) / 16))
        # Richardson-type estimate of the mu^-3 coefficient of alpha/(2 pi)
        m1, m2 = rows[-2], rows[-1]
        c2 = base['x0'] + base['k'] * (base['b'] - base['a']) / 4
        c3 = [(r['alpha_ex'] / (2 * np.pi) - c2 / r['mu']**2) * r['mu']**3 for r in (m1, m2)]
        print('mu^3*(alpha/2pi - (x0+kC1/4)/mu^2) at mu=%d,%d: %.5f, %.5f ; predicted -z0*Gamma = %.5f ; '
              'printed (36) predicts -z0*Gamma - 0.5 k B1 Gamma = %.5f' % (
                  m1['mu'], m2['mu'], c3[0], c3[1], -base['z0'] * base['Gamma'],
                  -base['z0'] * base['Gamma'] - 0.5 * base['k'] * (base['a'] - 1) / base['b'] * base['Gamma']))
        # (d) erratum evidence: evaluate printed formulas at the STRAINED time s (removes the
        # phase-drift part of the error) and with the single fix 4*y0' in r1.
        print('\n(d) printed (35) evaluated at strained s = Omega*tau vs exact orbit (isolates missing terms)')
        print('%6s %12s %12s %12s %12s %12s' % ('mu', 'r1 printed', "r1 4y0' fix", 'g1 printed', 'g2 printed', 'g3 printed'))
        ev = []
        for mu in MUS[1::2]:
            P = dict(P0, mu=float(mu))
            co0 = F.corrected_solution_scaled(np.array([0.0]), P)
            u, _ = exact_orbit(P, [co0['p1'][0], co0['q1'][0], 2 * np.pi / F.corrected_frequency(P)])
            g0 = P['Gamma'] / mu
            tau = np.linspace(0, u[2], 200)
            X = F.integrate_full_model(P, np.array([u[0], u[1], mu, np.sqrt(1 - g0**2), 0, g0]), tau / mu)
            s = F.corrected_frequency(P) * tau
            pr = F.printed_solution_35(s, P)
            r1fix = pr['r1'] - 0.25 * mu**-2 * 3 * P['y0'] * np.sin(s)
            e = [np.max(np.abs(pr['r1'] - X[2] / mu)), np.max(np.abs(r1fix - X[2] / mu)),
                 np.max(np.abs(pr['g1'] - X[3])), np.max(np.abs(pr['g2'] - X[4])), np.max(np.abs(pr['g3'] - X[5]))]
            ev.append(e)
            print('%6d ' % mu + ' '.join('%12.2e' % v for v in e))
        ev = np.array(ev)
        print('slope  ' + ' '.join('%12.2f' % slope(MUS[1::2], ev[:, j]) for j in range(5)))
    print('[%.1f s]' % (time.time() - t0))


if __name__ == '__main__':
    main()
