"""Euler angles (29)-(33): printed vs repaired vs corrected vs full model.

Exact angles along the numerically found periodic orbit (case (i)):
  theta = arccos gamma'', phi = unwrap(atan2(gamma, gamma')) (phi(0) = pi/2),
  psi from integrating psi' = (p gamma + q gamma')/(1 - gamma''^2), psi(0) = 0.
Errors = max over t in [0, 3T] (three periods).  Variants:
  P      : (32)-(33) as printed (r0 in units of c inside phi_2),
  P+l1   : printed with corrected l1 only,
  P+l1+f : additionally phi_2 repaired: 'r0^-1 k C1 tan^2' -> '1/2 k C1 tan^2' and the
           spurious '-1/4 (1+3/A1) r0^-1 cos 4 r0 t' dropped,
  C      : formulas.euler_angles (corrected; same as P+l1+f but with phase Omega r0 t).
Also prints the data of the suggested figure body (mu = 0.1) at a few times.

Run: python euler_angles.py     (~35 s)
"""
import numpy as np
import formulas as F
import printed as P
from fullmodel import Body, shoot, euler_from_numeric

MUS = 0.2 / np.sqrt(2.0) ** np.arange(8)


def run(par, label):
    c = F.constants(**par)
    pc = P.constants(**par)
    body = Body(par['a'], par['b'], par['x0'], par['y0'], par['z0'], par['k_gt'])
    g0 = c['g0']
    print(f'\n=== {label}')
    rows = []
    for mu in MUS:
        r0 = np.sqrt(g0) / mu
        s0 = F.initial_state(r0, c)
        s, Tn, rn = shoot(body, r0, g0, s0[0], s0[1], F.period(r0, c))
        t = np.linspace(0.0, 3 * Tn, 721)
        th, ps, ph, _ = euler_from_numeric(body, s, Tn, t)
        variants = {
            'P': P.euler_angles(t, r0, pc),
            'P+l1': P.euler_angles(t, r0, pc, l1=c['l1']),
            'P+l1+f': P.euler_angles(t, r0, pc, l1=c['l1'], half_not_r0inv=True, drop_cos4=True),
            'C': F.euler_angles(t, r0, c),
        }
        row = [mu]
        for v in variants.values():
            row += [np.max(np.abs(v[0] - th)), np.max(np.abs(v[1] - ps)), np.max(np.abs(v[2] - ph))]
        rows.append(row)
    rows = np.array(rows)
    names = ['P', 'P+l1', 'P+l1+f', 'C']
    print('    mu    ' + ''.join(f'{n + ":th":>10s}{n + ":psi":>10s}{n + ":phi":>10s}' for n in names))
    for r in rows:
        print(f'  {r[0]:7.4f} ' + ''.join(f'{v:10.2e}' for v in r[1:]))
    print('  fitted orders (5 smallest mu):')
    lm = np.log(rows[-5:, 0])
    for i, n in enumerate(names):
        sl = [np.polyfit(lm, np.log(rows[-5:, 1 + 3 * i + j]), 1)[0] for j in range(3)]
        print(f'     {n:7s} theta {sl[0]:5.2f}  psi {sl[1]:5.2f}  phi {sl[2]:5.2f}')


def figure_data():
    par = F.FIGURE_BODY
    c = F.constants(**par)
    body = Body(par['a'], par['b'], par['x0'], par['y0'], par['z0'], par['k_gt'])
    r0 = F.FIGURE_R0
    s0 = F.initial_state(r0, c)
    s, Tn, rn = shoot(body, r0, c['g0'], s0[0], s0[1], F.period(r0, c))
    tmax = 60.0
    t = np.linspace(0.0, tmax, 6001)
    th, ps, ph, _ = euler_from_numeric(body, s, tmax, t)
    thc, psc, phc = F.euler_angles(t, r0, c)
    print(f'\n=== figure body, mu = 0.1 (r0 = {r0:.6f} c), t in [0, {tmax}] (1/c), '
          f'T = {Tn:.8f} (series {F.period(r0, c):.8f})')
    print(f'   initial state (p, q, r, g, g\', g\'\') = {np.array2string(s, precision=10)}')
    for tw in (20.0, 60.0):
        m = t <= tw + 1e-12
        print(f'   t in [0,{tw:4.0f}]: max |theta err| {np.max(np.abs(thc[m] - th[m])):.2e}'
              f'  |psi err| {np.max(np.abs(psc[m] - ps[m])):.2e}  |phi err| {np.max(np.abs(phc[m] - ph[m])):.2e}')
    print(f'   theta range num [{np.degrees(th.min()):.5f}, {np.degrees(th.max()):.5f}] deg,'
          f' psi(60) num {ps[-1]:.6f} series {psc[-1]:.6f}, phi(60) num {ph[-1]:.4f} series {phc[-1]:.4f}')
    for tt in (0.0, 0.35, 10.0, 30.0, 60.0):
        i = int(round(tt / tmax * 6000))
        print(f'   t={t[i]:6.2f}: theta {th[i]:.8f}/{thc[i]:.8f}  psi {ps[i]:.8f}/{psc[i]:.8f}'
              f'  phi {ph[i]:.6f}/{phc[i]:.6f}   (num/series)')


if __name__ == '__main__':
    run(F.FIGURE_BODY, 'B1 (figure body)')
    from case_i_convergence import BODIES
    run(BODIES['B2'], 'B2 (larger k C1 tan^2 theta0: isolates the phi_2 garble)')
    figure_data()
