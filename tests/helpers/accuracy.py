"""Shared set-up of the accuracy tests: chaotic scenes, the scene where round-off dominates, the long-double
reference of a scene (``gyrolab.physics.reference``: a Taylor method in plain numpy on np.longdouble, independent of
the kernels), and auto's amplification measured as none."""

import numpy as np

from gyrolab import compose_scene
from gyrolab.kernels import layout
from gyrolab.physics.reference import fixed_point_reference

SLOW_SPIN = ["initial=slow_spin"]
CHAOTIC_TOP = ["initial.theta0=1", "initial.r0=2", "initial.p0=0.3", "initial.q0=-0.2"]
#: scene 184 of ``benchmarks/promise_audit.py --n 200 --seed 11``, where round-off dominates (its output times apart)
ROUND_OFF = ["body.a=0.7046", "body.b=1.4132",
             "body.com_direction=[-0.8673026531207482,-0.4887282266173314,-0.09450306025304023]",
             "force=[uniform_gravity]", "initial.theta0=2.67839", "initial.phi0=1.08408", "initial.psi0=2.71915",
             "initial.r0=0.171348", "initial.p0=-0.2898", "initial.q0=0.08809", "time.end=54.48"]


def long_double_states(scene, times, alpha: bool = False) -> np.ndarray:
    """The long-double reference's (ω, γ) of ``scene`` at ``times``, from the scene's own body, field and start
    (``alpha``: (ω, γ, α), of a scene whose state carries α)."""
    p = scene.system.compiled_model().built_in
    return fixed_point_reference(p[layout.INERTIA:layout.INERTIA + 3], p[layout.U_Z:layout.U_Z + 3], p[layout.N_Z],
                                 scene.system.initial_state()[:9 if alpha else 6], times).astype(float)


def long_double_final(overrides) -> np.ndarray:
    """The long-double reference's (ω, γ) at the end of the scene of ``overrides``."""
    scene = compose_scene(["integrator=taylor", "time.n_output=2", *overrides])
    return long_double_states(scene, scene.times[[0, -1]])[-1]


def no_growth(monkeypatch):
    """auto's amplification measured as none, by a tangent run first or by its Taylor run's one pass: its prediction
    then misses the chaos (as a measured growth that scatters low would make it miss)."""
    import gyrolab.accuracy.auto as auto_module
    from gyrolab.accuracy.amplification import Amplification

    monkeypatch.setattr(auto_module, "amplification",
                        lambda compiled, fun, y0, t0, t_pilot, t_end, method: Amplification(0.0, 0.0, t_end - t0,
                                                                                           "none (test)"))
    monkeypatch.setattr(auto_module, "growth_of", lambda own, span: Amplification(0.0, 0.0, span, "none (test)"))
