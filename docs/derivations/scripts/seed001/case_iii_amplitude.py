"""Cases (ii)-(iv) of (23): finite p-mode amplitude, E^2 = M1^2 + M2^2 = a2/a1.

(a) Case (iii) (M1 = +-sqrt(a2/a1), M2 = 0): the exact periodic orbit of the full
    model is found by shooting from the generating solution; the Fourier
    coefficients c3, s3 of p1(th) on cos 3th, sin 3th are compared with
    sqrt(a2/a1) using the PRINTED a2 and the CORRECTED a2.  Expect |c3| - E = O(mu)
    for the right a2, and s3 = O(mu) (phase locked to eps = 0, pi).
(b) Cases (ii)/(iv) (M2 != 0): Newton started from M1 = 0, M2 = E (and from the
    45-degree phase of (iv)) does not find an orbit with that phase: it either
    diverges or lands on a case-(iii)/(i) orbit (prints where it ends).
    Reason (lp_symbolic.py, order-3 solvability): the cos-3th periodicity condition
    contains the resonant forcing M3^3 L310 (L310 = k z0' C1 (4b-1)/(16ab) != 0),
    which can only be balanced when M1 != 0; with M1 = 0 it leaves
    -3 M^3 k z (2a+1)(4a-1)^2 != 0.  So (ii) and (iv) are NOT realised unless L310 = 0.

Run: python case_iii_amplitude.py      (~40 s)
"""
import numpy as np
import formulas as F
import printed as P
from fullmodel import Body, shoot

PAR = dict(a=0.4, b=1.0 / 7.0, x0=0.48, y0=0.36, z0=-0.8, k_gt=2.0, theta0=np.pi / 3)
MUS = 0.04 / np.sqrt(2.0) ** np.arange(5)


def fourier3(body, s, Tn, g0):
    t = np.linspace(0.0, Tn, 513)[:-1]
    Y = body.flow(s, Tn, dense=True).sol(t)
    th = 2 * np.pi * t / Tn
    p1 = Y[0] / np.sqrt(g0)
    return 2 * np.mean(p1 * np.cos(3 * th)), 2 * np.mean(p1 * np.sin(3 * th))


def main():
    c = F.constants(**PAR)
    pc = P.constants(**PAR)
    body = Body(PAR['a'], PAR['b'], PAR['x0'], PAR['y0'], PAR['z0'], PAR['k_gt'])
    g0, sq, A1 = c['g0'], np.sqrt(c['g0']), c['A1']
    Ec, Ep = np.sqrt(c['a2'] / c['a1']), np.sqrt(pc['a2'] / pc['a1'])
    print(f'body: a=0.4 b=1/7 r_c=(0.48,0.36,-0.8) k_gt=2 theta0=60deg  M3={c["M"]:.6f} k={c["k"]:.3f}')
    print(f'a1 = {c["a1"]:.6f} (printed = corrected);  a2 printed {pc["a2"]:.6f}, corrected {c["a2"]:.6f}')
    print(f'E = sqrt(a2/a1): printed {Ep:.6f}, corrected {Ec:.6f};  L310 (corrected) = {c["L310"]:.6f}')
    for sign in (+1, -1):
        print(f'\n(a) case (iii), M1 = {"+" if sign > 0 else "-"}E')
        print('     mu        c3          s3       |c3|-E_printed  |c3|-E_corrected')
        rows = []
        for mu in MUS:
            r0 = sq / mu
            p0 = sq * (sign * Ec + mu * (c['e'] + c['e1'] * c['M']))
            q0 = sq * mu * (PAR['y0'] / PAR['a']) / A1
            s, Tn, rn = shoot(body, r0, g0, p0, q0, 2 * np.pi / r0)
            if rn > 1e-9:
                print(f'  {mu:8.5f}  shooting failed |res|={rn:.1e}')
                continue
            c3, s3 = fourier3(body, s, Tn, g0)
            rows.append((mu, abs(c3) - Ep, abs(c3) - Ec, s3))
            print(f'  {mu:8.5f} {c3: .7f} {s3: .3e}   {abs(c3) - Ep: .3e}     {abs(c3) - Ec: .3e}')
        rows = np.array(rows)
        if len(rows) >= 4:
            lm = np.log(rows[-4:, 0])
            print('   fitted order of |c3|-E_corrected: %.2f ; of s3: %.2f ; |c3|-E_printed -> %.4f (no decay)'
                  % (np.polyfit(lm, np.log(np.abs(rows[-4:, 2])), 1)[0],
                     np.polyfit(lm, np.log(np.abs(rows[-4:, 3])), 1)[0], rows[-1, 1]))
    print('\n(b) Newton started on case (ii) M1=0, M2=E and case (iv) M1=M2=E/sqrt2 (mu = 0.02):')
    mu = 0.02
    r0 = sq / mu
    for lab, (m1, m2) in (('(ii)', (0.0, Ec)), ('(iv)', (Ec / np.sqrt(2), Ec / np.sqrt(2)))):
        p0 = sq * (m1 + mu * (c['e'] + c['e1'] * c['M']))
        q0 = sq * (-3 * m2 / A1 + mu * (PAR['y0'] / PAR['a']) / A1)   # Q0 = -P0'/A1
        s, Tn, rn = shoot(body, r0, g0, p0, q0, 2 * np.pi / r0, maxit=40)
        if rn < 1e-9:
            c3, s3 = fourier3(body, s, Tn, g0)
            print(f'   {lab}: converged to an orbit with c3 = {c3:.5f}, s3 = {s3:.2e} '
                  f'(i.e. M1 ~ {c3:.3f}, M2 ~ 0: not the requested phase)')
        else:
            print(f'   {lab}: Newton did not converge (|res| = {rn:.2e}) -> no periodic orbit with that phase')


if __name__ == '__main__':
    main()
