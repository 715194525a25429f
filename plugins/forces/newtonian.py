"""Newtonian attracting centre: the gravity-gradient torque N e × I e about a reference axis e.

The papers' Newtonian field (Ismail (2021) eq. 1, Shaker et al. eq. 7): a centre at distance R from the fixed point
along Z adds, to first order in ℓ/R, the torque N γ × Iγ with potential V = ½ N γ·Iγ. Give ``R`` (m) for an SI
body, which uses its g, or ``k = N/c²`` for a nondimensional body. A body on a circular orbit (``orbiting_gyrostat``)
says which axis points to the centre (``body.attracting_axis``) and N = 3Ω² (``body.gravity_gradient``): leave k and
R null there (k = N/Ω² = 3 on a Keplerian orbit; docs/gyrostat.md). ``N`` may be given directly (model units).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np

from gyrolab.physics.body import Body
from gyrolab.contracts.force import Axes, CompiledTerms, Force
from gyrolab.errors import ConfigError, as_number
from gyrolab.physics.vectors import cross, dot

log = logging.getLogger(__name__)


class Newtonian(Force):
    name = "newtonian"
    required_axes = frozenset({2})
    preserves_area_integral = True

    def __init__(self, body: Body, *, k: float | None = None, R: float | None = None, N: float | None = None) -> None:
        self.axis = int(getattr(body, "attracting_axis", 2))
        if self.axis != 2:
            self.required_axes = frozenset({self.axis})
            self.preserves_area_integral = False
        orbital_N = getattr(body, "gravity_gradient", None)  # 3Ω² for a body on a circular orbit
        self._nondim: dict[str, Any] = {}
        if N is not None:
            if k is not None or R is not None:
                raise ConfigError(f"force.newtonian needs one of k, R and N, got k={k}, R={R}, N={N}; "
                                  "set the others to null")
            self.N = as_number(N, "force.newtonian.N", nonnegative=True)
        elif orbital_N is not None:
            if R is not None:
                raise ConfigError(f"force.newtonian.R={R} does not apply to a body on a circular orbit, whose "
                                  f"gravity gradient is N = 3Ω² = {orbital_N:g}; set R to null")
            if k is None:
                self.N = float(orbital_N)
            else:  # k = N/Ω², the orbit's rate being the body's unit of rate; a Keplerian orbit has k = 3
                self.N = as_number(k, "force.newtonian.k", nonnegative=True) * orbital_N / 3.0
                self._nondim = {"c2": orbital_N / 3.0}
                if self.N != orbital_N:
                    log.warning("force.newtonian.k=%g gives N = %g Ω²; the circular orbit's gravity gradient is "
                                "3Ω² (k=3 or k=null)", k, k)
        else:
            self._init_fixed_point(body, k, R)
        self.inertia = body.inertia

    def _init_fixed_point(self, body: Body, k: float | None, R: float | None) -> None:
        if (k is None) == (R is None):
            raise ConfigError(f"force.newtonian needs exactly one of k = N/c² or R (m), got k={k}, R={R}")
        self._nondim = body.nondimensional()
        c2 = self._nondim.get("c2", 1.0)  # model units of a nondimensional body have c² = 1
        if k is not None:
            k = as_number(k, "force.newtonian.k", nonnegative=True)
            if body.units == "si" and not c2 > 0:
                raise ConfigError("force.newtonian.k = N/c² needs c² = Mgl/C > 0; give R (m) for a body without weight")
            self.N = k * c2
        else:
            R = as_number(R, "force.newtonian.R", positive=True)
            if body.units != "si" or not body.g:
                raise ConfigError(f"force.newtonian.R={R:g} needs an SI body with g > 0 (N = 3g/R); "
                                  "a nondimensional body takes k = N/c²")
            self.N = 3.0 * body.g / R

    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        e = axes[self.axis]
        return self.N * cross(e, self.inertia * e)

    def potential(self, axes: Axes) -> np.ndarray:
        e = axes[self.axis]
        return 0.5 * self.N * dot(e, self.inertia * e)

    def attributes(self) -> dict[str, Any]:
        attrs: dict[str, Any] = {"N": self.N}
        c2 = self._nondim.get("c2")
        if c2:
            attrs["k"] = self.N / c2
        if self.axis != 2:
            attrs["axis"] = self.axis
        return attrs

    def compiled_terms(self) -> CompiledTerms:
        return CompiledTerms(gradient={self.axis: self.N})
