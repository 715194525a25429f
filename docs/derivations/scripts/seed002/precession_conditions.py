"""Seed 002: existence conditions of regular precessions
    psi = n t + psi0,  theta = theta0,  phi = m t
re-derived with sympy from the VECTOR equations and checked against every
printed condition set of sections 4.1.1, 4.1.2, 4.2 of the paper.

Run:  python precession_conditions.py        (about 30 s)

Method.  Along the precession the Poisson equations hold identically (the
frames are built from eq. (1)); the Euler-equation residual
    R(t) = I dw/dt + w x (I w + k) - M          (body components)
is a trigonometric polynomial in x = n t and y = m t.  Writing
sin/cos of x, y as symbols (sx, cx, sy, cy) and reducing modulo
sx^2 + cx^2 = 1, sy^2 + cy^2 = 1 gives a canonical polynomial whose monomials
sx^a cx^b sy^c cy^d (a, c <= 1) are linearly independent functions of t when
n, m and n/m are generic; for the resonant cases (n = 0, m = n, m = 2n,
theta0 in {0, pi}) the substitution is made before reducing.  The motion is a
solution iff every coefficient vanishes.
"""
import sympy as sp

A, B, C, W = sp.symbols('A B C Omega', real=True)
k1, k2, k3, m1, m2, m3, h1, h3 = sp.symbols('k1 k2 k3 mu1 mu2 mu3 h1 h3', real=True)
n, m, ps0, th0, t = sp.symbols('n m psi0 theta0 t', real=True)
x, y = sp.symbols('x y', real=True)
sx, cx, sy, cy = sp.symbols('sx cx sy cy')
s, c = sp.sin, sp.cos
S3 = sp.sqrt(3)


def residual(psi, theta, phi, dpsi, dphi):
    """Vector residual for psi(t), theta = const, phi(t) (sympy, body comps)."""
    al = sp.Matrix([c(psi) * c(phi) - c(theta) * s(phi) * s(psi),
                    -c(psi) * s(phi) - c(theta) * c(phi) * s(psi), s(theta) * s(psi)])
    ga = sp.Matrix([s(theta) * s(phi), s(theta) * c(phi), c(theta)])
    wr = sp.Matrix([dpsi * s(theta) * s(phi), dpsi * s(theta) * c(phi), dpsi * c(theta) + dphi])
    I = sp.diag(A, B, C)
    k = sp.Matrix([k1, k2, k3])
    mu = sp.Matrix([m1, m2, m3])
    w = wr + W * ga
    M = 3 * W ** 2 * al.cross(I * al) + h1 * al.cross(mu) + h3 * ga.cross(mu)
    return I * w.diff(t) + w.cross(I * w + k) - M


def coefficients(R, two_vars):
    """Canonical trigonometric coefficients of the three components of R."""
    gens = [sx, cx, sy, cy] if two_vars else [sx, cx]
    G = [sx ** 2 + cx ** 2 - 1] + ([sy ** 2 + cy ** 2 - 1] if two_vars else [])
    out = []
    for comp in R:
        e = sp.expand(sp.expand_trig(comp))
        e = e.subs({s(x): sx, c(x): cx, s(y): sy, c(y): cy})
        _, r = sp.reduced(sp.expand(e), G, *gens, order='lex')
        P = sp.Poly(r, *gens)
        out.extend([cf for _, cf in P.terms()])
    return out


def motion(kind, theta0=th0, psi0=ps0):
    """Residual coefficients for the structural families used in the paper."""
    if kind == 'n=0':              # psi = psi0, phi = m t   (x = m t)
        R = residual(psi0, theta0, m * t, 0, m).subs(m * t, x)
        return coefficients(R, False)
    if kind == 'm=n':              # psi = n t + psi0, phi = n t
        R = residual(psi0 + n * t, theta0, n * t, n, n).subs(n * t, x)
        return coefficients(R, False)
    if kind == 'm=2n':
        R = residual(psi0 + n * t, theta0, 2 * n * t, n, 2 * n).subs(n * t, x)
        return coefficients(R, False)
    if kind == 'generic':          # n t = x, m t = y independent
        R = residual(psi0 + n * t, theta0, m * t, n, m).subs({n * t: x, m * t: y})
        return coefficients(R, True)
    raise ValueError(kind)


def leftover(coeffs, subs):
    """Coefficients that do not vanish after substituting the conditions."""
    out = []
    for cf in coeffs:
        e = cf
        for _ in range(3):          # values may contain substituted symbols
            e = e.subs(subs)
        e = sp.simplify(sp.factor(sp.expand(e)))
        if e != 0:
            out.append(e)
    # deduplicate up to sign
    uniq = []
    for e in out:
        if not any(sp.simplify(e - u) == 0 or sp.simplify(e + u) == 0 for u in uniq):
            uniq.append(e)
    return uniq


def report(label, coeffs, subs, extra=''):
    lo = leftover(coeffs, subs)
    verdict = 'HOLDS' if not lo else 'FAILS'
    print('%-7s %-5s %s' % (label, verdict, extra))
    for e in lo:
        print('            nonvanishing coefficient: %s' % sp.factor(e))
    return lo


def main():
    print('=== general n = 0 family (permanent rotation in the orbital frame), '
          'coefficients of R ===')
    G0 = motion('n=0')
    for e in G0:
        print('   ', sp.factor(e))

    print('\n=== printed condition sets ===')
    # 4.1.1 Case I : psi0 = 0, A = B
    cI0 = motion('n=0', theta0=0, psi0=0)
    report('14.1', cI0, {B: A, m1: 0, m2: 0, k1: 0, k2: 0}, 'theta0=0: mu1=mu2=0, k1=k2=0')
    report('14.2', cI0, {B: A, m1: 0, m2: 0, m: -W}, 'theta0=0: mu1=mu2=0, m=-Omega')
    report('14.3', cI0, {B: A, h1: 0, k1: h3 * m1 / (m + W), k2: h3 * m2 / (m + W)},
           'theta0=0: h1=0, k_i = h3 mu_i/(m+Omega)')
    cIb = motion('n=0', psi0=0)
    report('17.1', cIb, {B: A, h1: 0, m1: 0, m2: 0, k1: 0, k2: 0,
                         k3: (W ** 2 * (B - C) * c(th0) - m * W * C + m3 * h3) / W})
    report('17.2', cIb, {B: A, m1: 0, m2: 0, m3: 0, k1: 0, k2: 0,
                         k3: c(th0) * (B - C) * W - C * m})
    # 4.1.1 Case II : psi0 = pi/2
    cIIa = motion('n=0', theta0=sp.pi / 3, psi0=sp.pi / 2)
    k3_read = (-m3 * h1 + S3 * (W ** 2 * (A + B - C) + m3 * h3)) / (S3 * W)
    k3_lit = -m3 * h1 * S3 * (W ** 2 * (A + B - C) + m3 * h3) / (S3 * W)
    report('19.1', cIIa, {m: -W, m1: 0, m2: 0, k1: 0, k2: 0, k3: k3_read},
           'reading k3 = (-mu3 h1 + sqrt3(Omega^2(A+B-C) + mu3 h3))/(sqrt3 Omega)')
    report('19.1L', cIIa, {m: -W, m1: 0, m2: 0, k1: 0, k2: 0, k3: k3_lit},
           'literal k3 = -mu3 h1 sqrt3 (Omega^2(A+B-C) + mu3 h3)/(sqrt3 Omega)')
    report('19.2', cIIa, {m: -W, h1: -S3 * h3, k1: 2 * m1 * h3 / W, k2: 2 * m2 * h3 / W,
                          k3: (W ** 2 * (A + B - C) + 2 * m3 * h3) / W})
    cII0 = motion('n=0', theta0=0, psi0=sp.pi / 2)
    report('22', cII0, {B: A, m1: 0, m2: 0, m3: 0, k1: 0, k2: 0})
    report('23', cII0, {B: A, h1: 0, k1: m1 * h3 / (m + W), k2: m2 * h3 / (m + W)})
    cIIb = motion('n=0', psi0=sp.pi / 2)
    report('24', cIIb, {B: A, k1: 0, k2: 0, m1: 0, m2: 0,
                        k3: (s(th0) * (4 * c(th0) * (B - C) * W ** 2 - C * W * m + m3 * h3)
                             - m3 * h1 * c(th0)) / (W * s(th0))})
    # 4.1.2 : n != 0
    c27 = motion('m=n', theta0=sp.pi)
    report('27', c27, {k1: (m3 * h1 * c(ps0) + m1 * h3) / W, k2: (m3 * h1 * s(ps0) + m2 * h3) / W,
                       h1: -sp.Rational(3, 2) * W ** 2 * (A - B) * s(2 * ps0) / (m1 * s(ps0) - m2 * c(ps0))})
    c29 = motion('m=n', theta0=0)
    report('29.1', c29, {B: A, m1: 0, m2: 0, k1: m3 * h1 * c(ps0) / (W + 2 * n),
                         k2: m3 * h1 * s(ps0) / (W + 2 * n)})
    report('29.1c', c29, {B: A, m1: 0, m2: 0, h1: 0, k1: 0, k2: 0}, 'corrected: add h1*mu3 = 0 => k1=k2=0')
    report('29.2', c29, {B: A, h1: 0, k1: m1 * h3 / (W + 2 * n), k2: m2 * h3 / (W + 2 * n)})
    c31 = motion('m=2n', theta0=sp.pi)
    report('31.1', c31, {B: A, h1: 0, k1: -m1 * h3 / (n - W), k2: -m2 * h3 / (n - W)})
    report('31.2a', c31, {B: A, m1: 0, m2: 0, m3: 0, k1: 0, k2: 0})
    report('31.2b', c31, {B: A, m1: 0, m2: 0, m3: 0, n: W})
    # 4.2 : generic n/m, theta0 = 0
    c44 = motion('generic', theta0=0)
    report('44.1', c44, {B: A, h1: 0, m1: (W + m + n) * k1 / h3, m2: (W + m + n) * k2 / h3})
    report('44.2', c44, {B: A, m1: 0, m2: 0, m3: 0, k1: 0, k2: 0})
    report('44.3', c44, {B: A, m1: 0, m2: 0, m3: 0, m: -W - n})
    # families not listed in the paper
    cN1 = motion('n=0', psi0=ps0)
    report('N1', cN1, {B: A, m1: 0, m2: 0, k1: 0, k2: 0,
                       h1: 3 * W ** 2 * (A - C) * s(ps0) * s(th0) / m3,
                       k3: (h3 * m3 - W * m * C - W ** 2 * (C - A) * c(th0) * (3 * s(ps0) ** 2 + 1)) / W
                       - h1 * m3 * s(ps0) * c(th0) / (W * s(th0))},
           'A=B, n=0, ANY psi0 (magnetic torque balances gravity gradient)')
    cN2 = motion('n=0', theta0=2 * sp.pi / 3, psi0=sp.pi / 2)
    report('N2', cN2, {m: W, h1: S3 * h3, k1: 2 * m1 * h3 / W, k2: 2 * m2 * h3 / W,
                       k3: -W * (A + B - C) + 2 * m3 * h3 / W}, 'mirror of 19.2 with cos th0 = -1/2')

    print('\n=== re-derived complete conditions for the families ===')
    # cylindrical theta0 = 0 (only s = n + m matters): use n = 0, m = s
    cyl = motion('n=0', theta0=0, psi0=0)
    print('theta0 = 0, spin s = n + m != 0 (cylindrical): coefficients')
    for e in sorted({sp.factor(e) for e in cyl}, key=str):
        print('   ', e)
    print('   => A = B, h1*mu = 0 (all components), (s+Omega) k1 = h3 mu1, (s+Omega) k2 = h3 mu2;'
          ' k3, C free')
    # Case II, A != B: solve
    print('psi0 = pi/2, n = 0, A != B (Case II):')
    cII = motion('n=0', psi0=sp.pi / 2)
    grav = [sp.factor(e.subs({k1: 0, k2: 0, k3: 0, m1: 0, m2: 0, m3: 0})) for e in cII]
    grav = [e for e in grav if e != 0]
    print('    field/gyrostat-free coefficients:', grav)
    u = sp.Symbol('u')  # cos theta0
    print('    sin^2 th0 - 3 cos^2 th0 = 0  =>  cos th0 =', sp.solve(1 - 4 * u ** 2, u))
    cIIp = motion('n=0', theta0=sp.pi / 3, psi0=sp.pi / 2)
    sol = sp.solve(cIIp, [m, k1, k2, k3, h1], dict=True)
    for d in sol:
        print('    cos th0 = 1/2 solution:', {kk: sp.simplify(v) for kk, v in d.items()})
    cIIm = motion('n=0', theta0=2 * sp.pi / 3, psi0=sp.pi / 2)
    sol = sp.solve(cIIm, [m, k1, k2, k3, h1], dict=True)
    for d in sol:
        print('    cos th0 = -1/2 solution:', {kk: sp.simplify(v) for kk, v in d.items()})
    # A = B, sin th0 != 0: solve for k3 (Case I and II)
    for lab, p0 in (('Case I (psi0=0)', 0), ('Case II (psi0=pi/2)', sp.pi / 2)):
        cc = motion('n=0', psi0=p0)
        cc = [sp.factor(e.subs({B: A, k1: 0, k2: 0, m1: 0, m2: 0})) for e in cc]
        cc = [e for e in cc if e != 0]
        sk = [v for e in cc if e.has(k3) for v in sp.solve(e, k3)][:1]
        print('    A=B, k1=k2=mu1=mu2=0, %s: remaining coefficients %s' % (lab, cc))
        print('        solved for k3:', [sp.simplify(v) for v in sk])
    # m = n, theta0 = 0 (29) complete
    print('theta0 = 0, m = n (29): coefficients with A = B:')
    for e in sorted({sp.factor(e.subs(B, A)) for e in c29} - {0}, key=str):
        print('   ', e)
    # generic, sin theta0 != 0
    print('generic n/m, sin th0 != 0: field-free gravity coefficients')
    cg = motion('generic')
    gg = sorted({sp.factor(e.subs({k1: 0, k2: 0, k3: 0, m1: 0, m2: 0, m3: 0}))
                 for e in cg} - {0}, key=str)
    for e in gg:
        print('   ', e)
    print('   => (B-C)cos2psi0, (B-C)sin2psi0, (A-C)cos2psi0, (A-C)sin2psi0 all appear: for sin th0 != 0'
          ' this needs A = B = C (spherical body); the magnetic coefficients then give h1 mu = 0')
    # spherical, generic: solve the rest
    sph = [sp.factor(e.subs({B: A, C: A, h1: 0})) for e in cg]
    sph = [e for e in sph if e != 0]
    print('    spherical, h1 = 0, remaining:', sph)
    print('    => k1 = k2 = 0, h3 mu1 = h3 mu2 = 0, k3 = h3 mu3/(Omega + n) - A m  (m != 0)')


if __name__ == '__main__':
    main()
