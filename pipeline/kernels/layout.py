"""The compiled models' parameter arrays ``p``, named in one place (``fixed_point.pack``, ``model.compile`` write them).

Every kernel and every caller reads ``p`` by these names, never by bare numbers. numba freezes module-level
integers as compile-time constants, so ``p[U_Z + 1]`` compiles to the same machine code as ``p[10]``.

    p[INERTIA + k]      I_k, the principal moments (k = 0, 1, 2)
    p[U_X : U_X + 3]    U_0: the torque U_0 × α (a linear torque on the fixed horizontal axis X)
    p[U_Y : U_Y + 3]    U_1: the torque U_1 × β (β = γ × α, the fixed horizontal axis Y)
    p[U_Z : U_Z + 3]    U_2: the torque U_2 × γ (uniform gravity: U = M g r_c)
    p[N_X], p[N_Y], p[N_Z]   N_i: the torque N_i e_i × I e_i (a Newtonian centre along Z: N_Z)
    p[CARRIES_ALPHA]    1.0 when the state carries α (9 components), else 0.0 (state (ω, γ))
    p[INV_INERTIA + k]  1/I_k (the inner loops multiply instead of dividing)

A model compiled from its traced equations (``model``) has a layout of its own:

    p[TRACED_ADDRESS]                the right-hand side kernel's address
    p[TRACED_FIRST_CONSTANT:-TRACED_TAIL]   the equations' numbers, in the order the trace met them
    p[-4], p[-3]     the Taylor kernel's address and work columns (``taylor_series``; 0 until compiled)
    p[-2], p[-1]     the double-double Taylor kernel's address and scratch columns (``series_dd``; 0 until compiled)
"""

from __future__ import annotations

from dataclasses import dataclass, field

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
#: a traced model's parameter array (``model``): the right-hand side kernel's address, then the equations' numbers
TRACED_ADDRESS = 0
TRACED_FIRST_CONSTANT = 1
TRACED_TAIL = 4

#: state components: ω at OMEGA, γ at GAMMA, α at ALPHA (each 3)
OMEGA, GAMMA, ALPHA = 0, 3, 6


def torques_on_horizontal_axes(P: np.ndarray) -> bool:
    """True when some row of ``P`` has a torque on a fixed horizontal axis (U_X, U_Y, N_X or N_Y non-zero):
    such a torque needs α, and the (ω, γ)-only analyses (periodic orbits, chaos indicators) refuse it."""
    P = np.asarray(P)
    return bool(np.any(P[..., U_X:U_Z] != 0.0) or np.any(P[..., N_X:N_Z] != 0.0))


@dataclass
class CompiledTerms:
    """A torque written in the two built-in forms the packed parameters hold (model units).

    ``linear[i]`` = u adds u × e_i; ``gradient[i]`` = N adds N e_i × I e_i, where e_i
    is the body-frame image of reference axis i. Uniform gravity, the Newtonian
    centre and a uniform magnetic field are all of this form (``fixed_point.pack`` packs them).
    """

    linear: dict[int, np.ndarray] = field(default_factory=dict)
    gradient: dict[int, float] = field(default_factory=dict)
