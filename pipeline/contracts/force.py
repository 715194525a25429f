"""Contract of a force-field plugin: a torque on the body and, if conservative, its potential."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np

from gyrolab.errors import ConfigError
from gyrolab.kernels.layout import CompiledTerms

#: Body components of the system's reference-frame axes, indexed 0, 1, 2.
#: For ``fixed_point`` the frame is the fixed space frame (X, Y, Z = vertical);
#: an entry is ``None`` when the scene does not carry that axis.
Axes = tuple[np.ndarray | None, np.ndarray | None, np.ndarray | None]


class Force(ABC):
    """A torque acting on a rigid body, composable with others in a list.

    Rules for implementers (``gyrolab.testing.check_force`` checks them; run it in your tests):

    1. ``__init__(self, body, *, coefficient=0.1, ...)`` takes the system's
       body (in model units, see ``gyrolab.physics.body``) and the plugin's
       config parameters, each declared as a keyword with a default (the
       defaults are the plugin's default config; ``**params`` is refused, as it
       would accept any key and advertise none); it validates them and raises
       ``gyrolab.errors.ConfigError`` (one sentence, naming the bad value) on
       bad input (what gyrolab makes of other exceptions: docs/plugins.md,
       "What the engine checks").
       Read what the torque needs from ``body`` in ``__init__`` and keep it as
       plain floats or arrays (docs/plugins.md, "What body offers a force").
    2. ``required_axes`` names the reference-frame axes (0, 1, 2) whose body
       components ``torque`` and ``potential`` read. A system carries an axis
       only if some force (or the output) needs it, so ask for no more; an axis
       not declared is passed as ``None``.
    3. ``torque(omega, axes)`` returns the torque in body axes, model units,
       for one state (vectors of shape (3,)). Written as numpy arithmetic on the
       vectors it is traced once into compiled code; one that branches on the
       state or converts it to a float runs with the Python integrators only
       (docs/plugins.md, "How a plain-Python torque runs compiled").
    4. ``time_dependent = True`` declares a torque that also depends on time:
       it is then called as ``torque(omega, axes, t)``. Such a force has no
       conserved energy (its ``potential`` is not used).
    5. A conservative force overrides ``potential(axes)``, returning the
       potential energy for axes of shape (n, 3) (vectorised over a
       trajectory); a force that does not is non-conservative, and the system
       then stops monitoring the energy.
       The torque of a potential V(axes) is Σ_i e_i × ∂V/∂e_i.
    6. ``preserves_area_integral`` has no default: every force declares it (a
       class attribute, or set in ``__init__`` when it depends on the
       parameters). It is true exactly when the torque has no component along
       the reference Z axis (axis 2, γ) for every state — a field symmetric
       about Z — so that the area integral Iω·γ is conserved (d(Iω·γ)/dt =
       torque·γ) and monitored as an invariant. Drag, or a field along X, is
       False. A force without the declaration is refused (ConfigError).
    7. ``attributes()`` describes the parameters for the dataset, in both the
       SI and the nondimensional form where the body allows it (netCDF-safe
       values: str, int, float, lists of numbers; names of letters, digits, _).
    8. Optionally, ``compiled_terms()`` returns the torque as ``CompiledTerms``,
       the built-in forms every compiled integrator evaluates (which ones take a
       traced torque instead: docs/plugins.md, "Which integrators take a compiled
       plugin torque").

    gyrolab checks a third-party force's claims (rules 5, 6) when the scene is
    built and its torque (rule 3) during a run, each failure one sentence naming
    the force (docs/plugins.md, "What the engine checks").
    """

    name: ClassVar[str]
    required_axes: frozenset[int] = frozenset()
    time_dependent: ClassVar[bool] = False
    preserves_area_integral: bool  # no default: declare it (rule 6)

    @abstractmethod
    def torque(self, omega: np.ndarray, axes: Axes) -> np.ndarray:
        """Torque (3,) in body axes for one state (``torque(omega, axes, t)`` when ``time_dependent``)."""

    @property
    def conservative(self) -> bool:
        """True when the plugin defines a potential (it overrides ``potential``) of a time-independent torque."""
        return type(self).potential is not Force.potential and not self.time_dependent

    def potential(self, axes: Axes) -> np.ndarray | None:
        """Potential energy along a trajectory, or None for a non-conservative force."""
        return None

    def attributes(self) -> dict[str, Any]:
        """Parameters for the dataset's attributes."""
        return {}

    def compiled_terms(self) -> CompiledTerms | None:
        """The torque in the compiled kernels' built-in form, or None (the torque is then traced, rule 3)."""
        return None


def check_declared(force: Force, where: str) -> None:
    """ConfigError unless the force declares ``preserves_area_integral`` as a bool (rule 6)."""
    flag = getattr(force, "preserves_area_integral", None)
    if not isinstance(flag, (bool, np.bool_)):
        raise ConfigError(f"{where} ({type(force).__name__}) must declare preserves_area_integral = True or False: "
                          "True only when its torque has no component along the vertical Z (γ) for every state; "
                          "see gyrolab.contracts.Force")
