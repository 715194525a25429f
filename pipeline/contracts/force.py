"""Contract of a force-field plugin: a torque on the body and, if conservative, its potential."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

#: Body components of the system's reference-frame axes, indexed 0, 1, 2.
#: For ``fixed_point`` the frame is the fixed space frame (X, Y, Z = vertical);
#: an entry is ``None`` when the scene does not carry that axis.
Axes = tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]


@dataclass
class CompiledTerms:
    """A torque written in the two forms compiled kernels evaluate (model units).

    ``linear[i]`` = u adds u × e_i; ``gradient[i]`` = N adds N e_i × I e_i, where e_i
    is the body-frame image of reference axis i. Uniform gravity, the Newtonian
    centre and a uniform magnetic field are all of this form.
    """

    linear: dict[int, np.ndarray] = field(default_factory=dict)
    gradient: dict[int, float] = field(default_factory=dict)


class Force(ABC):
    """A torque acting on a rigid body, composable with others in a list.

    Rules for implementers:

    1. ``__init__(self, body, **params)`` takes the system's body (in model
       units, see ``gyrolab.physics.body``) and the plugin's config parameters as
       keyword arguments with defaults; it validates them and raises
       ``gyrolab.errors.ConfigError`` (one sentence, naming the bad value) on
       bad input. The keyword defaults are the plugin's default config.
    2. ``required_axes`` names the reference-frame axes (0, 1, 2) whose body
       components ``torque`` and ``potential`` read. A system carries an axis
       only if some force (or the output) needs it, so ask for no more.
    3. ``torque(omega, axes)`` returns the torque in body axes, model units,
       for one state (vectors of shape (3,)). It is called in the integrator's
       inner loop: no allocation beyond the result, no Python-level loops.
    4. A conservative force overrides ``potential(axes)``, returning the
       potential energy for axes of shape (n, 3) (vectorised over a
       trajectory); a force that does not is non-conservative, and the system
       then stops monitoring the energy.
       The torque of a potential V(axes) is Σ_i e_i × ∂V/∂e_i.
    5. ``preserves_area_integral`` is true when the torque has no component
       along the reference Z axis for every state (a field symmetric about Z),
       so that the area integral Iω·γ is conserved.
    6. ``attributes()`` describes the parameters for the dataset, in both the
       SI and the nondimensional form where the body allows it (netCDF-safe
       values: str, numbers, lists of numbers).
    7. Optionally, ``compiled_terms()`` returns the torque as ``CompiledTerms``
       so that compiled integrators can run it; a force without that form
       runs with the Python integrators only.
    """

    name: ClassVar[str]
    required_axes: frozenset[int] = frozenset()
    preserves_area_integral: bool = True

    @abstractmethod
    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        """Torque (3,) in body axes for one state."""

    @property
    def conservative(self) -> bool:
        """True when the plugin defines a potential (it overrides ``potential``)."""
        return type(self).potential is not Force.potential

    def potential(self, axes: Axes) -> np.ndarray | None:
        """Potential energy along a trajectory, or None for a non-conservative force."""
        return None

    def attributes(self) -> dict[str, Any]:
        """Parameters for the dataset's attributes."""
        return {}

    def compiled_terms(self) -> CompiledTerms | None:
        """The torque in the compiled kernels' form, or None if it has none."""
        return None
