"""Physical admissibility of the resonance omega = 3 (seed 001).

omega^2 = -A1 B1 = (C-A)(C-B)/(A B) = (1-a)(1-b)/(a b),  a = A/C, b = B/C > 0.
Key identity:   omega^2 - 1 = (1 - a - b)/(a b) = C (C - A - B)/(A B).
Hence for every physical body (triangle inequality A + B >= C):  omega^2 <= 1,
with equality only for a planar lamina (C = A + B).  omega = 3 (indeed any
omega > 1) requires A + B < C: NON-PHYSICAL inertia.  Cases:
  a, b < 1 (spin about major axis): omega^2 > 1  <=>  a + b < 1  (violates A + B >= C)
  a, b > 1 (spin about minor axis): omega^2 = (1-1/a)(1-1/b) < 1 always
  mixed                            : omega^2 < 0 (no oscillation)
On the omega = 3 curve  b = (1-a)/(1+8a), 0 < a < 1:
  1 - a - b = 8 a (1-a)/(1+8a) > 0,  so the triangle defect never closes;
  a = b = 1/4 is the symmetric point (the paper's 'A, B vs C/4' classification).
Run: python admissibility.py
"""
import sympy as sp

a, b = sp.symbols('a b', positive=True)
w2 = (1 - a) * (1 - b) / (a * b)
print('omega^2 - 1 =', sp.factor(sp.simplify(w2 - 1)), '  (= (1 - a - b)/(a b))')
assert sp.simplify(w2 - 1 - (1 - a - b) / (a * b)) == 0
# a, b > 1: omega^2 < 1 ; substitute a = 1 + u, b = 1 + v, u, v > 0
u, v = sp.symbols('u v', positive=True)
e = sp.simplify(1 - w2.subs({a: 1 + u, b: 1 + v}))
print('a,b>1: 1 - omega^2 =', sp.factor(e), ' > 0 for u, v > 0:', sp.factor(e).is_positive)
# omega^2 = 9  <=>  b = (1-a)/(1+8a)
bsol = sp.solve(sp.Eq(w2, 9), b)
print('omega = 3 curve: b =', bsol)
bb = bsol[0]
defect = sp.factor(sp.simplify(1 - a - bb))
print('triangle defect 1 - a - b on the curve =', defect)
s = sp.Symbol('s', positive=True)   # a = s/(1+s) in (0,1)
print('  positive for all 0<a<1:', sp.factor(defect.subs(a, s / (1 + s))).is_positive)
print('max of a + b on the curve (0<a<1):',
      sp.maximum(a + bb, a, sp.Interval.open(0, 1)), '(supremum, at a -> 0 or 1, not attained)')
print('symmetric point a = b:', sp.solve(sp.Eq(bb, a), a))
print('\nExample bodies on the omega=3 curve (a, b, a+b):')
for av in (sp.Rational(1, 10), sp.Rational(1, 4), sp.Rational(2, 5), sp.Rational(1, 2), sp.Rational(9, 10)):
    bv = bb.subs(a, av)
    print(f'   a={av}, b={bv}, a+b={sp.nsimplify(av + bv)} = {float(av + bv):.4f} < 1,'
          f' omega^2 = {sp.simplify(w2.subs({a: av, b: bv}))}')
