"""Seed 002: numerical checks of the vector-form model (model.py).

Run:  python check_vector_model.py      (a few seconds)

 A. Jacobi integral conservation (DOP853, rtol = atol = 1e-12, 10 orbits) for
    random asymmetric gyrostats with all fields on; for contrast the same run
    with the Omega-terms dropped from the Poisson equations (wrong model).
 B. Derived Euler-angle equations vs. projected vector equations:
        E(q, qd, qdd) = J(q)^T R,   R = I dw/dt + w x (I w + k) - M,
    on random (q, qd, qdd) and random parameters.
 C. Same initial state integrated in Euler angles (rhs_euler) and in vector
    form (rhs_vector): agreement of gamma(t) over 2 orbits.
"""
import os
import sys

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import model  # noqa: E402

RTOL = ATOL = 1e-12


def random_params(rng):
    A, B, C = rng.uniform(0.8, 2.0, 3)
    return model.make_params(A, B, C, rng.normal(scale=0.5, size=3), rng.normal(scale=0.5, size=3),
                             rng.normal(scale=0.5), rng.normal(scale=0.5), 1.0)


def rhs_wrong(t, y, p):
    """Poisson equations written in the inertial-frame form (d alpha/dt = alpha x w):
    used only to show that the Jacobi test detects a missing Omega term."""
    I = model.inertia(p)
    w, al, be, ga = y[0:3], y[3:6], y[6:9], y[9:12]
    wd = (model.torque(al, ga, p) - np.cross(w, I * w + p['k'])) / I
    return np.concatenate([wd, np.cross(al, w), np.cross(be, w), np.cross(ga, w)])


def part_A(rng):
    print('A. Jacobi integral, 10 orbits, DOP853 rtol=atol=1e-12')
    T = 10 * 2 * np.pi
    worst = 0.0
    for trial in range(4):
        p = random_params(rng)
        q, qd = rng.uniform(-np.pi, np.pi, 3), rng.normal(size=3)
        q[1] = rng.uniform(0.3, 2.8)
        y0 = model.state_from_euler(q, qd, p)
        sol = solve_ivp(model.rhs_vector, (0, T), y0, method='DOP853', rtol=RTOL, atol=ATOL,
                        args=(p,), dense_output=False, t_eval=np.linspace(0, T, 2001))
        H = np.array([model.jacobi(y, p) for y in sol.y.T])
        dH = np.max(np.abs(H - H[0]))
        Y = sol.y.T
        orth = max(np.max(np.abs(np.einsum('ij,ij->i', Y[:, 3:6], Y[:, 9:12]))),
                   np.max(np.abs(np.linalg.norm(Y[:, 9:12], axis=1) - 1)))
        worst = max(worst, dH)
        print('   trial %d: H0 = %+.6f  max|H-H0| = %.2e  rel %.1e  (orthonormality drift %.1e, nfev %d)'
              % (trial, H[0], dH, dH / abs(H[0]), orth, sol.nfev))
        if trial == 0:
            solw = solve_ivp(rhs_wrong, (0, T), y0, method='DOP853', rtol=RTOL, atol=ATOL,
                             args=(p,), t_eval=np.linspace(0, T, 2001))
            Hw = np.array([model.jacobi(y, p) for y in solw.y.T])
            print('   (contrast, Poisson eqs without Omega terms: max|H-H0| = %.2e)'
                  % np.max(np.abs(Hw - Hw[0])))
    print('   worst max|H-H0| = %.2e' % worst)


def part_B(rng):
    print('B. Euler-angle equations vs J^T (vector residual), 1000 random states')
    worst = 0.0
    for _ in range(1000):
        p = random_params(rng)
        q = rng.uniform(-np.pi, np.pi, 3)
        qd, qdd = rng.normal(size=3), rng.normal(size=3)
        E = model.euler_angle_eqs(q, qd, qdd, p)
        R = model.vector_residual(q, qd, qdd, p)
        J = model.kin_matrix(q[1], q[2])
        worst = max(worst, np.max(np.abs(E - J.T @ R)))
    print('   max |E - J^T R| = %.2e' % worst)


def part_C(rng):
    print('C. Euler-angle integration vs vector integration, 2 orbits')
    p = random_params(rng)
    q, qd = np.array([0.3, 1.1, -0.4]), np.array([0.2, -0.1, 0.5])
    T = 2 * 2 * np.pi
    te = np.linspace(0, T, 401)
    s1 = solve_ivp(model.rhs_euler, (0, T), np.concatenate([q, qd]), method='DOP853',
                   rtol=RTOL, atol=ATOL, args=(p,), t_eval=te)
    s2 = solve_ivp(model.rhs_vector, (0, T), model.state_from_euler(q, qd, p), method='DOP853',
                   rtol=RTOL, atol=ATOL, args=(p,), t_eval=te)
    dmax = 0.0
    for x, y in zip(s1.y.T, s2.y.T):
        ye = model.state_from_euler(x[:3], x[3:], p)
        dmax = max(dmax, np.max(np.abs(ye - y)))
    th = s1.y[1]
    print('   theta range [%.3f, %.3f]; max |state_euler - state_vector| = %.2e'
          % (th.min(), th.max(), dmax))


if __name__ == '__main__':
    rng = np.random.default_rng(2021)
    part_A(rng)
    part_B(rng)
    part_C(rng)
