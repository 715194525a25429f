"""Task 2b: check the Euler-angle formulas (38)-(39) of seed 000 against the exact
periodic orbit of the full model (gamma = sin th sin ph, gamma' = sin th cos ph,
gamma'' = cos th; psi_dot = (p gamma + q gamma')/(1 - gamma''^2)).  ~10 s.

Variants of the printed formula (each adds ONE more fix to the previous):
  L  literal: r0^-1 t in all trig arguments, theta sign '+', '-0.667 k', psi1 with
     '0.25(chi1+chi2/A1) + sin 2 r0^-1 t', psi prefactor mu^-1 sqrt(Mgl/C), phi rate r0^-1
  F1 = L with r0^-1 t -> r0 t and phi rate r0^-1 -> r0 (as in the Conclusions)
  F2 = F1 with '+ sin 2r0t' -> '* sin 2r0t' in psi1 and prefactor mu^-1 c -> mu^-2
  F3 = F2 with theta sign '+' -> '-' and -0.667 k -> +0.5 k
  C  corrected (formulas.corrected_euler): F3 + strained time + phase/rate terms in phi
"""
import sys, os, time
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import formulas as F
from check_periodic import exact_orbit, slope

BASE = dict(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=np.sqrt(0.66), k=0.3, Gamma=0.5, c=1.0)


def variant(t, P, level):
    d = F.derived(P)
    a, b, x, y, z, k, mu, c = (P[n] for n in ('a', 'b', 'x0', 'y0', 'z0', 'k', 'mu', 'c'))
    g0, C1, A1, chi1, chi2 = d['g0'], d['C1'], d['A1'], d['chi1'], d['chi2']
    r0 = mu * c
    th0 = np.arccos(g0)
    w = 1 / r0 if level == 'L' else r0
    kth = -0.667 if level in ('L', 'F1', 'F2') else 0.5
    sgn = 1.0 if level in ('L', 'F1', 'F2') else -1.0

    def th2(tt):
        return (y * g0 / (1 - b) * np.sin(w * tt) - x * g0 / (1 - a) * np.cos(w * tt)
                + 0.5 * C1 * (z / (a + b - 1) + kth * k * g0) * np.cos(2 * w * tt))

    def ps1(tt):
        A = 0.25 * (chi1 + chi2 / A1)
        trig = (A + np.sin(2 * w * tt)) if level in ('L', 'F1') else A * np.sin(2 * w * tt)
        return trig + y * g0 / (1 - b) * np.cos(w * tt) + x * g0 / (1 - a) * np.sin(w * tt)
    pref = c / mu if level in ('L', 'F1') else mu**-2
    theta = th0 + sgn * mu**-2 / np.sin(th0) * (th2(t) - th2(0.0))
    psi = 0.5 * c**2 / r0 * (chi1 - chi2 / A1) * t + pref * (ps1(t) - ps1(0.0))
    phi = np.pi / 2 + (w - 0.5 * c**2 / r0 * g0 * (chi1 - chi2 / A1)) * t
    return dict(theta=theta, psi=psi, phi=phi)


def main():
    t0 = time.time()
    mus = [8, 16, 32, 64, 128, 256]
    levels = ['L', 'F1', 'F2', 'F3', 'C']
    res = {lv: {q: [] for q in ('theta', 'psi', 'phi')} for lv in levels}
    amp = []
    for mu in mus:
        P = dict(BASE, mu=float(mu))
        co0 = F.corrected_solution_scaled(np.array([0.0]), P)
        u, _ = exact_orbit(P, [co0['p1'][0], co0['q1'][0], 2 * np.pi / F.corrected_frequency(P)])
        g0 = P['Gamma'] / mu
        X0 = np.array([u[0], u[1], mu, np.sqrt(1 - g0**2), 0.0, g0])
        t = np.linspace(0, u[2] / mu, 400)           # one period, physical time (c = 1)
        Z = F.integrate_full_model(P, X0, t, extra_psi=True)
        ex = dict(theta=np.arccos(Z[5]), phi=np.unwrap(np.arctan2(Z[3], Z[4])), psi=Z[6])
        amp.append([np.ptp(ex['theta']), np.ptp(ex['psi']), np.ptp(ex['phi'])])
        for lv in levels:
            S = F.corrected_euler(t, P) if lv == 'C' else variant(t, P, lv)
            for q in ('theta', 'psi', 'phi'):
                res[lv][q].append(np.max(np.abs(S[q] - ex[q])))
    print('max error over one period of the exact periodic orbit (body I, Gamma = 0.5)')
    for q_i, q in enumerate(('theta', 'psi', 'phi')):
        print('\n%s   (peak-to-peak of exact %s at mu=8: %.3e, at mu=256: %.3e)' % (q, q, amp[0][q_i], amp[-1][q_i]))
        print('%6s ' % 'mu' + ' '.join('%11s' % lv for lv in levels))
        for i, mu in enumerate(mus):
            print('%6d ' % mu + ' '.join('%11.3e' % res[lv][q][i] for lv in levels))
        print('slope  ' + ' '.join('%11.2f' % slope(mus, res[lv][q]) for lv in levels))
    # physical-units check of formulas.large_parameter_solution (c != 1)
    P = dict(BASE, mu=100.0, c=2.5)
    c, mu = P['c'], P['mu']
    co0 = F.corrected_solution_scaled(np.array([0.0]), P)
    u, _ = exact_orbit(P, [co0['p1'][0], co0['q1'][0], 2 * np.pi / F.corrected_frequency(P)])
    g0 = P['Gamma'] / mu
    X0 = np.array([u[0], u[1], mu, np.sqrt(1 - g0**2), 0.0, g0])     # nondimensional (omega/c, time c t)
    t = np.linspace(0, 3 * u[2] / (mu * c), 600)                       # three periods, physical time
    Z = F.integrate_full_model(P, X0, c * t, extra_psi=True)
    S = F.large_parameter_solution(t, P)
    errs = [np.max(np.abs(S['p'] - c * Z[0])) / c, np.max(np.abs(S['q'] - c * Z[1])) / c,
            np.max(np.abs(S['r'] - c * Z[2])) / (c * mu), np.max(np.abs(S['g3'] - Z[5])),
            np.max(np.abs(S['psi'] - Z[6])), np.max(np.abs(S['phi'] - np.unwrap(np.arctan2(Z[3], Z[4]))))]
    print('\nlarge_parameter_solution, physical units c = 2.5, mu = 100, three periods:'
          ' |dp|/c %.1e |dq|/c %.1e |dr|/r0 %.1e |dgamma\'\'| %.1e |dpsi| %.1e |dphi| %.1e; T = %.6f (exact %.6f)'
          % (*errs, S['T'], u[2] / (mu * c)))
    print('\n[%.1f s]' % (time.time() - t0))


if __name__ == '__main__':
    main()
