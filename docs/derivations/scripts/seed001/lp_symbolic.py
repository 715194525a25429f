"""Independent Lindstedt-Poincare (LP) derivation of the omega = 3 periodic
solutions (seed 001, Shaker / El-Barki / Ismail).

Works directly on the full scaled Euler-Poisson system -- it does NOT use the
paper's reduced system (1)-(4) -- so it is an independent check of the printed
formulas (22)-(28).

Scaled variables (paper eq. (5)); k below is the PAPER's k = k_gt * gamma0''.
    P = p1, Q = q1, R = r1, G = gamma1, H = gamma1', K = gamma1''
    theta = Omega * tau,  Omega = 2*pi/T,  tau = r0 t,  ' = d/dtheta
    Omega P' = -A1 Q R + mu a^-1 (y K - z H + k a A1 H K)
    Omega Q' = -B1 P R + mu b^-1 (z G - x K + k b B1 K G)
    Omega R' = mu^2 (-C1 P Q + x H - y G + k C1 G H)
    Omega G' = R H - mu Q K
    Omega H' = mu P K - R G
    Omega K' = mu (Q G - P H)
(x, y, z) = (x0', y0', z0').  Normalisation of the periodic orbit:
R(0) = 1, K(0) = 1 (definitions of r0, gamma0''), H(0) = 0 (phase: gamma'(0)=0,
i.e. phi(0) = pi/2), G(0) = M exactly, hence M = tan(theta0) exactly.
The omega = 3 constraint A1*B1 = -9 is imposed by the parametrisation
    b = (1-a)/(1+8a),  A1 = 9/(1+8a),  B1 = -(1+8a),  C1 = b - a.

Generating solution: P0 = M1 cos 3th + M2 sin 3th, Q0 = -P0'/A1,
G0 = M cos th, H0 = -M sin th, R0 = K0 = 1.
Case (i): M1 = M2 = 0.  Case (ii)-(iv): see main_case_iii().

Run:  python lp_symbolic.py        (~7 s on one core)
Writes lp_case_i.txt with all derived coefficients (plain sympy strings).
"""
import os
import time
import sympy as sp
from sympy import QQ

GENS = 'a,x,y,z,k,M,M1,M2,l1,m1,l2,m2,l3,m3'
FLD, a, x, y, z, k, M, M1, M2, l1, m1, l2, m2, l3, m3 = sp.field(GENS, QQ)
one = FLD.one
b = (1 - a) / (1 + 8 * a)
A1 = 9 / (1 + 8 * a)
B1 = -(1 + 8 * a)
C1 = b - a
HALF = one / 2


# ------------------------------------------------------------- real trig polys
class T:
    """sum_m c[m] cos(m th) + s[m] sin(m th), m >= 0, coefficients in FLD"""

    def __init__(self, c=None, s=None):
        self.c = {m: v for m, v in (c or {}).items() if v != 0}
        self.s = {m: v for m, v in (s or {}).items() if v != 0 and m != 0}

    @staticmethod
    def const(v):
        return T({0: FLD(v)})

    def __add__(self, o):
        if not isinstance(o, T):
            o = T.const(o)
        c, s = dict(self.c), dict(self.s)
        for m, v in o.c.items():
            c[m] = c.get(m, 0) + v
        for m, v in o.s.items():
            s[m] = s.get(m, 0) + v
        return T(c, s)

    __radd__ = __add__

    def __neg__(self):
        return T({m: -v for m, v in self.c.items()}, {m: -v for m, v in self.s.items()})

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, T):
            return T({m: v * o for m, v in self.c.items()}, {m: v * o for m, v in self.s.items()})
        c, s = {}, {}

        def addc(m, v):
            m = abs(m)
            c[m] = c.get(m, 0) + v

        def adds(m, v):
            if m < 0:
                m, v = -m, -v
            s[m] = s.get(m, 0) + v

        for m, u in self.c.items():
            for n, v in o.c.items():
                addc(m + n, HALF * u * v)
                addc(m - n, HALF * u * v)
            for n, v in o.s.items():  # cos m sin n = (sin(m+n) - sin(m-n))/2
                adds(m + n, HALF * u * v)
                adds(m - n, -HALF * u * v)
        for m, u in self.s.items():
            for n, v in o.c.items():  # sin m cos n = (sin(m+n) + sin(m-n))/2
                adds(m + n, HALF * u * v)
                adds(m - n, HALF * u * v)
            for n, v in o.s.items():  # sin m sin n = (cos(m-n) - cos(m+n))/2
                addc(m - n, HALF * u * v)
                addc(m + n, -HALF * u * v)
        return T(c, s)

    __rmul__ = __mul__

    def d(self):
        c = {m: m * v for m, v in self.s.items()}
        s = {m: -m * v for m, v in self.c.items() if m}
        return T(c, s)

    def at0(self):
        return sum(self.c.values(), FLD.zero)

    def subs(self, rule):
        """rule: dict generator-name -> FLD element"""
        def sb(v):
            e = v.as_expr().subs({sp.Symbol(kk): vv.as_expr() for kk, vv in rule.items()})
            return FLD.from_expr(sp.together(e)) if e != 0 else FLD.zero
        return T({m: sb(v) for m, v in self.c.items()}, {m: sb(v) for m, v in self.s.items()})

    def items(self):
        for m in sorted(set(self.c) | set(self.s)):
            if m in self.c:
                yield ('cos', m), self.c[m]
            if m in self.s:
                yield ('sin', m), self.s[m]

    def expr(self, th):
        e = 0
        for (kind, m), v in self.items():
            f = 1 if m == 0 else (sp.cos(m * th) if kind == 'cos' else sp.sin(m * th))
            e += v.as_expr() * f
        return e


def smul(A, B, n):
    out = T()
    for i in range(n + 1):
        if i < len(A) and n - i < len(B):
            out = out + A[i] * B[n - i]
    return out


def residual(X, Om, n):
    """order-n coefficient of  Omega X' - f(X, mu), with X[.][n] = 0, Omega_n = 0"""
    P, Q, R, G, H, K = (X[s] for s in 'PQRGHK')
    Oms = [T.const(1)] + [T.const(o) for o in Om[1:n]] + [T()]

    def lhs(S):
        return smul(Oms, [s.d() for s in S], n)

    def at(j, fn):  # coefficient of mu^n in mu^j * fn(order)
        return fn(n - j) if n - j >= 0 else T()

    fP = -A1 * smul(Q, R, n) + at(1, lambda j: (y * K[j] - z * H[j] + k * a * A1 * smul(H, K, j)) * (1 / a))
    fQ = -B1 * smul(P, R, n) + at(1, lambda j: (z * G[j] - x * K[j] + k * b * B1 * smul(K, G, j)) * (1 / b))
    fR = at(2, lambda j: -C1 * smul(P, Q, j) + x * H[j] - y * G[j] + k * C1 * smul(G, H, j))
    fG = smul(R, H, n) - at(1, lambda j: smul(Q, K, j))
    fH = at(1, lambda j: smul(P, K, j)) - smul(R, G, n)
    fK = at(1, lambda j: smul(Q, G, j) - smul(P, H, j))
    f = dict(zip('PQRGHK', (fP, fQ, fR, fG, fH, fK)))
    return {s: lhs(X[s]) - f[s] for s in 'PQRGHK'}


def integrate(S, name):
    if S.c.get(0, 0) != 0:
        raise RuntimeError(f'secular mean in {name}')
    return T({m: -v / m for m, v in S.s.items()}, {m: v / m for m, v in S.c.items() if m})


def solve_order(X, Om, n, hom):
    """Solve order n in place. hom = (lam, nu): homogeneous cos3/sin3 part of P_n.
    Returns (Omega_n, check, [cos3, sin3] resonance of P block)."""
    for s in 'PQRGHK':
        X[s] = X[s][:n] + [T()]
    S = {s: -v for s, v in residual(X, Om, n).items()}
    P0, Q0, G0, H0 = X['P'][0], X['Q'][0], X['G'][0], X['H'][0]
    # R and K: pure integrations, constants from R(0)=K(0)=1
    Rn = integrate(S['R'], 'R')
    Rn = Rn - Rn.at0()
    Kn = integrate(S['K'], 'K')
    Kn = Kn - Kn.at0()
    # G block  G' - H = SG,  H' + G = SH  (R_n coupling moved to rhs)
    SG = S['G'] + H0 * Rn
    SH = S['H'] - G0 * Rn
    # Omega_n term: S -= Omega_n X0'  ->  adds Omega_n*M*(sin, cos) to (SG, SH)
    chk = SH.s.get(1, 0) - SG.c.get(1, 0)          # must vanish identically
    Omn = -(SH.c.get(1, 0) + SG.s.get(1, 0)) / (2 * M)
    SG = SG + T({}, {1: Omn * M})
    SH = SH + T({1: Omn * M})
    # P0, Q0 also carry Omega_n X0' terms
    SP = S['P'] - Omn * P0.d() - A1 * Q0 * Rn
    SQ = S['Q'] - Omn * Q0.d() - B1 * P0 * Rn
    gc, gs, hc, hs = {}, {}, {}, {}
    for m in sorted(set(SG.c) | set(SG.s) | set(SH.c) | set(SH.s)):
        if m == 1:
            # resonant mode: solvable (chk = 0, Omega_n chosen); particular solution
            # with gc = gs = 0:  hc = -SG_c, hs = SH_c  (homogeneous part added below)
            hc[1], hs[1] = -SG.c.get(1, 0), SH.c.get(1, 0)
            continue
        sgc, sgs = SG.c.get(m, 0), SG.s.get(m, 0)
        shc, shs = SH.c.get(m, 0), SH.s.get(m, 0)
        if m == 0:
            gc[0], hc[0] = shc, -sgc
            continue
        gs[m] = (shs - m * sgc) / (1 - m * m)
        gc[m] = (shc + m * sgs) / (1 - m * m)
        hc[m] = m * gs[m] - sgc
        hs[m] = -m * gc[m] - sgs
    Gn, Hn = T(gc, gs), T(hc, hs)
    # homogeneous u cos + v sin (G), -u sin + v cos (H): impose G(0)=H(0)=0
    u, v = -Gn.at0(), -Hn.at0()
    Gn = Gn + T({1: u}, {1: v})
    Hn = Hn + T({1: v}, {1: -u})
    # P block:  P'' + 9P = SP' - A1 SQ
    rhs = SP.d() - A1 * SQ
    res3 = [rhs.c.get(3, FLD.zero), rhs.s.get(3, FLD.zero)]
    Pn = T({m: v / (9 - m * m) for m, v in rhs.c.items() if m != 3},
           {m: v / (9 - m * m) for m, v in rhs.s.items() if m != 3})
    lam, nu = hom
    Pn = Pn + T({3: lam}, {3: nu})
    Qn = (SP - Pn.d()) * (1 / A1)
    X['P'][n], X['Q'][n], X['R'][n] = Pn, Qn, Rn
    X['G'][n], X['H'][n], X['K'][n] = Gn, Hn, Kn
    return Omn, chk, res3


def subs_all(X, Om, rule):
    for s in X:
        X[s] = [t.subs(rule) for t in X[s]]
    return [Om[0]] + [FLD.from_expr(sp.together(o.as_expr().subs(
        {sp.Symbol(kk): vv.as_expr() for kk, vv in rule.items()}))) if o != 0 else o for o in Om[1:]]


def init(P0):
    Q0 = P0.d() * (-1 / A1)
    return {'P': [P0], 'Q': [Q0], 'R': [T.const(1)], 'G': [T({1: M})],
            'H': [T({}, {1: -M})], 'K': [T.const(1)]}, [one]


def fmt(v):
    return sp.factor(v.as_expr())


def main_case_i(verbose=True):
    t0 = time.time()
    X, Om = init(T())
    homs = {1: (l1, m1), 2: (l2, m2), 3: (l3, m3)}
    info = {}
    for n in (1, 2, 3):
        Omn, chk, res3 = solve_order(X, Om, n, homs[n])
        Om.append(Omn)
        assert chk == 0, f'G-block consistency failed at order {n}: {chk}'
        if n < 3:
            assert res3[0] == 0 and res3[1] == 0, 'unexpected resonance'
        else:
            # res3 linear in (l1, m1): solve 2x2
            e = [r.as_expr() for r in res3]
            sol = sp.solve(e, [sp.Symbol('l1'), sp.Symbol('m1')], dict=True)[0]
            info['l1'] = FLD.from_expr(sp.together(sol[sp.Symbol('l1')]))
            info['m1'] = FLD.from_expr(sp.together(sol[sp.Symbol('m1')]))
        if verbose:
            print(f'order {n} solved ({time.time() - t0:.1f}s), Omega_{n} =', fmt(Omn))
    # parity: P2 homogeneous part is fixed at order 4; by mu -> -mu symmetry l2 = m2 = 0
    Om = subs_all(X, Om, {'l1': info['l1'], 'm1': info['m1'], 'l2': FLD.zero, 'm2': FLD.zero})
    info['Om'] = Om
    return X, Om, info


def dump(X, Om, info, fname, orders=3):
    th = sp.Symbol('th')
    lines = []
    for key in ('l1', 'm1'):
        if key in info:
            lines.append(f'{key} = {fmt(info[key])}')
    for n, o in enumerate(Om):
        lines.append(f'Omega{n} = {sp.factor(o.as_expr()) if n else 1}')
    for s in 'PQRGHK':
        for n in range(min(orders + 1, len(X[s]))):
            for (kind, m), v in X[s][n].items():
                lines.append(f'{s}{n} {kind}{m} = {fmt(v)}')
    with open(fname, 'w') as fh:
        fh.write('\n'.join(lines) + '\n')
    return lines


if __name__ == '__main__':
    here = os.path.dirname(os.path.abspath(__file__))
    X, Om, info = main_case_i()
    lines = dump(X, Om, info, os.path.join(here, 'lp_case_i.txt'), orders=2)
    for ln in lines:
        print(ln)


def main_case_iii(verbose=True, M2zero=False):
    """Generating solution with O(1) p-mode: P0 = M1 cos 3th + M2 sin 3th.
    Order-2 P-block resonance -> amplitude equations (paper (22));
    order-3 resonance -> phase condition (which of (ii)-(iv) survive)."""
    t0 = time.time()
    P0 = T({3: M1}, {3: FLD.zero if M2zero else M2})
    X, Om = init(P0)
    homs = {1: (l1, m1), 2: (l2, m2), 3: (l3, m3)}
    out = {}
    for n in (1, 2, 3):
        Omn, chk, res3 = solve_order(X, Om, n, homs[n])
        Om.append(Omn)
        assert chk == 0, f'G-block consistency failed at order {n}'
        out[n] = (Omn, res3)
        if verbose:
            print(f'[case iii] order {n} solved ({time.time() - t0:.1f}s)')
        if n == 1:
            assert res3[0] == 0 and res3[1] == 0
    return X, Om, out
