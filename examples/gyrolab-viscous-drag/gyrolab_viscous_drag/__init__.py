"""Linear viscous drag on the body: torque −c ω (a gyrolab force plugin)."""

from dataclasses import dataclass

from gyrolab.contracts import Force
from gyrolab.errors import as_number


@dataclass
class ViscousDragConfig:                  # the config's schema (force.viscous_drag): its keys and their types,
    _target_: str = "gyrolab_viscous_drag:ViscousDrag"   # checked by Hydra while composing (gyrolab.engine.schemas)
    coefficient: float = 0.1


class ViscousDrag(Force):
    name = "viscous_drag"
    schema = ViscousDragConfig
    required_axes = frozenset()           # reference axes the torque reads: none (2 would be the vertical γ)
    preserves_area_integral = False       # −c ω has a component along γ: Iω·γ decays, it is no invariant

    def __init__(self, body, *, coefficient=0.1):   # keyword defaults are the plugin's config
        self.coefficient = as_number(coefficient, "force.viscous_drag.coefficient", nonnegative=True)

    def torque(self, omega, axes):        # plain numpy on 3-vectors: gyrolab compiles it
        return -self.coefficient * omega

    def attributes(self):                 # stored in run.nc as force_viscous_drag_coefficient
        return {"coefficient": self.coefficient}
    # no potential(axes): drag is not conservative, so the energy is not monitored
