"""Independent Lindstedt-Poincare construction of the periodic solution of the
paper's system (1) (seed 000, Ismail 2021) in the regime gamma0'' = Gamma/mu.

Run:  python lindstedt.py            (prints the corrected solution, ~20 s)
      python lindstedt.py 4          (also Omega_4, ~100 s)

Conventions (consistent scaling, see the report):
    eps = 1/mu = c/r0,   p1 = p/c, q1 = q/c, r1 = r/r0, tau = r0 t,
    s = Omega*tau  (strained time, the exact period in tau is T = 2*pi/Omega),
    gamma''(0) = eps*Gamma, gamma'(0) = 0, gamma(0) = sqrt(1-eps^2 Gamma^2) > 0,
    r1(0) = 1, and no free oscillation at frequency omega (M1 = M2 = 0).
System (1) in s:
    Om p' = -A1 q r + eps[a^-1(y g3 - z g2) + k A1 g2 g3]
    Om q' = -B1 p r + eps[b^-1(z g1 - x g3) + k B1 g3 g1]
    Om r' = eps^2[-C1 p q + x g2 - y g1 + k C1 g1 g2]
    Om g1' = r g2 - eps q g3 ; Om g2' = eps p g3 - r g1 ; Om g3' = eps(q g1 - p g2)
(g1, g2, g3) = (gamma, gamma', gamma''); (x, y, z) = (x0', y0', z0').
The solution is expanded as  X = sum_n eps^n X_n(s)  with X_n trigonometric
polynomials, solved by harmonic balance order by order.
"""
import sympy as sp

a, b, x, y, z, k, G = sp.symbols('a b x y z k Gamma', real=True)
A1 = (1 - b) / a
B1 = (a - 1) / b
C1 = b - a
w2 = -A1 * B1  # omega^2


class TP:
    """Trig polynomial: {m: (cos coeff, sin coeff)}, m >= 0."""

    def __init__(self, d=None):
        self.d = {}
        for m, (c, s_) in (d or {}).items():
            self.d[m] = (sp.sympify(c), sp.sympify(s_ if m else 0))

    @staticmethod
    def const(c):
        return TP({0: (c, 0)})

    def copy(self):
        return TP(dict(self.d))

    def __add__(self, o):
        if not isinstance(o, TP):
            o = TP.const(o)
        r = dict(self.d)
        for m, (c, s_) in o.d.items():
            c0, s0 = r.get(m, (0, 0))
            r[m] = (c0 + c, s0 + s_)
        return TP(r)

    __radd__ = __add__

    def __neg__(self):
        return TP({m: (-c, -s_) for m, (c, s_) in self.d.items()})

    def __sub__(self, o):
        return self + (-o if isinstance(o, TP) else -sp.sympify(o))

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, TP):
            o = sp.sympify(o)
            return TP({m: (c * o, s_ * o) for m, (c, s_) in self.d.items()})
        r = {}

        def add(m, c, s_):
            if m < 0:
                m, s_ = -m, -s_
            c0, s0 = r.get(m, (0, 0))
            r[m] = (c0 + c, s0 + s_)
        for m, (c1, s1) in self.d.items():
            for n, (c2, s2) in o.d.items():
                # cos m cos n, sin m sin n, cos m sin n, sin m cos n
                add(m - n, c1 * c2 / 2, 0); add(m + n, c1 * c2 / 2, 0)
                add(m - n, s1 * s2 / 2, 0); add(m + n, -s1 * s2 / 2, 0)
                add(m + n, 0, c1 * s2 / 2); add(m - n, 0, -c1 * s2 / 2)
                add(m + n, 0, s1 * c2 / 2); add(m - n, 0, s1 * c2 / 2)
        return TP(r)

    __rmul__ = __mul__

    def deriv(self):
        return TP({m: (m * s_, -m * c) for m, (c, s_) in self.d.items() if m})

    def at0(self):
        return sum((c for c, _ in self.d.values()), sp.Integer(0))

    def simplify(self):
        r = {}
        for m, (c, s_) in self.d.items():
            c, s_ = sp.factor(sp.simplify(c)), sp.factor(sp.simplify(s_))
            if c != 0 or s_ != 0:
                r[m] = (c, s_)
        return TP(r)

    def expr(self, s):
        return sum((c * sp.cos(m * s) + s_ * sp.sin(m * s) for m, (c, s_) in self.d.items()), sp.Integer(0))


def solve(order=3, order_omega=None, verbose=True):
    """Return dict of lists of TP for p, q, r, g1, g2, g3 up to eps^order and Omega list."""
    if order_omega is None:
        order_omega = order
    N = max(order, order_omega)
    Z = TP()
    P = [Z]; Q = [Z]; R = [TP.const(1)]
    C = [TP({1: (1, 0)})]; S = [TP({1: (0, -1)})]; H = [Z]
    Om = [sp.Integer(1)]
    # gamma(0) = sqrt(1 - eps^2 Gamma^2) expansion
    eps = sp.Symbol('eps')
    g0ser = sp.series(sp.sqrt(1 - eps**2 * G**2), eps, 0, N + 2).removeO()
    Cinit = [g0ser.coeff(eps, n) for n in range(N + 2)]

    def cut(L, n):  # safe access
        return L[n] if n < len(L) and L[n] is not None else Z

    def conv(U, V, n):  # coefficient of eps^n of U*V
        out = TP()
        for i in range(n + 1):
            ui, vj = cut(U, i), cut(V, n - i)
            if ui.d and vj.d:
                out = out + ui * vj
        return out

    def lhs_known(X, n):  # sum_{i>=1, i<=n} Om_i X_{n-i}'  (excluding Om_n*X_0' if Om_n unknown)
        out = TP()
        for i in range(1, n + 1):
            if i < len(Om):
                out = out + cut(X, n - i).deriv() * Om[i]
        return out

    for n in range(1, N + 1):
        # right-hand sides: terms of order eps^n that do not contain unknown order-n quantities
        # Om p' = -A1 q r + eps[...]
        # -A1 (q r)_n = -A1 Q_n - A1 * sum_{i<n} Q_i R_{n-i}
        qr = TP()
        for i in range(n):
            qr = qr + cut(Q, i) * cut(R, n - i) if cut(Q, i).d and cut(R, n - i).d else qr
        pr = TP()
        for i in range(n):
            pr = pr + cut(P, i) * cut(R, n - i) if cut(P, i).d and cut(R, n - i).d else pr
        e1 = lambda U, V: conv(U, V, n - 1)
        fp = -A1 * qr + (cut(H, n - 1) * y - cut(S, n - 1) * z) * (1 / a) + e1(S, H) * (k * A1) - lhs_known(P, n)
        fq = -B1 * pr + (cut(C, n - 1) * z - cut(H, n - 1) * x) * (1 / b) + e1(H, C) * (k * B1) - lhs_known(Q, n)
        # r: Om r' = eps^2 [...]  -> order n uses order n-2 of bracket
        if n >= 2:
            m2 = n - 2
            fr = conv(P, Q, m2) * (-C1) + cut(S, m2) * x - cut(C, m2) * y + conv(C, S, m2) * (k * C1)
        else:
            fr = TP()
        fr = fr - lhs_known(R, n)
        # solve P_n, Q_n: P' + A1 Q = fp ; Q' + B1 P = fq  (no free oscillation)
        Pn, Qn = {}, {}
        for m in set(fp.d) | set(fq.d):
            fc, fs = fp.d.get(m, (0, 0)); gc, gs = fq.d.get(m, (0, 0))
            pc, ps, qc, qs = sp.symbols('pc ps qc qs')
            eqs = [m * ps + A1 * qc - fc, -m * pc + A1 * qs - fs, m * qs + B1 * pc - gc, -m * qc + B1 * ps - gs]
            sol = sp.solve(eqs, [pc, ps, qc, qs], dict=True)[0]
            Pn[m] = (sp.simplify(sol[pc]), sp.simplify(sol[ps] if m else 0))
            Qn[m] = (sp.simplify(sol[qc]), sp.simplify(sol[qs] if m else 0))
        P.append(TP(Pn).simplify()); Q.append(TP(Qn).simplify())
        # R_n: R' = fr, zero mean required, R_n(0)=0
        c0 = sp.simplify(fr.d.get(0, (0, 0))[0])
        if c0 != 0 and verbose:
            print('  WARNING secular term in r at order', n, c0)
        Rn = {m: (-s_ / m, c / m) for m, (c, s_) in fr.d.items() if m}
        Rn = TP(Rn)
        Rn = Rn - Rn.at0()
        R.append(Rn.simplify())
        # H_n: Om g3' = eps (q g1 - p g2): order n uses order n-1 of bracket
        fh = conv(Q, C, n - 1) - conv(P, S, n - 1) - lhs_known(H, n)
        c0 = sp.simplify(fh.d.get(0, (0, 0))[0])
        if c0 != 0 and verbose:
            print('  WARNING secular term in gamma\'\' at order', n, c0)
        if n >= 2:
            Hn = TP({m: (-s_ / m, c / m) for m, (c, s_) in fh.d.items() if m})
            Hn = Hn - Hn.at0()
            H.append(Hn.simplify())
        else:
            H.append(TP.const(G))
        # C_n, S_n: C' - S = fc ; S' + C = fs (+ unknown Om_n terms)
        rs = TP(); rc = TP()
        for i in range(1, n + 1):
            if cut(R, i).d and cut(S, n - i).d:
                rs = rs + cut(R, i) * cut(S, n - i)
            if cut(R, i).d and cut(C, n - i).d:
                rc = rc + cut(R, i) * cut(C, n - i)
        fc_ = rs - conv(Q, H, n - 1) - lhs_known(C, n)
        fs_ = conv(P, H, n - 1) - rc - lhs_known(S, n)
        Omn = sp.Symbol('Omn')
        fc_ = fc_ - C[0].deriv() * Omn
        fs_ = fs_ - S[0].deriv() * Omn
        Cn, Sn = {}, {}
        extra = []
        for m in set(fc_.d) | set(fs_.d):
            f1, f2 = fc_.d.get(m, (0, 0)); g1_, g2_ = fs_.d.get(m, (0, 0))
            cc, cs, sc, ss = sp.symbols('cc cs sc ss')
            eqs = [m * cs - sc - f1, -m * cc - ss - f2, m * ss + cc - g1_, -m * sc + cs - g2_]
            if m == 1:
                # singular: kernel (cc,cs,sc,ss) = (1,0,0,-1) and (0,1,1,0)
                # solvability: f1 + g2_ = 0 (from eq1+eq4) and f2 - g1_ = 0 (eq2 + eq3 ... )
                cond1 = sp.simplify(f1 - g2_)
                cond2 = sp.simplify(f2 + g1_)
                extra.append((cond1, cond2))
                sol_om = sp.solve([cond1, cond2], [Omn], dict=True)
                if not sol_om:
                    # one condition must hold identically
                    raise RuntimeError(f'no Omega at order {n}: {cond1}, {cond2}')
                om_val = sp.simplify(sol_om[0][Omn])
                # particular solution with cs = 0, ss = 0 -> then add kernel
                other = [c_ for c_ in (cond1, cond2) if sp.simplify(c_.subs(Omn, om_val)) != 0]
                if other:
                    print('  WARNING: second solvability condition not satisfied:', other)
                # direct: with cc=cs=0: eq1 -> sc = -f1 ; eq2 -> ss = -f2
                Cn[m] = [0, 0]; Sn[m] = [sp.simplify(-f1.subs(Omn, om_val)), sp.simplify(-f2.subs(Omn, om_val))]
                Om_n = om_val
            else:
                sol = sp.solve([e for e in eqs], [cc, cs, sc, ss], dict=True)[0]
                Cn[m] = [sp.simplify(sol[cc].subs(Omn, 0)), sp.simplify(sol[cs].subs(Omn, 0) if m else 0)]
                Sn[m] = [sp.simplify(sol[sc].subs(Omn, 0)), sp.simplify(sol[ss].subs(Omn, 0) if m else 0)]
        if 1 not in Cn:
            Om_n = sp.Integer(0)
            Cn[1] = [0, 0]; Sn[1] = [0, 0]
        # add kernel alpha*(cos, -sin) + beta*(sin, cos) to satisfy C_n(0)=Cinit[n], S_n(0)=0
        C0v = sum(v[0] for v in Cn.values()); S0v = sum(v[0] for v in Sn.values())
        alpha = Cinit[n] - C0v  # C(0) += alpha
        beta = -S0v             # S(0) += beta
        Cn[1][0] += alpha; Sn[1][1] += -alpha
        Cn[1][1] += beta; Sn[1][0] += beta
        C.append(TP({m: tuple(v) for m, v in Cn.items()}).simplify())
        S.append(TP({m: tuple(v) for m, v in Sn.items()}).simplify())
        Om.append(sp.factor(sp.simplify(Om_n)))
        if verbose:
            print(f'order {n}: Omega_{n} =', Om[n])
    return dict(p=P, q=Q, r=R, g1=C, g2=S, g3=H, Om=Om)


if __name__ == '__main__':
    import time
    import sys
    t0 = time.time()
    order = int(sys.argv[1]) if len(sys.argv) > 1 else 3   # 'python lindstedt.py 4' also gives Omega_4 (~100 s)
    sol = solve(order=order)
    s = sp.Symbol('s')
    names = {'p': 'p1', 'q': 'q1', 'r': 'r1', 'g1': 'gamma', 'g2': "gamma'", 'g3': "gamma''"}
    for key in ['p', 'q', 'r', 'g1', 'g2', 'g3']:
        for n in range(0, 3):
            e = sol[key][n]
            if e is None:
                continue
            ex = sp.simplify(e.expr(s))
            if ex != 0:
                print(f'{names[key]} [eps^{n}] =', ex)
    print('Omega =', ' + '.join(f'eps^{i}*({sp.factor(o)})' for i, o in enumerate(sol['Om'])))
    T = sp.series(2 * sp.pi / sum(sp.Symbol('eps')**i * o for i, o in enumerate(sol['Om'])), sp.Symbol('eps'), 0, 4)
    print('period T = 2 pi/Omega =', sp.simplify(T))
    print(f'[{time.time()-t0:.1f} s]')
