"""Calibration of small_parameter's refusal band around the resonances ω = 1, 2 (docs/regimes.md).

For c/r0 = 0.1, 0.05, 0.025 and ρ = ε²/|n² − ω²| = 0.02 … 0.1 (upper side, ω > n), the max relative error of
the series against the exact periodic orbit over one period (regime_validity.resonance_point, domain check
off), then a fit err = K ε^a / |n² − ω²|^s per resonance. Needs the gyrolab package. Run: python resonance_band.py
(~10 s). Printed fit (2026-11-22): ω = 2: K = 5.71, a = 2.96, s = 0.95 (log residuals ≤ 0.05);
ω = 1: no power law (residuals up to 1.9): the error blows up at |1 − ω²| ≈ 0.11, 0.042, 0.017.
"""
import logging

import numpy as np

from gyrolab.engine.config import compose_config
from gyrolab.experiments.regime_validity import resonance_point

logging.disable(logging.WARNING)


def main():
    cfg = compose_config(["experiment=regime_validity"])
    rows = {1.0: [], 2.0: []}
    for r0 in (10.0, 20.0, 40.0):
        cfg.regime_validity.resonance_sweep.r0 = r0
        eps = 1 / r0
        for n in rows:
            line = []
            for rho in (0.02, 0.035, 0.05, 0.07, 0.1):
                w = np.sqrt(n * n + eps**2 / rho)
                status, e = resonance_point(cfg, w, check=False)
                if status == "ok":
                    rows[n].append((eps, w, max(e.values())))
                line.append(f"{w:.4f}:{max(e.values()):.1e}" if status == "ok" else f"{w:.4f}:{status[:6]}")
            print(f"c/r0={eps:.3f} n={n:g}", " ".join(line))
    for n, data in rows.items():
        eps, w, err = np.array(data).T
        A = np.column_stack([np.ones_like(eps), np.log(eps), -np.log(np.abs(n * n - w * w))])
        coef = np.linalg.lstsq(A, np.log(err), rcond=None)[0]
        print(f"n={n:g}: K={np.exp(coef[0]):.3g} a={coef[1]:.2f} s={coef[2]:.2f} "
              f"max |log residual| {np.max(np.abs(np.log(err) - A @ coef)):.2f}")


if __name__ == "__main__":
    main()
