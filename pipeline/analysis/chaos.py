"""Chaos indicators of a compiled model: MEGNO, FLI, nutation deviation, Poincaré sections.

The indicators come from the model's tangent flow, generated from its traced equations (``gyrolab.kernels.tangent``:
x' = f, u' = J u − (u·J u) u, ℓ' = u·J u with ℓ = ln|δ|, and the MEGNO quadratures), run by the ordinary compiled
batch integrators (RK4 by blocks of trajectories, DOP853 by lanes; parallel over trajectories):

* MEGNO ⟨Y⟩ (Cincotta & Simó 2000, A&AS 147, 205): the time mean of Y(t) = (2/t) ∫₀ᵗ s δ̇·δ/δ·δ ds.
  Regular quasi-periodic motion → 2, a stable periodic orbit without shear → 0, chaos → grows like λt/2
  (λ the largest Lyapunov exponent).
* FLI (Froeschlé, Lega & Gonczi 1997, Celest. Mech. 67, 41): max over t of ln‖δ(t)‖, ‖δ(0)‖ = 1; grows
  linearly in t for chaos, logarithmically for regular motion.

On the fixed point the tangent vector starts tangent to the constraint manifold |γ| = 1 and stays so (the flow keeps
γ·δγ); a state carrying α that no torque reads is followed in (ω, γ) alone (``tangent.flow_size``).
Docs: docs/stability_map.md.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts.capabilities import integrators_with, or_list
from gyrolab.contracts.integrator import VARIATIONAL
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels import layout, model, models, tangent
from gyrolab.plugins.integrators.compiled_solvers import DOP853Numba, RK4Numba
from gyrolab.plugins.integrators.refinement import steps_per_interval

INDICATOR_NAME = "MEGNO"
INDICATOR_DEFINITION = ("MEGNO <Y>(t_end) (Cincotta & Simo 2000): time mean of Y(t) = (2/t) int_0^t s d'.d/d.d ds "
                        "along the tangent vector d of the variational equations; regular quasi-periodic -> 2, "
                        "stable periodic -> 0, chaotic -> grows like lambda t / 2")
FLI_DEFINITION = ("fast Lyapunov indicator (Froeschle, Lega & Gonczi 1997): max over t of ln|d(t)|, |d(0)| = 1, "
                  "d the tangent vector of the variational equations")
#: an adaptive run reads max ln|δ| and max |θ − θ0| at the requested times and this many more, evenly spread (its
#: dense output: no extra step); a fixed-step run reads them after every step
FLI_SAMPLES = 256
#: bytes of samples one call of a batch kernel may hold (trajectories × samples × (2n + 3) doubles, ``batch.memory``'s
#: default): a fixed-step run goes on from its last sample in windows of time (the same steps: bit for bit the
#: result of one call), an adaptive run takes the trajectories in groups (each its own steps: independent)
MEMORY = 64 * 2**20


def _initial_states(compiled: Any, y0s: np.ndarray, params: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The initial states the tangent flow runs (``tangent.flow_size`` leading components) and its parameter rows,
    checked: one ConfigError per bad input. A fixed point (``compiled.built_in``) also needs torques about the
    vertical only and |γ| = 1."""
    try:
        traced = model.traced_model(compiled)
    except (ValueError, AttributeError):  # no compiled model
        raise ConfigError("chaos indicators need a system compiled from its equations (its compiled_model()); this "
                          "system has none") from None
    if traced.time_dependent:
        raise ConfigError("chaos indicators of a model compiled from its equations need autonomous equations; a "
                          "time-dependent force has none here")
    y0s = np.atleast_2d(np.asarray(y0s, dtype=float))
    size = model.state_size(compiled)
    if y0s.ndim != 2 or y0s.shape[1] != size:
        raise ConfigError(f"initial states have shape {y0s.shape}; chaos indicators need (trajectories, {size})")
    if not np.all(np.isfinite(y0s)):
        raise ConfigError("initial states contain NaN or inf; every initial state must be finite")
    rows = compiled.params if params is None else np.asarray(params, dtype=float)
    if rows.shape[-1] != compiled.params.size or (rows.ndim == 2 and len(rows) not in (1, len(y0s))):
        raise ConfigError(f"params has shape {rows.shape}; it must be ({len(y0s)}, {compiled.params.size})")
    if compiled.built_in is not None:
        if layout.torques_on_horizontal_axes(compiled.built_in):
            raise ConfigError("chaos indicators need torques about the vertical only (uniform gravity, Newtonian "
                              "attraction along Z); a torque on the fixed horizontal axes is not supported")
        gamma = np.linalg.norm(y0s[:, layout.GAMMA:layout.GAMMA + 3], axis=1)
        if np.any(np.abs(gamma - 1.0) > 1e-9):
            raise ConfigError(f"an initial γ has norm {gamma[np.argmax(np.abs(gamma - 1.0))]:.12g}; |γ| must be 1 "
                              "within 1e-9")
    return np.ascontiguousarray(y0s[:, :tangent.flow_size(compiled)]), rows


def variational_settings(integrator: Any) -> Any:
    """How the tangent flow runs with ``integrator`` (its ``variational_settings()``); one ConfigError naming it,
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

    The model's generated tangent flow runs with the batch kernels of the method ``integrator`` declares
    (VARIATIONAL, ``variational_settings()``): fixed-step RK4 with the fewest equal steps no longer than its ``step``
    in each output interval (rk4, rk4_numba), FLI and the nutation deviation read after every step; or adaptive
    DOP853 with its rtol, atol and max_step (dop853, dop853_numba; ``steps``: accepted steps per trajectory), FLI and
    the deviation read at the output times and ``FLI_SAMPLES`` more. Any other integrator is refused in one sentence
    listing those that have it. ``params``: parameter rows of ``compiled``'s layout (a batch's), else its own.
    Returns arrays ``megno`` (trajectories, times; with ``every_time=False`` (trajectories, 1): ⟨Y⟩ at the last
    time only), ``fli``, ``max_nutation_deviation`` (trajectories,; θ = arccos of the state's third component of γ,
    the last three of the followed state: the fixed point's γ, the orbiting gyrostat's orbit normal; NaN when those
    are no unit vector), ``final_state`` (trajectories, followed state) and ``failed`` (trajectories,) True where the
    trajectory became non-finite (its values are then NaN).
    """
    times = np.ascontiguousarray(times, dtype=float)
    if times.ndim != 1 or times.size < 2 or not np.all(np.diff(times) > 0):
        raise ConfigError("times must be at least two increasing output times")
    settings = variational_settings(integrator)
    y0s, rows = _initial_states(compiled, y0s, params)
    augmented = tangent.compiled_megno(compiled)
    P = tangent.megno_params(augmented, rows)
    if len(P) == 1 and len(y0s) > 1:
        P = np.repeat(P, len(y0s), axis=0)
    n = y0s.shape[1]
    sphere = slice(n - 3, n)
    on_sphere = np.allclose(np.linalg.norm(y0s[:, sphere], axis=1), 1.0, atol=1e-9)
    z0 = tangent.initial_augmented(y0s, tangent.direction(y0s, sphere if on_sphere else None))
    width = z0.shape[1]
    if settings.fixed_step:  # every step an output: the grid of the steps, in windows of time
        steps = steps_per_interval(times, float(settings.step))
        grid = np.concatenate([times[:1]] + [np.linspace(a, b, k + 1)[1:] for a, b, k in
                                             zip(times[:-1], times[1:], steps)])
        method = RK4Numba(step=float(settings.step))
        window = max(64, MEMORY // (len(y0s) * width * 8))
        parts = [(slice(None), first, min(first + window, grid.size - 1)) for first in range(0, grid.size - 1, window)]
    else:
        grid = np.union1d(times, np.linspace(times[0], times[-1], FLI_SAMPLES + 1))
        method = DOP853Numba(rtol=float(settings.rtol), atol=float(settings.atol),
                             max_step=float(settings.max_step) if np.isfinite(settings.max_step) else None)
        group = max(256, MEMORY // (grid.size * width * 8))
        parts = [(slice(r, r + group), 0, grid.size - 1) for r in range(0, len(y0s), group)]
    requested = np.searchsorted(grid, times)
    b = np.zeros((len(y0s), times.size))  # the quadrature b at the requested times
    fli, low, high = np.zeros(len(y0s)), z0[:, n - 1].copy(), z0[:, n - 1].copy()  # max ℓ; min, max of γ3
    failed = np.zeros(len(y0s), dtype=bool)
    taken = np.zeros(len(y0s), dtype=np.int64)
    last = z0.copy()
    for which, first, stop in parts:
        t = grid[first:stop + 1] - times[0]
        if first == 0:
            t[0] = tangent.START
        run = method.integrate_batch(augmented, t, np.ascontiguousarray(last[which]), np.ascontiguousarray(P[which]),
                                     "mark")
        z = run.y
        last[which] = z[:, -1]
        failed[which] |= np.asarray(run.failed, dtype=bool)
        taken[which] += run.steps if run.steps is not None else run.n_steps
        fli[which] = np.maximum(fli[which], z[:, :, 2 * n].max(axis=1))
        low[which] = np.minimum(low[which], z[:, :, n - 1].min(axis=1))
        high[which] = np.maximum(high[which], z[:, :, n - 1].max(axis=1))
        inside = np.flatnonzero((requested >= first) & (requested <= stop))
        b[which, inside] = z[:, requested[inside] - first, 2 * n + 2]
    megno = np.zeros((len(y0s), times.size))
    megno[:, 1:] = b[:, 1:] / (times[1:] - times[0])
    failed |= ~np.isfinite(megno[:, -1])
    theta0 = np.arccos(np.clip(y0s[:, n - 1], -1.0, 1.0))  # θ = arccos γ3 falls as γ3 rises
    deviation = np.maximum(np.arccos(np.clip(low, -1.0, 1.0)) - theta0, theta0 - np.arccos(np.clip(high, -1.0, 1.0)))
    megno[failed] = np.nan
    return {"megno": megno if every_time else megno[:, -1:], "fli": np.where(failed, np.nan, fli),
            "max_nutation_deviation": np.where(failed | (not on_sphere), np.nan, deviation),
            "final_state": np.where(failed[:, None], np.nan, last[:, :n]), "failed": failed, "steps": taken}


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
    """Upward crossings of the section γ3 = level (default: the initial γ3) by one trajectory of the fixed point.

    On the section the energy, the area integral and |γ| = 1 leave a 2-D set; its coordinates here are the
    proper-rotation angle φ = atan2(γ1, γ2) (γ = (sin θ sin φ, sin θ cos φ, cos θ)) and the spin ω3.
    The model's compiled RK4 (``rk4_numba``, its generated right-hand side) takes steps ``step`` with an output after
    each; a crossing is located on its step by the cubic Hermite interpolant of the step (values and right-hand
    sides at both ends: error O(h⁴), the order of RK4), refined by bisection on it. ``params``: a parameter row of
    ``compiled``'s layout. Returns ``t``, ``state`` (crossings, 6), ``phi`` (rad) and ``r`` (ω3).
    """
    y0s, row = _initial_states(compiled, y0, params)
    if not (np.isfinite(t_end) and t_end > 0 and np.isfinite(step) and step > 0):
        raise ConfigError(f"a Poincaré section needs t_end > 0 and step > 0, not t_end={t_end}, step={step}")
    k = layout.GAMMA + 2
    level = float(y0s[0, k] if level is None else level)
    if not -1.0 < level < 1.0:
        raise ConfigError(f"section level γ3 = {level} must lie strictly between -1 and 1")
    p = np.ascontiguousarray(np.atleast_2d(row)[0])
    run_model = model.CompiledModel(p)
    y0 = np.asarray(y0, dtype=float).ravel()
    times = np.arange(int(np.ceil(t_end / step)) + 1) * step
    try:
        y = RK4Numba(step=step).integrate(None, times, y0, None, run_model).y
    except IntegrationError:
        raise IntegrationError("the Poincaré-section trajectory became non-finite; reduce the step") from None
    at = np.flatnonzero((y[:-1, k] < level) & (level <= y[1:, k]))[:max_points]
    f = np.empty((2, at.size, y.shape[1]))
    for side in (0, 1):
        for j, i in enumerate(at + side):
            models.evaluate(float(times[i]), y[i], p, f[side, j])
    lo, hi = np.zeros(at.size), np.ones(at.size)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        below = _hermite(y[at, k], y[at + 1, k], f[0, :, k], f[1, :, k], step, mid) < level
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    u = (0.5 * (lo + hi))[:, None]
    state = _hermite(y[at, :6], y[at + 1, :6], f[0, :, :6], f[1, :, :6], step, u)
    return {"t": times[at] + u[:, 0] * step, "state": state, "phi": np.arctan2(state[:, 3], state[:, 4]),
            "r": state[:, 2]}


def _hermite(y0: Any, y1: Any, f0: Any, f1: Any, h: float, u: Any) -> Any:
    """The cubic Hermite interpolant on a step of length h at fraction u."""
    u2 = u * u
    u3 = u2 * u
    return ((2 * u3 - 3 * u2 + 1) * y0 + (u3 - 2 * u2 + u) * h * f0 + (-2 * u3 + 3 * u2) * y1
            + (u3 - u2) * h * f1)


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
    phi, r = np.full((2, len(runs), width), np.nan)  # NaN past a point's last crossing
    for j, run in enumerate(runs):
        phi[j, :len(run["t"])], r[j, :len(run["t"])] = run["phi"], run["r"]
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
