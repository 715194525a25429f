"""Case (i) (M1 = M2 = 0): printed (27)/(28) vs corrected series vs the full model.

For each mu (log range) the exact periodic orbit of the full Euler-Poisson
model is found by shooting (r(0) = r0, gamma''(0) = gamma0'', gamma'(0) = 0),
then the max error over one period of each printed / corrected formula is
measured, and the order is fitted (least squares of log err vs log mu over the
5 smallest mu).

Columns:  P = printed as is, P+l1 = printed with only l1 replaced by the corrected
value, C = corrected (formulas.py).  Errors in scaled units: p, q / (c sqrt(g0'')),
r / r0, gamma-components / gamma0'', alpha in tau units.

Run: python case_i_convergence.py     (~25 s)
"""
import numpy as np
import formulas as F
import printed as P
from fullmodel import Body, shoot

BODIES = {
    'B1 (figure body)': F.FIGURE_BODY,
    'B2': dict(a=0.6, b=F.omega3_b(0.6), x0=-0.3, y0=0.5, z0=float(np.sqrt(1 - 0.34)),
               k_gt=2.5, theta0=np.pi / 3),
}
MUS = 0.2 / np.sqrt(2.0) ** np.arange(9)      # 0.2 ... 0.0125


def slope(mus, errs, n=5):
    m, e = np.log(mus[-n:]), np.log(np.abs(errs[-n:]))
    return np.polyfit(m, e, 1)[0]


def run(name, par, verbose=True):
    c = F.constants(**par)
    pc = P.constants(**par)
    body = Body(par['a'], par['b'], par['x0'], par['y0'], par['z0'], par['k_gt'])
    g0 = c['g0']
    sq = np.sqrt(g0)
    print(f'\n=== {name}: a={par["a"]:.4g} b={par["b"]:.6g} r_c=({par["x0"]:.3g},{par["y0"]:.3g},'
          f'{par["z0"]:.4g}) k_gt={par["k_gt"]} theta0={np.degrees(par["theta0"]):.4g} deg, M3={c["M"]:.6g}')
    print(f'   l1: printed {pc["l1"]:.6g}  corrected {c["l1"]:.6g};  a2: printed {pc["a2"]:.6g} '
          f'corrected {c["a2"]:.6g};  L310: printed {pc["L310"]:.6g} corrected {c["L310"]:.6g}')
    print(f'   alpha/mu^2: printed {pc["alpha2"]:.6g}  corrected {c["alpha2"]:.6g}')
    keys = ['pq_P', 'pq_Pl', 'pq_C', 'r_P', 'r_C', 'gpp_P', 'gpp_C', 'gpp_Pl', 'g_P', 'g_C',
            'al_P', 'al_C', 'l1num']
    E = {k: [] for k in keys}
    for mu in MUS:
        r0 = sq / mu
        s0 = F.initial_state(r0, c)
        T = F.period(r0, c)
        s, Tn, rn = shoot(body, r0, g0, s0[0], s0[1], T)
        assert rn < 1e-10, rn
        t = np.linspace(0.0, Tn, 241)
        sol = body.flow(s, Tn, dense=True)
        Y = sol.sol(t)
        Xc = F.body_solution(t, r0, c)
        Xp = P.body_solution(t, r0, pc)
        Xpl = P.body_solution(t, r0, pc, l1=c['l1'])

        def err(X, rows, scale):
            return np.max(np.abs(X[rows] - Y[rows])) / scale

        E['pq_P'].append(err(Xp, [0, 1], sq))
        E['pq_Pl'].append(err(Xpl, [0, 1], sq))
        E['pq_C'].append(err(Xc, [0, 1], sq))
        E['r_P'].append(err(Xp, [2], r0))
        E['r_C'].append(err(Xc, [2], r0))
        E['gpp_P'].append(err(Xp, [5], g0))
        E['gpp_Pl'].append(err(Xpl, [5], g0))
        E['gpp_C'].append(err(Xc, [5], g0))
        E['g_P'].append(err(Xp, [3, 4], g0))
        E['g_C'].append(err(Xc, [3, 4], g0))
        al = Tn * r0 - 2 * np.pi
        E['al_P'].append(abs(al - pc['alpha2'] * mu ** 2))
        E['al_C'].append(abs(al - c['alpha2'] * mu ** 2))
        # numerical l1: cos(3 th) Fourier coefficient of p1 over one period, / mu
        th = 2 * np.pi * t / Tn
        p1 = Y[0] / sq
        E['l1num'].append(2 * np.mean(p1[:-1] * np.cos(3 * th[:-1])) / mu)   # periodic rectangle rule
    E = {k: np.array(v) for k, v in E.items()}
    if verbose:
        print('     mu      |pq| P     |pq| P+l1  |pq| C     |r| P      |r| C      |g"| P     |g"| C'
              '     |g,g\'| P  |g,g\'| C  |alpha| P  |alpha| C   l1(num)')
        for i, mu in enumerate(MUS):
            print(f'  {mu:8.5f} ' + ' '.join(f'{E[k][i]:10.3e}' for k in
                  ('pq_P', 'pq_Pl', 'pq_C', 'r_P', 'r_C', 'gpp_P', 'gpp_C', 'g_P', 'g_C', 'al_P', 'al_C'))
                  + f'  {E["l1num"][i]: .6f}')
        print('  fitted order (5 smallest mu):')
        for k, lab in (('pq_P', 'p,q printed'), ('pq_Pl', 'p,q printed+l1'), ('pq_C', 'p,q corrected'),
                       ('r_P', 'r printed'), ('r_C', 'r corrected'), ('gpp_P', "gamma'' printed"),
                       ('gpp_Pl', "gamma'' printed+l1"), ('gpp_C', "gamma'' corrected"),
                       ('g_P', "gamma,gamma' printed(O(1) only)"), ('g_C', "gamma,gamma' corrected"),
                       ('al_P', 'alpha printed'), ('al_C', 'alpha corrected')):
            print(f'     {lab:34s} {slope(MUS, E[k]):5.2f}   (err at mu=0.0125: {E[k][-1]:.2e})')
        print(f'  alpha_num/mu^2 at smallest mu: {((E["al_C"][-1]) / MUS[-1] ** 2):.2e} off corrected;'
              f'  l1 from numerics -> {E["l1num"][-1]:.6f} (corrected {c["l1"]:.6f}, printed {pc["l1"]:.6f})')
    return E


if __name__ == '__main__':
    for name, par in BODIES.items():
        run(name, par)
