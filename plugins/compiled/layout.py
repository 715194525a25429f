"""The fixed-point model's parameter array ``p``, named in one place (``fixed_point.pack`` writes it).

Every kernel and every caller reads ``p`` by these names, never by bare numbers. numba freezes module-level
integers as compile-time constants, so ``p[U_Z + 1]`` compiles to the same machine code as ``p[10]``.

    p[INERTIA + k]      I_k, the principal moments (k = 0, 1, 2)
    p[U_X : U_X + 3]    U_0: the torque U_0 × α (a linear torque on the fixed horizontal axis X)
    p[U_Y : U_Y + 3]    U_1: the torque U_1 × β (β = γ × α, the fixed horizontal axis Y)
    p[U_Z : U_Z + 3]    U_2: the torque U_2 × γ (uniform gravity: U = M g r_c)
    p[N_X], p[N_Y], p[N_Z]   N_i: the torque N_i e_i × I e_i (a Newtonian centre along Z: N_Z)
    p[CARRIES_ALPHA]    1.0 when the state carries α (9 components), else 0.0 (state (ω, γ))
    p[INV_INERTIA + k]  1/I_k (the inner loops multiply instead of dividing)

A model with a traced plugin torque appends, after these N_PARAMS entries, the torque kernel's address
(``ADDRESS``) and its constants (from ``FIRST_CONSTANT``); the Taylor entries end the array, the Taylor
kernel's address at ``p[p.size - 2]`` and its node count at ``p[p.size - 1]`` (``plugin_taylor``).
"""

from __future__ import annotations

import numpy as np

INERTIA = 0
U_X, U_Y, U_Z = 3, 6, 9
#: the start of U_i for reference axis i (0 = α, 1 = β, 2 = γ)
LINEAR = (U_X, U_Y, U_Z)
N_X, N_Y, N_Z = 12, 13, 14
#: N_i for reference axis i
GRADIENT = (N_X, N_Y, N_Z)
CARRIES_ALPHA = 15
INV_INERTIA = 16
N_PARAMS = 19
#: a model with a traced plugin torque (``plugin_torque``): the compiled torque's address right after the packed
#: forms, then its constants
ADDRESS = N_PARAMS
FIRST_CONSTANT = N_PARAMS + 1

#: state components: ω at OMEGA, γ at GAMMA, α at ALPHA (each 3)
OMEGA, GAMMA, ALPHA = 0, 3, 6


def torques_on_horizontal_axes(P: np.ndarray) -> bool:
    """True when some row of ``P`` has a torque on a fixed horizontal axis (U_X, U_Y, N_X or N_Y non-zero):
    such a torque needs α, and the (ω, γ)-only analyses (periodic orbits, chaos indicators) refuse it."""
    P = np.asarray(P)
    return bool(np.any(P[..., U_X:U_Z] != 0.0) or np.any(P[..., N_X:N_Z] != 0.0))
