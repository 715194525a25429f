"""Which scaling makes the paper's eqs. (1)-(2) consistent with the full model, and what
regime it describes.  (seed 000, Ismail 2021)   ~10 s.

Part A (sympy): let tau = lam*t, p1 = p/sig, q1 = q/sig, r1 = r/rho and divide the
dimensional Euler-Poisson equations so that they take the printed form (1):
    p1' + A1 q1 r1 = mu^-1 a^-1 (gamma'' y0' - gamma' z0' + k a A1 gamma' gamma''), ...
    r1' = mu^-2 (...),  gamma_dot = r1 gamma' - mu^-1 q1 gamma'', ...
plus r1(0) = 1 (needed by the energy integral (2): r1^2 = 1 + mu^-2 s1 with s1(0) = 0).
Solve for lam, sig, rho, mu, k.

Part B (numerics): map the printed (35) to physical variables under
  reading A (consistent): mu = r0/c, r0 = mu c, tau = r0 t, p = c p1, r = r0 r1;
  reading B (as printed in (4)): mu = c/r0, r0 = c/mu, same maps otherwise;
integrate the full model from the mapped tau = 0 state and compare over one period.
"""
import sys, os, time
import numpy as np
import sympy as sp
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import formulas as F


def part_a():
    print('Part A: coefficient matching (sympy)')
    lam, sig, rho, mu, kk, r0, C, Mgl, N = sp.symbols('lambda sigma rho mu k r_0 C Mgl N', positive=True)
    A, B = sp.symbols('A B', positive=True)
    # dimensional p-equation: A p_dot + (C-B) q r = Mgl (y0 g'' - z0 g') + N (C-B) g' g''
    # with p = sig p1, q = sig q1, r = rho r1, d/dt = lam d/dtau:
    #   p1' + [(C-B)/A] (rho/lam) q1 r1 = Mgl/(A sig lam) (...) + N (C-B)/(A sig lam) g'g''
    # printed (1):   p1' + A1 q1 r1 = mu^-1 a^-1 (... + k a A1 g'g'')   with a = A/C, A1 = (C-B)/A
    eqs = [
        sp.Eq(rho / lam, 1),                               # coefficient of A1 q1 r1 in (1); r1 gamma' in Poisson
        sp.Eq(Mgl / (A * sig * lam), 1 / (mu * A / C)),    # gravity torque coefficient mu^-1 a^-1
        sp.Eq(N / (sig * lam), kk / mu),                   # Newtonian torque: mu^-1 k A1
        sp.Eq(sig / lam, 1 / mu),                          # -mu^-1 q1 gamma'' in the Poisson equation
        sp.Eq(rho, r0),                                    # r1(0) = 1 (energy integral (2))
    ]
    sol = sp.solve(eqs, [lam, sig, rho, mu, kk], dict=True)
    for s_ in sol:
        print('   ', {str(k_): sp.simplify(v) for k_, v in s_.items()})
    s_ = sol[0]
    # remaining coefficients of the r-equation: C r_dot + (B-A) p q = Mgl (x0 g' - y0 g) + N (B-A) g g'
    #   r1' = -(C1) sig^2/(rho lam) p1 q1 + Mgl/(C rho lam)(...) + N C1 /(rho lam) g g'
    chk = [sp.simplify((sig**2 / (rho * lam)).subs(s_) * s_[mu]**2),
           sp.simplify((Mgl / (C * rho * lam)).subs(s_) * s_[mu]**2),
           sp.simplify((N / (rho * lam)).subs(s_) * s_[mu]**2 / s_[kk])]
    print('    r-equation coefficients times mu^2 (must be 1, 1, 1):', chk)
    print('    => with c^2 = Mgl/C:  tau = r0 t, p1 = p/c, q1 = q/c, r1 = r/r0, k = N/c^2, and mu = r0/c'
          ' (NOT c/r0 as printed in (4)).')


def part_b():
    print('\nPart B: map printed (35) with the two readings, integrate the full model (c = 1)')
    base = dict(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=np.sqrt(0.66), k=0.3, Gamma=0.5, c=1.0)
    keys = ('p1', 'q1', 'r1', 'g1', 'g2', 'g3')
    print('%6s | %-44s | %-44s' % ('mu', 'reading A: mu=r0/c  max|err| gamma, gamma\'\'',
                                   'reading B: mu=c/r0  max|err| gamma, gamma\'\''))
    out = []
    for mu in [4, 16, 64, 256]:
        P = dict(base, mu=float(mu))
        tau = np.linspace(0, 2 * np.pi, 300)
        S = F.printed_solution_35(tau, P)
        Y0 = np.array([S[k_][0] for k_ in keys])
        row = []
        for r0 in (mu * 1.0, 1.0 / mu):
            # physical initial state: p = c p1, q = c q1, r = r0 r1 ; time t = tau / r0
            X0 = np.array([Y0[0], Y0[1], r0 * Y0[2], Y0[3], Y0[4], Y0[5]])
            X = F.integrate_full_model(P, X0, tau / r0)
            row += [np.max(np.abs(X[3] - S['g1'])), np.max(np.abs(X[5] - S['g3']))]
        out.append(row)
        print('%6d | gamma: %10.3e  gamma\'\': %10.3e            | gamma: %10.3e  gamma\'\': %10.3e' % (mu, *row))
    out = np.array(out)
    print('    reading A errors fall like mu^-2 (gamma) and mu^-4 (gamma\'\'); reading B errors are O(1):')
    print('    under B the body starts almost at rest (r0 = c/mu) with its z axis horizontal and simply falls')
    print('    (gamma\'\' leaves 0 by O(1) within a time ~1/c), while (35) predicts gamma\'\' ~ const.')
    # what time scale: under reading B, how long until |gamma''| > 0.5 ?
    mu = 16.0
    P = dict(base, mu=mu)
    S = F.printed_solution_35(np.array([0.0]), P)
    X0 = np.array([S['p1'][0], S['q1'][0], S['r1'][0] / mu, S['g1'][0], S['g2'][0], S['g3'][0]])
    t = np.linspace(0, 5, 501)
    X = F.integrate_full_model(P, X0, t)
    i = np.argmax(np.abs(X[5]) > 0.5)
    print('    reading B, mu = 16: |gamma\'\'| first exceeds 0.5 at c t = %.2f, whereas (35) needs c t = 2 pi mu = %.0f'
          ' for one period' % (t[i], 2 * np.pi * mu))


def part_c():
    """Fast-spin interpretation: the precession rate of (38) is the gyroscopic one."""
    print('\nPart C: meaning of the expansion (consistent reading)')
    print('    eps = 1/mu = c/r0 = sqrt(Mgl/C)/r0 -> expansion in powers of the ratio of the pendulum')
    print('    frequency c to the spin r0: the classical FAST-TOP (Lyapunov/Poincare) regime r0 >> c.')
    print('    Mean precession rate psi_dot = (c^2/r0)(chi1 - chi2/A1)/2 = -(Mgl z0\'/(C r0)) + O(k gamma0\'\'):'
          ' the gyroscopic precession of a fast top.')
    base = dict(a=2.0, b=1.5, x0=0.5, y0=0.3, z0=np.sqrt(0.66), k=0.0, Gamma=0.5, c=1.0, mu=50.0)
    d = F.derived(base)
    print('    check (k=0): (chi1 - chi2/A1)/2 = %.6f,  -z0\' = %.6f' % (0.5 * (d['chi1'] - d['chi2'] / d['A1']), -base['z0']))


if __name__ == '__main__':
    t0 = time.time()
    part_a()
    part_b()
    part_c()
    print('[%.1f s]' % (time.time() - t0))
