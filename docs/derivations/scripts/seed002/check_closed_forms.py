"""Seed 002: check of the printed closed-form solutions (15), (16), (18), (20),
(21), (25), (28), (30), the unnumbered one after (31), and (45).

Run:  python check_closed_forms.py        (a few seconds)

For each printed solution (alpha, beta, gamma, omega') we check, exactly with
sympy:
  eq1   equality with eq. (1) evaluated on the Euler angles of that case,
  rh    right-handed orthonormal triad (alpha x beta = gamma),
  kin   the Poisson kinematics d e/dt = e x omega' for e = alpha, beta, gamma
        (this is what eq. (1) implies: omega' is the relative angular velocity).
"""
import sympy as sp

t, m, n, W, ps0, th0 = sp.symbols('t m n Omega psi0 theta0', real=True)
s, c = sp.sin, sp.cos
S3 = sp.sqrt(3)
V = lambda *a: sp.Matrix(a)  # noqa: E731


def eq1(psi, theta, phi):
    al = V(c(psi) * c(phi) - c(theta) * s(phi) * s(psi), -c(psi) * s(phi) - c(theta) * c(phi) * s(psi), s(theta) * s(psi))
    be = V(s(psi) * c(phi) + c(theta) * s(phi) * c(psi), -s(psi) * s(phi) + c(theta) * c(phi) * c(psi), -s(theta) * c(psi))
    ga = V(s(theta) * s(phi), s(theta) * c(phi), c(theta))
    dpsi, dth, dphi = [sp.diff(v, t) for v in (psi, theta, phi)]
    w = V(dpsi * s(theta) * s(phi) + dth * c(phi), dpsi * s(theta) * c(phi) - dth * s(phi), dpsi * c(theta) + dphi)
    return al, be, ga, w


def zero(M):
    return all(sp.simplify(sp.expand_trig(e)) == 0 for e in M)


# (label, Euler angles (psi, theta, phi), printed (alpha, beta, gamma, omega'))
SOLUTIONS = [
    ('(15)', (0, 0, m * t),
     (V(c(m * t), -s(m * t), 0), V(s(m * t), c(m * t), 0), V(0, 0, 1), V(0, 0, m))),
    ('(16)', (0, 0, -W * t),
     (V(c(W * t), s(W * t), 0), V(-s(W * t), c(W * t), 0), V(0, 0, 1), V(0, 0, -W))),
    ('(18)', (0, th0, m * t),
     (V(c(m * t), -s(m * t), 0), V(c(th0) * s(m * t), c(th0) * c(m * t), -s(th0)),
      V(s(th0) * s(m * t), s(th0) * c(m * t), c(th0)), V(0, 0, m))),
    ('(20)', (sp.pi / 2, sp.pi / 3, -W * t),
     (V(s(W * t) / 2, -c(W * t) / 2, S3 / 2), V(c(W * t), s(W * t), 0),
      V(-S3 / 2 * s(W * t), S3 / 2 * c(W * t), sp.Rational(1, 2)), V(0, 0, -W))),
    ('(21)', (sp.pi / 2, 0, m * t),
     (V(s(m * t), c(m * t), 0), V(c(m * t), -s(m * t), 0), V(0, 0, 1), V(0, 0, m))),
    ('(25)', (sp.pi / 2, th0, m * t),
     (V(-c(th0) * s(m * t), -c(th0) * c(m * t), s(th0)), V(c(m * t), -s(m * t), 0),
      V(s(th0) * s(m * t), s(th0) * c(m * t), c(th0)), V(0, 0, m))),
    ('(28)', (n * t + ps0, sp.pi, n * t),
     (V(c(ps0), s(ps0), 0), V(s(ps0), -c(ps0), 0), V(0, 0, -1), V(0, 0, 0))),
    ('(30)', (n * t + ps0, 0, n * t),
     (V(c(2 * n * t + ps0), -s(2 * n * t + ps0), 0), V(s(2 * n * t + ps0), c(2 * n * t + ps0), 0),
      V(0, 0, 1), V(0, 0, 2 * n))),
    ('after (31)', (n * t + ps0, sp.pi, 2 * n * t),
     (V(c(n * t - ps0), s(n * t - ps0), 0), V(s(n * t - ps0), -c(n * t - ps0), 0),
      V(0, 0, -1), V(0, 0, n))),
    ('(45)', (n * t + ps0, 0, m * t),
     (V(c(n * t + ps0 + m * t), -s(n * t + ps0 + m * t), 0), V(s(n * t + ps0 + m * t), c(n * t + ps0 + m * t), 0),
      V(0, 0, 1), V(0, 0, n + m))),
]


def main():
    print('%-11s %-6s %-6s %-6s   notes' % ('solution', 'eq1', 'rh', 'kin'))
    for lab, angles, (al, be, ga, w) in SOLUTIONS:
        ang = [sp.sympify(a) for a in angles]
        al1, be1, ga1, w1 = eq1(*ang)
        ok_eq1 = [zero(al - al1), zero(be - be1), zero(ga - ga1), zero(w - w1)]
        rh = zero(al.cross(be) - ga) and zero(sp.Matrix([al.dot(al) - 1, be.dot(be) - 1, al.dot(be)]))
        kin = all(zero(e.diff(t) - e.cross(w)) for e in (al, be, ga))
        notes = []
        for name, ok, ref in zip(('alpha', 'beta', 'gamma', "omega'"), ok_eq1, (al1, be1, ga1, w1)):
            if not ok:
                notes.append('%s from eq.(1) = %s' % (name, list(sp.simplify(sp.expand_trig(ref)))))
        print('%-11s %-6s %-6s %-6s   %s' % (lab, all(ok_eq1), rh, kin, '; '.join(notes)))


if __name__ == '__main__':
    main()
