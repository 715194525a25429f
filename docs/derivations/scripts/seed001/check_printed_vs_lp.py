"""Symbolic comparison: printed formulas of seed 001 vs the independent LP derivation.

All expressions are reduced to rational functions of a on the omega = 3 curve
b = (1-a)/(1+8a) (A1 = 9/(1+8a), B1 = -(1+8a)), symbols x, y, z = x0', y0', z0',
k = paper's k (= k_gt gamma0''), M = M3 = tan(theta0).  A difference printed as 0
means 'identical on the omega = 3 curve'.

Run: python check_printed_vs_lp.py     (~30 s)
"""
import sympy as sp
from lp_symbolic import main_case_i, init, solve_order, T, l1 as L1, m1 as Mm1, l2, m2, l3, m3, M1, M2

a, x, y, z, k, M, L, th = sp.symbols('a x y z k M l1 th')
b = (1 - a) / (1 + 8 * a)
A1 = 9 / (1 + 8 * a)
B1 = -(1 + 8 * a)
C1 = b - a
e = x * A1 / (9 * b)
e1 = (k * (9 - A1) + z * (1 / a - A1 / b)) / 8
nu = -(1 + B1) / 8
e2 = e1 + z / a - k * A1


def z0(expr):
    return sp.factor(sp.simplify(sp.expand_trig(sp.cancel(expr))))


def main():
    X, Om, info = main_case_i(verbose=False)
    l1c = info['l1'].as_expr()
    P1, Q1 = X['P'][1].expr(th), X['Q'][1].expr(th)
    R2, K2 = X['R'][2].expr(th), X['K'][2].expr(th)
    print('1) (27) p at O(mu): printed e + e1 M cos + l1 cos3 (l1 := LP value) minus LP  ->',
          z0(e + e1 * M * sp.cos(th) + l1c * sp.cos(3 * th) - P1))
    print('   (27) q at O(mu): A1^-1 (y/a + e2 M sin + 3 l1 sin3) minus LP ->',
          z0((y / a + e2 * M * sp.sin(th) + 3 * l1c * sp.sin(3 * th)) / A1 - Q1))
    print('   LP: m1 (sin 3 tau coefficient, beta2 at O(mu)) =', info['m1'], '  (paper (26): m_i = 0)')
    print('2) (27) r at O(mu^2) minus LP ->',
          z0(-M * (x * (1 - sp.cos(th)) + y * sp.sin(th) + k * C1 * M / 4 * (1 - sp.cos(2 * th))) - R2))
    brk = M * (M / 2 * (e1 * a + b * e2 / A1) + a * e + x + k * C1 * M / 4 + a * L - (x + a * e) * sp.cos(th)
               + y * (1 + b / (a * A1)) * sp.sin(th)
               + (3 * b * L / A1 - a * L - k * C1 * M / 2 - e1 * a * M - e2 * b * M / A1) / 2 * sp.cos(2 * th)
               - L * (a + 3 * b / A1) / 2 * sp.cos(4 * th))
    print("3) (27) gamma'' bracket (same l1) minus LP ->", z0(brk.subs(L, l1c) - K2))
    a1p = (a - 1) * (a + b - 2) / (2 * b)
    a2p = z / (a * b) * (3 * (a + b) - 2 * (2 * a * b + 1)) + 18 * k * (1 - (a + b) + b * M ** 2 / 2)
    a2c = z / (a * b) * (3 * (a + b) - 2 * (2 * a * b + 1)) + 18 * k * (1 - (a + b) + (a + b) * M ** 2 / 4)
    L310p = k / 4 * (8 * e1 * (a - b) - z / 2 * (1 / a - A1 / b) * (a - b) + e2 * (1 - C1) + e1 * A1
                     + (A1 - 9) * (a * e1 + b * e2 / A1))
    L310c = k * z * C1 * (4 * b - 1) / (16 * a * b)
    print('4) l1 (LP) =', sp.factor(l1c))
    print('   l1_LP - M^3 L310c/a2c ->', z0(l1c - M ** 3 * L310c / a2c))
    print('   l1_LP - M^3 L310p/a2p (printed (26)) ->', z0(l1c - M ** 3 * L310p / a2p))
    print('   L310 printed =', sp.factor(sp.cancel(L310p)))
    print('   L310 correct =', sp.factor(sp.cancel(L310c)), '   [contains k*z only; printed has k^2 terms]')
    print('   a2 printed - a2 corrected =', z0(a2p - a2c), '  = 18 k M^2 (b/2 - (a+b)/4)')
    # amplitude equation of cases (ii)-(iv) from LP order 2
    Xg, Omg = init(T({3: M1}, {3: M2}))
    for n in (1, 2):
        Omn, chk, res3 = solve_order(Xg, Omg, n, {1: (L1, Mm1), 2: (l2, m2)}[n])
        Omg.append(Omn)
    E2 = sp.Symbol('M1') ** 2 + sp.Symbol('M2') ** 2
    amp = sp.factor(res3[0].as_expr() / sp.Symbol('M1'))
    print('5) LP order-2 cos3 periodicity condition / M1 =', amp)
    print('   -> check it equals (a2c - a1 E^2) * const:',
          sp.factor(sp.cancel(amp / (a2c - a1p * E2))))
    print('   printed a1 = (a-1)(a+b-2)/(2b) on the curve =', sp.factor(sp.cancel(a1p)))
    # alpha
    al_lp = -2 * sp.pi * Om[2].as_expr()
    al_p = sp.pi * (2 * M * x - 8 * nu * e1 - z / b + k * (M ** 2 * (b - a) - B1))
    al_c = sp.pi * (2 * M * x - 8 * nu * e1 - z / b + k * (M ** 2 * (b - a) / 2 - B1))
    print('6) alpha/mu^2 printed (28) - LP ->', z0(al_p - al_lp), '   = pi k C1 M^2 / 2')
    print('   alpha/mu^2 corrected - LP ->', z0(al_c - al_lp))
    # internal consistency with the paper's own phi rate in (32)
    rate_phi = 1 - ((e1 - e2 / A1) / 2 + M * x + k * C1 * M ** 2 / 4)       # (32): mean dphi/dtau / ... in mu^2 units
    print('7) (32) mean phi rate => Omega = 1 - mu^2[(e1-e2/A1)/2 + M x + k C1 M^2/4];'
          ' 2pi(1-Omega)/mu^2 - alpha_corrected ->', z0(2 * sp.pi * (1 - rate_phi) - al_c),
          '; - alpha_printed ->', z0(2 * sp.pi * (1 - rate_phi) - al_p))
    # Euler angles from the LP series (Fourier arithmetic, exact):
    #   dpsi/dtau = mu^2 X/(M sin th0), X = P1 G0 + Q1 H0  ->  psi_2 = int (X - <X>) / M
    #   phi_2 = int (R2 - <R2>) - psi_2 / M          (cot th0 = 1/M, tan th0 = M)
    from lp_symbolic import FLD, integrate as tint
    fe = lambda ex: FLD.from_expr(sp.together(sp.sympify(ex)))
    Xt = X['P'][1] * X['G'][0] + X['Q'][1] * X['H'][0]
    Xm = Xt.c.get(0, FLD.zero)
    print('8) (32) precession rate: 2<X>/M^2 - (e1 - e2/A1) ->', z0(2 * Xm.as_expr() / M ** 2 - (e1 - e2 / A1)))
    psi2 = tint(Xt - Xm, 'psi') * (1 / fe(M))
    R2t = X['R'][2]
    phi2 = tint(R2t - R2t.c.get(0, FLD.zero), 'phi') - psi2 * (1 / fe(M))
    Lc = info['l1']
    tn, ct = fe(M), 1 / fe(M)
    E_, E1, E2, A1f, C1f = fe(e), fe(e1), fe(e2), fe(A1), fe(C1)
    psi2_p = T({1: fe(y / (a * A1))}, {1: E_, 2: ((E2 / A1f + E1) * tn + Lc * (1 - 3 / A1f)) / 4,
                                        4: Lc * (1 + 3 / A1f) / 8})

    def phi2_p(f_sin2, cos4):
        return T({1: fe(y) * (tn - ct / (fe(a) * A1f)), 4: -(1 + 3 / A1f) / 4 * cos4},
                 {1: fe(x) * tn - E_ * ct,
                  2: (f_sin2 * fe(k) * C1f * tn ** 2 - E2 / A1f - E1 - Lc * ct + 3 * Lc * ct / A1f) / 4,
                  4: -(1 + 3 / A1f) / 4 * Lc * ct / 2})

    def show(lab, d):
        d = d - d.c.get(0, FLD.zero)          # constants cancel in psi2(t) - psi2(0)
        print(lab, {f'{kk[0]}{kk[1]}': sp.factor(v.as_expr()) for kk, v in d.items()} or 0)
    show('   psi_2 printed (33) - derived (same l1) ->', psi2_p - psi2)
    show('   phi_2 printed (33), r0^-1 kept as 0 (r0 -> inf) - derived ->', phi2_p(FLD.zero, FLD.zero) - phi2)
    show('   phi_2 with r0^-1 k C1 tan^2 -> 1/2 k C1 tan^2 and r0^-1 cos4 term dropped - derived ->',
         phi2_p(FLD(1) / 2, FLD.zero) - phi2)
    # cases (ii)/(iv): order-3 solvability
    for lab, P0 in (('(iii) M2=0', T({3: M1})), ('(ii)  M1=0', T({}, {3: M2}))):
        Xh, Omh = init(P0)
        for n in (1, 2, 3):
            Omn, chk, res3 = solve_order(Xh, Omh, n, {1: (L1, Mm1), 2: (l2, m2), 3: (l3, m3)}[n])
            Omh.append(Omn)
        r = [sp.expand(sp.numer(sp.together(v.as_expr()))) for v in res3]
        Ls, Ms = sp.Symbol('l1'), sp.Symbol('m1')
        print(f'9) case {lab}: order-3 periodicity, terms free of (l1, m1):'
              f' cos3 -> {sp.factor(r[0].subs({Ls: 0, Ms: 0}))},  sin3 -> {sp.factor(r[1].subs({Ls: 0, Ms: 0}))}')
    print('   In (ii) the cos3 condition reads 8(D - a E^2 poly) l1 - 3 M^3 k z (2a+1)(4a-1)^2 = 0 with')
    print('   D - a E^2 poly = 0 (amplitude relation): impossible unless k z (4a-1) = 0, i.e. L310 = 0.')


if __name__ == '__main__':
    main()
