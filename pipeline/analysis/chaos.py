"""Chaos indicators of the heavy body about a fixed point: MEGNO, FLI, nutation deviation, Poincaré sections.

The indicators come from the variational equations integrated with the state in a compiled batch kernel
(``gyrolab.kernels.variational``: analytic Jacobian; fixed-step RK4 by blocks of trajectories, or adaptive
DOP853 one trajectory per thread; parallel over trajectories):

* MEGNO ⟨Y⟩ (Cincotta & Simó 2000, A&AS 147, 205): the time mean of Y(t) = (2/t) ∫₀ᵗ s δ̇·δ/δ·δ ds.
  Regular quasi-periodic motion → 2, a stable periodic orbit without shear → 0, chaos → grows like λt/2
  (λ the largest Lyapunov exponent).
* FLI (Froeschlé, Lega & Gonczi 1997, Celest. Mech. 67, 41): max over t of ln‖δ(t)‖, ‖δ(0)‖ = 1; grows
  linearly in t for chaos, logarithmically for regular motion.

The tangent vector starts tangent to the constraint manifold |γ| = 1 and stays so (the flow keeps γ·δγ).
Docs: docs/stability_map.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import VARIATIONAL
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels import fixed_point, layout, model, models, tangent, variational
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, RK4Numba, steps_per_interval

INDICATOR_NAME = "MEGNO"
INDICATOR_DEFINITION = ("MEGNO <Y>(t_end) (Cincotta & Simo 2000): time mean of Y(t) = (2/t) int_0^t s d'.d/d.d ds "
                        "along the tangent vector d of the variational equations; regular quasi-periodic -> 2, "
                        "stable periodic -> 0, chaotic -> grows like lambda t / 2")
FLI_DEFINITION = ("fast Lyapunov indicator (Froeschle, Lega & Gonczi 1997): max over t of ln|d(t)|, |d(0)| = 1, "
                  "d the tangent vector of the variational equations")


def _model_arrays(compiled: Any, y0s: np.ndarray, params: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The (trajectories, 6) initial states and (trajectories, n) parameters the variational kernel runs.

    A state that carries the fixed horizontal axis α (9 components) is accepted when no torque depends on α:
    (ω, γ) is then a closed system and α (the precession angle's axis) does not enter the indicators.
    """
    if compiled is None or compiled.built_in is None:
        raise ConfigError("chaos indicators need the fixed-point system with built-in torques only "
                          "(uniform_gravity, newtonian); a force plugin's torque has no variational equations here")
    y0s = np.ascontiguousarray(y0s, dtype=float)
    if y0s.ndim != 2 or y0s.shape[1] not in (6, 9):
        raise ConfigError(f"initial states have shape {y0s.shape}; chaos indicators need (trajectories, 6) or (trajectories, 9)")
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial states contain NaN or inf; every initial state must be finite")
    P = np.tile(compiled.built_in, (len(y0s), 1)) if params is None else np.ascontiguousarray(params, dtype=float)
    if P.shape != (len(y0s), fixed_point.N_PARAMS):
        raise ConfigError(f"params has shape {P.shape}; it must be ({len(y0s)}, {fixed_point.N_PARAMS})")
    if layout.torques_on_horizontal_axes(P):
        raise ConfigError("chaos indicators need torques about the vertical only (uniform gravity, Newtonian "
                          "attraction along Z); a torque on the fixed horizontal axes is not supported")
    P = P.copy()
    P[:, layout.CARRIES_ALPHA] = 0.0  # α is not carried into the kernels (nothing depends on it: checked above)
    gamma = np.linalg.norm(y0s[:, 3:6], axis=1)
    if np.any(np.abs(gamma - 1.0) > 1e-9):
        raise ConfigError(f"an initial γ has norm {gamma[np.argmax(np.abs(gamma - 1.0))]:.12g}; |γ| must be 1 within 1e-9")
    return np.ascontiguousarray(y0s[:, :6]), P


def variational_settings(integrator: Any) -> Any:
    """How the variational kernels run with ``integrator`` (its ``variational_settings()``); one ConfigError naming it,
    the capability and the registered integrators that have it when it does not declare VARIATIONAL."""
    supports = getattr(integrator, "supports", None)
    if supports is None or not supports(VARIATIONAL):
        name = getattr(integrator, "name", None) or integrator
        raise ConfigError(f"integrator {name!r} has no variational equations (capability {VARIATIONAL}), which the "
                          f"chaos indicators need; valid choices: {or_list(integrators_with(VARIATIONAL))}")
    return integrator.variational_settings()


def megno_run(compiled: Any, integrator: Any, times: np.ndarray, y0s: np.ndarray,
              params: np.ndarray | None = None, every_time: bool = True) -> dict[str, np.ndarray]:
    """MEGNO ⟨Y⟩ at every output time, FLI, max |θ − θ0| and the final state of each trajectory.

    ``integrator`` declares VARIATIONAL and says how (``variational_settings()``): fixed-step RK4 with the batch
    kernels' steps (``integrate_arrays``: the fewest equal steps no longer than its ``step`` in each output
    interval), by blocks of trajectories (rk4, rk4_numba); or adaptive DOP853 with its rtol, atol and max_step,
    steps landing on every output time, one trajectory per thread (dop853, dop853_numba; ``steps``: accepted
    steps per trajectory). Any other integrator is refused in one sentence listing those that have it. Returns arrays ``megno`` (trajectories, times; with
    ``every_time=False`` (trajectories, 1): ⟨Y⟩ at the last time only), ``fli``, ``max_nutation_deviation`` (trajectories,),
    ``final_state`` (trajectories, 6) and ``failed`` (trajectories,) True where the trajectory became
    non-finite (its values are then NaN).
    """
    times = np.ascontiguousarray(times, dtype=float)
    if times.ndim != 1 or times.size < 2 or not np.all(np.diff(times) > 0):
        raise ConfigError("times must be at least two increasing output times")
    settings = variational_settings(integrator)
    if compiled is not None and compiled.model == models.TRACED and (compiled.built_in is None or params is not None):
        # traced equations: their generated tangent flow (a fixed point carrying α with built-in torques alone takes
        # the hand-written (ω, γ) flow below, unless its rows are given in the traced layout)
        return _generated_run(compiled, settings, times, y0s, params, every_time)
    y0, P = _model_arrays(compiled, y0s, params)
    n = len(y0)
    megno = np.empty((n, times.size if every_time else 1))
    fli, deviation, final = np.empty(n), np.empty(n), np.empty((n, 6))
    tangent = variational.initial_tangent(y0)
    if settings.fixed_step:
        grid = steps_per_interval(times, float(settings.step))
        variational.run_indicators(P, times, grid, y0, tangent, megno, fli, deviation, final)
        steps = np.full(n, int(grid.sum()))
    else:
        steps = np.zeros(n, dtype=np.int64)
        variational.run_indicators_dop853(P, times, y0, tangent, float(settings.rtol), float(settings.atol),
                                          float(settings.max_step), megno, fli, deviation, final, steps)
    return {"megno": megno, "fli": fli, "max_nutation_deviation": deviation, "final_state": final,
            "failed": ~np.isfinite(megno[:, -1]), "steps": steps}


def _generated_run(compiled: Any, settings: Any, times: np.ndarray, y0s: np.ndarray, params: np.ndarray | None,
                   every_time: bool) -> dict[str, np.ndarray]:
    """``megno_run`` for a model compiled from its traced equations: its tangent flow generated from them
    (``kernels.tangent``), run by the compiled batch kernels (RK4 or DOP853 with the integrator's settings). FLI is
    max ln|δ| over the output times and ``FLI_SAMPLES`` more (the hand-written fixed-point kernels take it over every
    step); the nutation
    deviation is that of the state's last three components when they are a unit vector γ (θ = arccos γ3: the
    orbiting gyrostat's orbit normal), else NaN."""
    if model.traced_model(compiled).time_dependent:
        raise ConfigError("chaos indicators of a model compiled from its equations need autonomous equations; a "
                          "time-dependent force has none here")
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial states contain NaN or inf; every initial state must be finite")
    augmented = tangent.compiled_megno(compiled)
    P = tangent.megno_params(augmented, compiled.params if params is None else params)
    if len(P) == 1 and len(y0s) > 1:
        P = np.repeat(P, len(y0s), axis=0)
    # the requested times and FLI_SAMPLES more, where max ln|δ| and max |θ − θ0| are read (a map asks for 2 times)
    grid = np.union1d(times, np.linspace(times[0], times[-1], FLI_SAMPLES + 1))
    requested = np.searchsorted(grid, times)
    t = grid - times[0]
    t[0] = tangent.START
    method = (RK4Numba(step=float(settings.step)) if settings.fixed_step else
              DOP853Numba(rtol=float(settings.rtol), atol=float(settings.atol),
                          max_step=float(settings.max_step) if np.isfinite(settings.max_step) else None))
    run = method.integrate_batch(augmented, t, tangent.initial_augmented(y0s), P, "mark")
    n = y0s.shape[1]
    z = run.y
    megno = np.zeros((len(y0s), times.size))
    megno[:, 1:] = z[:, requested[1:], -1] / (times[1:] - times[0])
    gamma = z[:, :, n - 3:n]
    deviation = np.full(len(y0s), np.nan)
    if np.allclose(np.linalg.norm(y0s[:, n - 3:n], axis=1), 1.0, atol=1e-9):
        theta = np.arccos(np.clip(gamma[:, :, 2], -1.0, 1.0))
        deviation = np.max(np.abs(theta - theta[:, :1]), axis=1)
    failed = np.asarray(run.failed, dtype=bool) | ~np.isfinite(megno[:, -1])
    megno[failed] = np.nan
    steps = run.steps if run.steps is not None else np.full(len(y0s), run.n_steps)
    return {"megno": megno if every_time else megno[:, -1:], "fli": np.where(failed, np.nan, z[:, :, 2 * n].max(axis=1)),
            "max_nutation_deviation": np.where(failed, np.nan, deviation),
            "final_state": np.where(failed[:, None], np.nan, z[:, -1, :n]), "failed": failed, "steps": steps}


#: output times of a generated tangent flow's run (besides the requested ones) where FLI and the nutation deviation
#: are read: the hand-written kernels read them after every step
FLI_SAMPLES = 256


def indicator_outputs(compiled: Any, integrator: Any, times: np.ndarray, y0s: np.ndarray,
                      params: np.ndarray | None = None) -> dict[str, tuple[np.ndarray, dict[str, Any]]]:
    """Per-trajectory chaos indicators with their CF attributes (first axis = trajectory).

    ``integrator``: one that declares VARIATIONAL (fixed-step RK4 or adaptive DOP853), see ``megno_run``.
    ``indicator``: MEGNO ⟨Y⟩ at ``times[-1]``; ``fli``: the fast Lyapunov indicator; ``max_nutation_deviation``:
    max |θ − θ0| over the integration steps (rad, θ from γ3 = cos θ). A trajectory that becomes non-finite
    gets NaN in all three (the caller marks it failed).
    """
    run = megno_run(compiled, integrator, times, y0s, params, every_time=False)
    return {
        "indicator": (run["megno"][:, -1], {
            "units": "1", "long_name": "MEGNO chaos indicator <Y> at the end of the integration",
            "indicator_name": INDICATOR_NAME, "definition": INDICATOR_DEFINITION}),
        "fli": (run["fli"], {
            "units": "1", "long_name": "fast Lyapunov indicator max ln|d|", "definition": FLI_DEFINITION}),
        "max_nutation_deviation": (run["max_nutation_deviation"], {
            "units": "rad", "long_name": "maximum deviation of the nutation angle |theta - theta0|"}),
    }


def poincare_section(compiled: Any, y0: np.ndarray, t_end: float, step: float, level: float | None = None,
                     params: np.ndarray | None = None, max_points: int = 2000) -> dict[str, np.ndarray]:
    """Upward crossings of the section γ3 = level (default: the initial γ3) by one trajectory.

    On the section the energy, the area integral and |γ| = 1 leave a 2-D set; its coordinates here are the
    proper-rotation angle φ = atan2(γ1, γ2) (γ = (sin θ sin φ, sin θ cos φ, cos θ)) and the spin ω3.
    Crossings are found on the RK4 steps (step ``step``) and located by cubic Hermite interpolation.
    Returns ``t``, ``state`` (crossings, 6), ``phi`` (rad) and ``r`` (ω3).
    """
    y, P = _model_arrays(compiled, np.atleast_2d(y0), None if params is None else np.atleast_2d(params))
    if not (np.isfinite(t_end) and t_end > 0 and np.isfinite(step) and step > 0):
        raise ConfigError(f"a Poincaré section needs t_end > 0 and step > 0, not t_end={t_end}, step={step}")
    level = float(y[0, 5] if level is None else level)
    if not -1.0 < level < 1.0:
        raise ConfigError(f"section level γ3 = {level} must lie strictly between -1 and 1")
    out = np.empty((max_points, 7))
    found = variational.section_crossings(P[0], y[0], step, int(np.ceil(t_end / step)), level, out)
    out = out[:found]
    if not np.all(np.isfinite(out)):
        raise IntegrationError("the Poincaré-section trajectory became non-finite; reduce the step")
    state = out[:, 1:]
    return {"t": out[:, 0], "state": state, "phi": np.arctan2(state[:, 3], state[:, 4]), "r": state[:, 2]}


def section_dataset(compiled: Any, y0s: np.ndarray, theta0: np.ndarray, r0: np.ndarray, t_end: float, step: float,
                    params: np.ndarray | None = None, max_points: int = 2000, rate_units: str = "1") -> xr.Dataset:
    """Poincaré sections (γ3 = its initial value, upward) of a few chosen points, as dataset variables.

    ``theta0``/``r0`` label the points (their coordinates on the map). Variables ``section_phi`` and
    ``section_r`` (section_point, crossing; NaN past a point's last crossing), ``section_theta0``,
    ``section_r0`` and ``section_level`` (section_point); the stability-map figure draws them. ``rate_units``:
    the CF units of ω3 and r0 (the body's ``rate_unit``: "1" nondimensional, "rad s-1" SI).
    """
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    runs = [poincare_section(compiled, y0, t_end, step, None, None if params is None else np.atleast_2d(params)[j],
                             max_points) for j, y0 in enumerate(y0s)]
    width = max([1] + [len(run["t"]) for run in runs])
    phi = np.full((len(runs), width), np.nan)
    r = np.full((len(runs), width), np.nan)
    for j, run in enumerate(runs):
        phi[j, :len(run["t"])] = run["phi"]
        r[j, :len(run["t"])] = run["r"]
    dims = ("section_point", "crossing")
    return xr.Dataset({
        "section_phi": (dims, phi, {"units": "rad", "long_name": "proper-rotation angle phi at upward crossings of "
                                    "the section gamma3 = const (Poincare section)"}),
        "section_r": (dims, r, {"units": rate_units, "long_name": "spin omega3 at upward crossings of the section gamma3 = "
                                "const (Poincare section)"}),
        "section_theta0": ("section_point", np.asarray(theta0, dtype=float),
                           {"units": "rad", "long_name": "initial nutation angle of the section's trajectory"}),
        "section_r0": ("section_point", np.asarray(r0, dtype=float),
                       {"units": rate_units, "long_name": "initial spin r0 of the section's trajectory"}),
        "section_level": ("section_point", y0s[:, 5],
                          {"units": "1", "long_name": "section level gamma3 = cos(theta0)"}),
    }, attrs={"section_t_end": float(t_end), "section_step": float(step)})
