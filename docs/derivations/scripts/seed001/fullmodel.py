"""Ground-truth full model and periodic-orbit shooting (helper for seed-001 scripts).

Nondimensional heavy rigid body + Newtonian centre on the fixed Z axis:
    I w' = (I w) x w + r_c x g + k_gt g x (I g),   g' = g x w,   I = diag(a, b, 1)
Time unit 1/c, angular velocity unit c.  Integrator: solve_ivp DOP853,
rtol = atol = 1e-12 (tighter is pointless in double precision).
"""
import numpy as np
from scipy.integrate import solve_ivp

RTOL = ATOL = 1e-12


def hat(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


class Body:
    def __init__(self, a, b, x0, y0, z0, k_gt):
        self.I = np.array([a, b, 1.0])
        self.rc = np.array([x0, y0, z0], dtype=float)
        self.k = k_gt

    def rhs(self, t, s):
        w, g = s[:3], s[3:6]
        I = self.I
        Iw, Ig = I * w, I * g
        dw = (np.cross(Iw, w) + np.cross(self.rc, g) + self.k * np.cross(g, Ig)) / I
        dg = np.cross(g, w)
        return np.concatenate([dw, dg])

    def rhs_psi(self, t, s):
        """state (w, g, psi): psi' = (p g + q g')/(1 - g''^2)"""
        d = self.rhs(t, s[:6])
        w, g = s[:3], s[3:6]
        dpsi = (w[0] * g[0] + w[1] * g[1]) / (1.0 - g[2] ** 2)
        return np.concatenate([d, [dpsi]])

    def jac(self, s):
        w, g = s[:3], s[3:6]
        I = self.I
        Id = np.diag(I)
        Jww = (hat(I * w) - hat(w) @ Id) / I[:, None]
        Jwg = (hat(self.rc) + self.k * (hat(g) @ Id - hat(I * g))) / I[:, None]
        Jgw = hat(g)
        Jgg = -hat(w)
        return np.block([[Jww, Jwg], [Jgw, Jgg]])

    def rhs_var(self, t, S):
        s = S[:6]
        Phi = S[6:].reshape(6, 6)
        return np.concatenate([self.rhs(t, s), (self.jac(s) @ Phi).ravel()])

    def energy(self, s):
        w, g = s[:3], s[3:6]
        return np.sum(self.I * w * w) - 2 * self.rc @ g + self.k * np.sum(self.I * g * g)

    def area(self, s):
        return np.sum(self.I * s[:3] * s[3:6])

    def flow(self, s0, T, dense=False, psi=False):
        f = self.rhs_psi if psi else self.rhs
        y0 = np.concatenate([s0, [0.0]]) if psi else s0
        return solve_ivp(f, (0.0, T), y0, method='DOP853', rtol=RTOL, atol=ATOL, dense_output=dense)

    def flow_var(self, s0, T):
        S0 = np.concatenate([s0, np.eye(6).ravel()])
        sol = solve_ivp(self.rhs_var, (0.0, T), S0, method='DOP853', rtol=RTOL, atol=ATOL)
        S = sol.y[:, -1]
        return S[:6], S[6:].reshape(6, 6)


def state_from(p0, q0, r0, g0pp, gp=0.0):
    """initial state with r(0) = r0, gamma''(0) = g0pp, gamma'(0) = gp, gamma(0) >= 0"""
    g = np.sqrt(1.0 - g0pp ** 2 - gp ** 2)
    return np.array([p0, q0, r0, g, gp, g0pp])


def shoot(body, r0, g0pp, p0, q0, T, phase=None, tol=1e-11, maxit=30, verbose=False):
    """Periodic orbit through a point with r = r0, gamma'' = g0pp and phase
    condition gamma' = phase(p0, q0) (default 0).  Unknowns (p0, q0, T).
    Gauss-Newton on the 6-component return residual.  Returns (state0, T, resnorm)."""
    u = np.array([p0, q0, T], dtype=float)
    ph = phase if phase is not None else (lambda p, q: 0.0)

    def s0_of(v):
        return state_from(v[0], v[1], r0, g0pp, ph(v[0], v[1]))

    res_norm = np.inf
    for it in range(maxit):
        s0 = s0_of(u)
        sT, Phi = body.flow_var(s0, u[2])
        res = sT - s0
        res_norm = np.linalg.norm(res)
        if verbose:
            print(f'   it {it}: |res| = {res_norm:.3e}')
        if res_norm < tol:
            break
        # d s0 / d(p0, q0) by finite differences of the (cheap) initial-state map
        h = 1e-7
        D = np.zeros((6, 2))
        for j in range(2):
            du = np.zeros(3)
            du[j] = h
            D[:, j] = (s0_of(u + du) - s0_of(u - du)) / (2 * h)
        J = np.zeros((6, 3))
        J[:, :2] = Phi @ D - D
        J[:, 2] = body.rhs(0.0, sT)
        du = np.linalg.lstsq(J, -res, rcond=None)[0]
        u = u + du
    return s0_of(u), u[2], res_norm


def euler_from_numeric(body, s0, T, t):
    """exact Euler angles along the numerical orbit at times t (psi(0) = 0)."""
    sol = body.flow(s0, max(T, t[-1]), dense=True, psi=True)
    Y = sol.sol(t)
    g, gp, gpp = Y[3], Y[4], Y[5]
    theta = np.arccos(np.clip(gpp, -1, 1))
    phi = np.unwrap(np.arctan2(g, gp))
    psi = Y[6]
    return theta, psi, phi, Y
