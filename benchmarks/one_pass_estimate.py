"""Issue 32 item 3, the design measured before it is built: a Taylor run's global error estimated in the same pass.

    python benchmarks/one_pass_estimate.py               # the reference scene, t ∈ [0, 300], 3,001 outputs (~2 min)
    python benchmarks/one_pass_estimate.py --end 30      # shorter
    python benchmarks/one_pass_estimate.py --rule gyrolab   # gyrolab's own step rule and orders

Today ``output.error_estimate`` runs a companion (the method at tol/100) and ``auto`` a separate tangent run for its
chaos measure: two more integrations, ~4× the run's own cost (docs/performance.md). This prototype (plain numpy, no
gyrolab kernel) tests the alternative: the run's local errors, taken with their sign from the series' next terms,
propagated along the run by the linearised equation e' = J(y(t)) e, whose Taylor series is carried at a LOW order m
on each step of the run (Lang & Verwer 2007's linearised global-error equation; the steps are the run's own, sized
for its order p, so the tangent series' omitted terms shrink like e^(−2m)):

    e(t_k + s) = Σ_{j ≤ m} E_j s^j + Σ_{j = p+1}^{p+extra} c_j s^j,   E_0 = e(t_k),   (j+1) E_{j+1} = [J(y) e]_j

Two step rules (``--rule``): heyoka's and gyrolab's, both Jorba & Zou's, gyrolab's with longer steps. Printed:
the estimated max-norm error over the actual one (against the extended-precision reference,
``gyrolab.physics.reference``) at every output time, and the extra work in right-hand-side bilinear evaluations.
Results and the design they support: docs/integrators.md, "A one-pass error estimate".
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from gyrolab.kernels.taylor import order_for
from gyrolab.physics.reference import fixed_point_reference

INERTIA = np.array([2.0, 1.5, 1.0])  # the reference scene (experiment=perf_reference)
R_C = np.array([0.3, 0.2, 0.9327379053088815])
K = 0.5
Y0 = np.array([0.1, -0.05, 5.0, math.sin(1.0), 0.0, math.cos(1.0)])


def f_linear(y: np.ndarray) -> np.ndarray:
    """The linear part of f (the weight's torque): rows of y → rows."""
    return np.concatenate([np.cross(R_C, y[..., 3:]) / INERTIA, 0.0 * y[..., 3:]], axis=-1)


def f_bilinear(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Q(a, b) summed over rows (a Cauchy product's terms), f(y) = f_linear(y) + Q(y, y), Q symmetric."""
    def half(u, v):  # (Iω) × ω + k γ × Iγ, and γ × ω, for ω, γ from u and v
        return np.concatenate([np.cross(INERTIA * u[..., :3], v[..., :3]) + K * np.cross(u[..., 3:], INERTIA * v[..., 3:]),
                               np.cross(u[..., 3:], v[..., :3])], axis=-1) / np.concatenate([INERTIA, np.ones(3)])
    return 0.5 * (half(a, b) + half(b, a)).sum(axis=0)


def coefficients(y: np.ndarray, order: int) -> np.ndarray:
    c = np.zeros((order + 1, 6))
    c[0] = y
    for j in range(order):
        c[j + 1] = (f_linear(c[j]) + f_bilinear(c[:j + 1], c[j::-1])) / (j + 1)
    return c


def tangent_coefficients(c: np.ndarray, e: np.ndarray, m: int) -> np.ndarray:
    """E_0..E_m of e' = J(y(t)) e = f_linear(e) + 2 Q(y(t), e) along y(t) = Σ c_i t^i."""
    E = np.zeros((m + 1, 6))
    E[0] = e
    for j in range(m):
        E[j + 1] = (f_linear(E[j]) + 2.0 * f_bilinear(c[:j + 1], E[j::-1])) / (j + 1)
    return E


def horner(c: np.ndarray, s: float) -> np.ndarray:
    out = np.zeros(c.shape[1])
    for row in c[::-1]:
        out = out * s + row
    return out


def run(tol: float, grid: np.ndarray, m: int, extra: int, rule: str) -> tuple[np.ndarray, np.ndarray, int, int]:
    """(states, estimated signed errors at the output times, steps, order) of one Taylor run; ``rule``: heyoka's
    steps (h = ρ e^(−2) e^(−0.7/(p−1)), order ⌈−ln(tol)/2⌉ + 1) or gyrolab's (``kernels.taylor``: its ``order_for``, and
    h = min_k (tol·scale/‖c_k‖)^(1/k) e^(−0.7/(p−1)), longer steps at its higher orders)."""
    p = int(math.ceil(-math.log(tol) / 2)) + 1 if rule == "heyoka" else order_for(tol)
    y, t, e, k, steps = Y0.copy(), 0.0, np.zeros(6), 1, 0
    out, est = np.zeros((len(grid), 6)), np.zeros((len(grid), 6))
    out[0] = y
    while k < len(grid):
        c = coefficients(y, p + extra)
        scale = max(1.0, float(np.max(np.abs(y))))
        within = 1.0 if rule == "heyoka" else tol  # (heyoka's ρ has no tolerance in it: its order has)
        h = min((within * scale / np.max(np.abs(c[j]))) ** (1.0 / j) for j in (p - 1, p)) * math.exp(-0.7 / (p - 1))
        h *= math.exp(-2.0) if rule == "heyoka" else 1.0
        E = tangent_coefficients(c, e, m)
        while k < len(grid) and grid[k] <= t + h:  # the propagated error, plus this step's truncation up to s
            s = grid[k] - t
            out[k], est[k] = horner(c[:p + 1], s), -(horner(E, s) + horner(c[p + 1:], s) * s ** (p + 1))
            k += 1
        e = horner(E, h) + horner(c[p + 1:], h) * h ** (p + 1)
        y, t, steps = horner(c[:p + 1], h), t + h, steps + 1
    return out, est, steps, p


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--end", type=float, default=300.0)
    parser.add_argument("--rule", choices=("heyoka", "gyrolab"), default="heyoka", help="the step rule (default heyoka)")
    args = parser.parse_args()
    grid = np.linspace(0.0, args.end, int(round(10 * args.end)) + 1)
    reference = fixed_point_reference(INERTIA, R_C, K, Y0, grid).astype(float)
    print(f"{args.rule}'s step rule; reference scene, t ∈ [0, {args.end:g}], {len(grid):,} outputs; estimated / actual max-norm error at "
          f"every output time where the actual one is above 1e-13\n")
    print("| tol | order p | steps | m | extra terms | actual final | estimate / actual: min – max | extra work |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for tol in (1e-6, 1e-8, 1e-10, 1e-12):
        for m, extra in ((4, 2), (6, 1), (6, 2)) if args.rule == "heyoka" else ((6, 2), (10, 2), (10, 4)):
            y, est, steps, p = run(tol, grid, m, extra, args.rule)
            actual = np.abs(y - reference).max(axis=1)
            measured = actual > 1e-13
            ratio = np.abs(est).max(axis=1)[measured] / actual[measured]
            # bilinear evaluations per step: the run's series to order p, its `extra` more orders, the tangent's m
            run_work, more = p * (p + 1) / 2, (p + extra) * (p + extra + 1) / 2 - p * (p + 1) / 2 + m * (m + 1) / 2
            print(f"| {tol:.0e} | {p} | {steps} | {m} | {extra} | {actual[-1]:.2e} | {ratio.min():.2f} – "
                  f"{ratio.max():.2f} | +{100 * more / run_work:.0f} % |")


if __name__ == "__main__":
    main()
