"""Radius of convergence of the fast-spin Lindstedt series near the resonances ω = 1, 2, 3 (issue 13, item 1).

Body family of regime_validity's resonance sweep: b = 0.6, a = (1 − b)/(1 − b + ω²b) (so ω is set exactly),
centre of mass and k of report 000's body I, fixed tilt γ0'' = 0.025 (Γ = 0.5 at c/r0 = 0.05). For each
|ω − n| the series is computed through order 32 and its radius R estimated (Domb–Sykes on Ω, the estimate the
regime reports: the median of the root test, Domb–Sykes and Padé). Fit the root test's R ∝ |n² − ω²|^β near
each n (near a resonance the Domb–Sykes ratios oscillate; the root test is monotone and agrees with Padé). The refusal band of small_parameter is |n² − ω²| < K ε^p;
the series converges where ε < R, i.e. |n² − ω²| > (ε/R0)^(1/β): the band's exponent p should be 1/β.

Also: the order-N series against the exact orbit at c/r0 = 0.05 just outside and inside the band near ω = 2.

Run: python docs/derivations/scripts/seed000/lindstedt_resonances.py   (about 20 s)
"""

import numpy as np
from gyrolab.errors import GyrolabError
from gyrolab.analysis.lindstedt_check import exact_orbit, series_error
from gyrolab.physics.lindstedt import Body, series
from gyrolab.plugins.regimes.small_parameter import divisor_threshold

Z0 = float(np.sqrt(1 - 0.34))
TILT = 0.025


def body(omega):
    b = 0.6
    a = (1 - b) / (1 - b + omega**2 * b)
    return Body(a=a, b=b, x0=0.5, y0=0.3, z0=Z0, k=0.3)


def main():
    distances = np.array([0.3, 0.2, 0.1, 0.05, 0.03, 0.02, 0.01, 0.005])
    for n in (1.0, 2.0, 3.0):
        print(f"\nω → {n:g}")
        for side in (-1, 1):
            rows = []
            for d in distances:
                w = n + side * d
                sol = series(body(w), 32, tilt=TILT)
                r = sol.radius()
                rows.append((abs(n * n - w * w), r["root"]))
                print(f"  ω = {w:.4f}  |n² − ω²| = {abs(n * n - w * w):.4g}  R = {sol.radius_of_convergence():.4g}  "
                      f"(root {r['root']:.4g}, Domb–Sykes {r['domb_sykes']:.4g}, Padé {r['pade']:.4g})")
            x, R = np.array(rows).T
            near = distances <= 0.05
            beta = np.polyfit(np.log(x[near]), np.log(R[near]), 1)[0]
            print(f"  side {'below' if side < 0 else 'above'}: root-test R ∝ |n² − ω²|^{beta:.3f} (fit |ω − n| ≤ 0.05); "
                  f"band exponent implied 1/β = {1 / beta:.3f}")
    # where the band puts the edge, at c/r0 = 0.05 and 0.1: ε/R there
    print("\nε/R at the band's edge (1.0×) and at 2× the band, below each resonance:")
    for eps in (0.05, 0.1):
        for n in (1.0, 2.0, 3.0):
            for factor in (1.0, 2.0):
                x = factor * divisor_threshold(n, eps)
                w = np.sqrt(n * n - x)
                R = series(body(w), 32, tilt=TILT).radius_of_convergence()
                print(f"  ε = {eps:g}, n = {n:g}, |n² − ω²| = {x:.4g} (ω = {w:.5f}): R = {R:.4g}, ε/R = {eps / R:.3f}")
    print("\nOrder-N series against the exact orbit near ω = 2 (c/r0 = 0.05, below):")
    eps = 0.05
    for x in (4 * divisor_threshold(2.0, eps), divisor_threshold(2.0, eps), 0.25 * divisor_threshold(2.0, eps)):
        w = np.sqrt(4 - x)
        sol = series(body(w), 32, tilt=TILT)
        try:
            orbit = exact_orbit(sol.body, eps, TILT, sol)
        except GyrolabError as err:
            print(f"  |4 − ω²| = {x:.4g}: no orbit ({err})")
            continue
        errs = [series_error(sol, orbit, eps, N)["state"] for N in (3, 6, 10)]
        print(f"  |4 − ω²| = {x:.4g} (ω = {w:.5f}), R = {sol.radius_of_convergence():.3g}: error order 3/6/10 = "
              + " / ".join(f"{e:.2e}" for e in errs))


if __name__ == "__main__":
    main()
