"""The paper's printed closed-form solutions (15), (16), (18), (20), (21), (25), (28), (30), after (31), (45)
checked numerically against eq. (1) (``gyrolab.physics.attitude.frame_from_angles`` and ω′ = J q̇) at random
parameters and times: max difference of α, β, γ, ω′, and whether the printed triad is right-handed."""

from __future__ import annotations

import numpy as np

from gyrolab.physics.attitude import frame_from_angles
from gyrolab.physics.gyrostat_euler import kinematic_matrix

c, s = np.cos, np.sin
R3 = np.sqrt(3.0)

# label -> (Euler angles (ψ, θ, φ) and rates as functions of (t, m, n, W, psi0, th0), printed α, β, γ, ω′)
SOLUTIONS = {
    "(15)": (lambda t, m, n, W, p0, th: ((0, 0, m * t), (0, 0, m)),
             lambda t, m, n, W, p0, th: ((c(m*t), -s(m*t), 0), (s(m*t), c(m*t), 0), (0, 0, 1), (0, 0, m))),
    "(16)": (lambda t, m, n, W, p0, th: ((0, 0, -W * t), (0, 0, -W)),
             lambda t, m, n, W, p0, th: ((c(W*t), s(W*t), 0), (-s(W*t), c(W*t), 0), (0, 0, 1), (0, 0, -W))),
    "(18)": (lambda t, m, n, W, p0, th: ((0, th, m * t), (0, 0, m)),
             lambda t, m, n, W, p0, th: ((c(m*t), -s(m*t), 0), (c(th)*s(m*t), c(th)*c(m*t), -s(th)),
                                         (s(th)*s(m*t), s(th)*c(m*t), c(th)), (0, 0, m))),
    "(20)": (lambda t, m, n, W, p0, th: ((np.pi/2, np.pi/3, -W * t), (0, 0, -W)),
             lambda t, m, n, W, p0, th: ((s(W*t)/2, -c(W*t)/2, R3/2), (c(W*t), s(W*t), 0),
                                         (-R3/2*s(W*t), R3/2*c(W*t), 0.5), (0, 0, -W))),
    "(21)": (lambda t, m, n, W, p0, th: ((np.pi/2, 0, m * t), (0, 0, m)),
             lambda t, m, n, W, p0, th: ((s(m*t), c(m*t), 0), (c(m*t), -s(m*t), 0), (0, 0, 1), (0, 0, m))),
    "(25)": (lambda t, m, n, W, p0, th: ((np.pi/2, th, m * t), (0, 0, m)),
             lambda t, m, n, W, p0, th: ((-c(th)*s(m*t), -c(th)*c(m*t), s(th)), (c(m*t), -s(m*t), 0),
                                         (s(th)*s(m*t), s(th)*c(m*t), c(th)), (0, 0, m))),
    "(28)": (lambda t, m, n, W, p0, th: ((n*t + p0, np.pi, n*t), (n, 0, n)),
             lambda t, m, n, W, p0, th: ((c(p0), s(p0), 0), (s(p0), -c(p0), 0), (0, 0, -1), (0, 0, 0))),
    "(30)": (lambda t, m, n, W, p0, th: ((n*t + p0, 0, n*t), (n, 0, n)),
             lambda t, m, n, W, p0, th: ((c(2*n*t+p0), -s(2*n*t+p0), 0), (s(2*n*t+p0), c(2*n*t+p0), 0),
                                         (0, 0, 1), (0, 0, 2*n))),
    "after (31)": (lambda t, m, n, W, p0, th: ((n*t + p0, np.pi, 2*n*t), (n, 0, 2*n)),
                   lambda t, m, n, W, p0, th: ((c(n*t-p0), s(n*t-p0), 0), (s(n*t-p0), -c(n*t-p0), 0),
                                               (0, 0, -1), (0, 0, n))),
    "(45)": (lambda t, m, n, W, p0, th: ((n*t + p0, 0, m*t), (n, 0, m)),
             lambda t, m, n, W, p0, th: ((c(n*t+p0+m*t), -s(n*t+p0+m*t), 0), (s(n*t+p0+m*t), c(n*t+p0+m*t), 0),
                                         (0, 0, 1), (0, 0, n+m))),
}


def check_closed_forms(seed: int = 2, samples: int = 20) -> list[dict]:
    rng = np.random.default_rng(seed)
    rows = []
    for label, (angles, printed) in SOLUTIONS.items():
        worst = {"alpha": 0.0, "beta": 0.0, "gamma": 0.0, "omega_relative": 0.0}
        handed = 0.0
        for _ in range(samples):
            t, m, n, W, p0, th = rng.uniform(0.1, 2.0, 6)
            q, qd = angles(t, m, n, W, p0, th)
            expected = (*frame_from_angles(*q), kinematic_matrix(q[1], q[2]) @ np.asarray(qd, dtype=float))
            got = [np.asarray(v, dtype=float) for v in printed(t, m, n, W, p0, th)]
            for key, e, g in zip(worst, expected, got):
                worst[key] = max(worst[key], float(np.max(np.abs(e - g))))
            handed = max(handed, float(np.max(np.abs(np.cross(got[0], got[1]) - got[2]))))
        rows.append({"solution": label, **{f"max_diff_{k}": v for k, v in worst.items()},
                     "right_handed_error": handed, "agrees_with_eq1": bool(max(worst.values()) < 1e-12)})
    return rows
