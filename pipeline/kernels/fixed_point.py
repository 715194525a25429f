"""The fixed-point system's packed built-in torque parameters.

Parameters are one float array ``p`` (``pack`` writes it), laid out and named in ``layout``: inertia I,
the linear-torque vectors U_i (torque U_i × e_i), the gradient coefficients N_i (torque N_i e_i × I e_i),
a flag saying whether the state carries α, and 1/I. e_0 = α (fixed X), e_1 = β = γ × α (fixed Y),
e_2 = γ (vertical).
"""

from __future__ import annotations

import numpy as np

from gyrolab.kernels.layout import (  # noqa: F401  (N_PARAMS: fixed_point.N_PARAMS for callers)
    CARRIES_ALPHA, CompiledTerms, GRADIENT, INERTIA, INV_INERTIA, LINEAR, N_PARAMS,
)


def pack(inertia: np.ndarray, terms: list[CompiledTerms], carries_alpha: bool) -> np.ndarray:
    p = np.zeros(N_PARAMS)
    p[INERTIA:INERTIA + 3] = inertia
    for term in terms:
        for axis, u in term.linear.items():
            p[LINEAR[axis]:LINEAR[axis] + 3] += u
        for axis, n in term.gradient.items():
            p[GRADIENT[axis]] += n
    p[CARRIES_ALPHA] = 1.0 if carries_alpha else 0.0
    p[INV_INERTIA:INV_INERTIA + 3] = 1.0 / inertia  # multiplications in the inner loop, not divisions
    return p


def built_in(inertia: np.ndarray, forces: list, carries_alpha: bool) -> np.ndarray | None:
    """The packed parameters (``pack``) when every force has ``compiled_terms()``, else None.

    Every kernel runs the system's traced equations; the Lie–Poisson splitting, the regimes and the chaos
    indicators' checks read these parameters."""
    terms = [force.compiled_terms() for force in forces]
    if any(term is None for term in terms):
        return None
    return pack(inertia, terms, carries_alpha)
