"""CF units of the quantities a run records as attributes or a sweep varies as a key (docs/datasets.md, "Conventions
common to every dataset").

``quantity_units(name, body_units)`` gives them from the quantity's name (an attribute name, or an override key
with dots as underscores) and the body's unit system: in the nondimensional form every model quantity is a pure
number (``"1"``) except angles (``rad``); a quantity gyrolab does not know is ``"1"`` for a nondimensional body
and has no units for an SI body (``None``): gyrolab does not guess a dimension.
"""

from __future__ import annotations

SI: dict[str, str | None] = {
    "1": "1", "rad": "rad", "time": "s", "rate": "rad s-1", "rate2": "s-2", "energy": "J", "torque": "N m",
    "momentum": "kg m2 s-1", "inertia": "kg m2", "mass": "kg", "length": "m", "acceleration": "m s-2", "wall": "s",
    # an absolute tolerance on the whole state, whose components have different SI units: no one unit
    "state": None}
#: nondimensional form: pure numbers, angles in radians, wall-clock seconds still seconds
NONDIMENSIONAL: dict[str, str | None] = {kind: ("rad" if kind == "rad" else "s" if kind == "wall" else "1")
                                         for kind in SI}

#: quantity name -> kind (keys of ``SI``)
KINDS = {
    # the body (body.* keys and the run's body_* attributes)
    "body_a": "1", "body_b": "1", "body_com_direction": "1", "body_nondim_a": "1", "body_nondim_b": "1",
    "body_nondim_com_direction": "1", "body_nondim_c2": "rate2", "body_time_scale_1_over_c": "time",
    "body_nonphysical": "1", "body_allow_nonphysical": "1", "body_inertia": "inertia", "body_mass": "mass",
    "body_com": "length", "body_g": "acceleration", "body_gyrostatic_momentum": "momentum",
    "body_orbit_rate": "rate", "body_gravity_gradient_N": "rate2",
    # the initial state
    "initial_omega": "rate", "initial_p0": "rate", "initial_q0": "rate", "initial_r0": "rate",
    "initial_gamma": "1", "initial_theta0": "rad", "initial_phi0": "rad", "initial_psi0": "rad",
    "initial_euler_angles": "rad", "initial_euler_rates": "rate",
    # forces gyrolab ships
    "force_uniform_gravity_weight_moment": "torque", "force_newtonian_N": "rate2", "force_newtonian_k": "1",
    "force_newtonian_axis": "1",
    # time and integrator settings
    "time_start": "time", "time_end": "time", "time_n_output": "1", "integrator_step": "time",
    "integrator_max_step": "time", "integrator_first_step": "time", "integrator_rtol": "1",
    "integrator_atol": "state", "integrator_order": "1", "integrator_tol": "1",
    # integrator statistics
    "integrator_nfev": "1", "integrator_n_steps": "1", "integrator_n_rejected": "1", "integrator_njev": "1",
    "integrator_nlu": "1", "integrator_wall_time": "wall",
    # sampling of the output and the model's scales
    "sampling_fastest_rate": "rate", "sampling_samples_per_period": "1", "state_size": "1",
    "time_scale_s": "time", "energy_scale_J": "energy", "git_dirty": "1",
}


def quantity_units(name: str, body_units: str | None) -> str | None:
    """CF units of quantity ``name`` (``body_a`` or ``body.a``) for a body in ``body_units`` (None: unknown)."""
    key = name.lstrip("+~").replace(".", "_")
    table = SI if body_units == "si" else NONDIMENSIONAL if body_units == "nondimensional" else None
    kind = KINDS.get(key)
    if kind is not None:
        if table is not None:
            return table[kind]
        return SI[kind] if SI[kind] == NONDIMENSIONAL[kind] else None   # known only if the same in either system
    return "1" if body_units == "nondimensional" else None
