"""Contract checks for plugin authors, one kit per plugin kind, to call in your own tests.

Like scikit-learn's ``check_estimator``: each kit builds the plugin and checks its contract's rules
one by one, raising ``AssertionError`` that names the first violation.

* ``check_force(ForceClass, **params)`` (below), ``gyrolab.contracts.Force``;
* ``check_integrator(IntegratorClass, **params)``, ``gyrolab.contracts.Integrator``;
* ``check_system(SystemClass, body, initial, **params)``, ``gyrolab.contracts.System``;
* ``check_regime(RegimeClass, scene=OVERRIDES, **params)``, ``gyrolab.contracts.Regime``.

``check_force`` builds the force on a triaxial test body and checks:

1. the force builds with ``params``, declares ``preserves_area_integral`` (a bool) and
   ``required_axes`` within {0, 1, 2};
2. ``torque`` returns a finite float array of shape (3,) at random states, reading only the
   declared axes (the others are passed as None);
3. ``preserves_area_integral`` is right: True exactly when torque·γ = 0 at every random state
   (d(Iω·γ)/dt = torque·γ);
4. a ``potential`` belongs to the torque: torque = Σ e_i × ∂V/∂e_i, the derivative of V under
   small rotations of the body (central differences), and V is vectorised over (n, 3) axes;
5. ``attributes()`` are netCDF-safe (names of letters, digits and _; values str, int, float or
   non-empty lists of numbers, all finite);
6. every keyword parameter given a nonsense value ("abc") raises gyrolab's one-sentence
   ``ConfigError`` naming the parameter when gyrolab builds the force (parameters whose default
   is None only when ``params`` gives them);
7. the compiled torque (traced from ``torque``, see ``gyrolab.kernels.expression``)
   equals the Python torque; a torque that cannot be traced is reported as a warning, not a
   failure (it then runs with the Python integrators only).
"""

from __future__ import annotations

import ctypes
import inspect
import math
import re
import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from gyrolab.contracts.claims import POTENTIAL_RTOL, random_states, rotation_torque
from gyrolab.contracts.claims import axes_of as _axes
from gyrolab.contracts.force import Force
from gyrolab.contracts.integrator import COMPILED_MODEL, Integrator, IntegratorStats, Solution
from gyrolab.contracts.integrator_rules import unchecked
from gyrolab.contracts.regime import Regime
from gyrolab.contracts.system import System
from gyrolab.engine.scene import build_force, compose_scene
from gyrolab.errors import ConfigError, IntegrationError
from gyrolab.kernels import expression, model, models
from gyrolab.physics.body import Body
from gyrolab.physics.vectors import cross
from gyrolab.plugins.integrators.compiled_solvers import Taylor
from gyrolab.plugins.systems.fixed_point import FixedPoint

__all__ = ["check_force", "check_integrator", "check_regime", "check_system", "random_states", "rotation_torque"]

#: torque·γ below this fraction of |torque| counts as "no component along the vertical" (tighter than the scene's)
AREA_RTOL = 1e-12
_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def _call(force: Force, omega: np.ndarray, frame: np.ndarray, t: float) -> Any:
    axes = _axes(force, frame)
    return force.torque(omega, axes, t) if force.time_dependent else force.torque(omega, axes)


def _fail(cls: type, message: str) -> AssertionError:
    return AssertionError(f"{cls.__name__}: {message}")


def _check_class(cls: type, contract: type, key: str) -> None:
    """``cls`` subclasses ``contract`` and its ``name`` is a config key (``key`` says where the config names it)."""
    if not (isinstance(cls, type) and issubclass(cls, contract)):
        raise AssertionError(f"{cls!r} is not a subclass of gyrolab.contracts.{contract.__name__}")
    name = getattr(cls, "name", None)
    if not isinstance(name, str) or not _NAME.match(name):
        raise _fail(cls, f"name={name!r} must be a string of letters, digits and _ ({key})")


def _as_config(params: dict[str, Any]) -> dict[str, Any]:
    """The kit's keyword parameters as a config gives them (arrays as lists)."""
    return {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in params.items()}


def check_force(cls: type, body: Any = None, *, n_states: int = 20, **params: Any) -> None:
    """Check a force plugin class against the Force contract; AssertionError names the first violation.

    Parameters
    ----------
    cls : type
        The force plugin class (a subclass of ``gyrolab.contracts.Force``).
    body : optional
        The body the force is built on; by default a triaxial nondimensional body with an off-axis
        centre of mass.
    n_states : int
        How many random states the torque is checked on.
    **params
        The plugin's keyword parameters for the checks (its defaults when omitted).
    """
    _check_class(cls, Force, "the config key force.NAME")
    if body is None:  # triaxial, with an off-axis centre of mass
        body = Body.from_config({"units": "nondimensional", "a": 0.7, "b": 0.9,
                                 "com_direction": [0.3, 0.4, 0.866025403784]})
    where = f"force.{cls.name}"
    params = _as_config(params)
    force = _build_plugin(lambda **kw: build_force(cls, kw, where, body), cls, params)
    axes = force.required_axes
    if not isinstance(axes, (set, frozenset)) or not set(axes) <= {0, 1, 2}:
        raise _fail(cls, f"required_axes={axes!r} must be a frozenset of axis indices 0, 1, 2")
    omegas, frames = random_states(n_states)
    torques = _check_torque(cls, force, omegas, frames)
    _check_area_flag(cls, force, torques, frames)
    if force.conservative:
        _check_potential(cls, force, frames)
    _check_mapping(cls, force.attributes(), "attributes()")
    _check_bad_parameters(cls, params, "", lambda **kw: build_force(cls, kw, where, body))
    _check_compiled(cls, force, body, omegas, frames)


def _check_torque(cls: type, force: Force, omegas: np.ndarray, frames: np.ndarray) -> np.ndarray:
    torques = np.empty_like(omegas)
    for k, (omega, frame) in enumerate(zip(omegas, frames)):
        try:
            value = _call(force, omega.copy(), frame, 0.7 * k)
        except TypeError as exc:
            if "NoneType" in str(exc):
                raise _fail(cls, f"torque reads a reference axis not in required_axes={set(force.required_axes)} "
                                 f"({exc}); declare every axis it reads") from None
            raise
        value = np.asarray(value)
        if value.shape != (3,) or not np.issubdtype(value.dtype, np.floating):
            raise _fail(cls, f"torque returned shape {value.shape} and dtype {value.dtype}; it must be a float "
                             "array of shape (3,) (body components)")
        if not np.all(np.isfinite(value)):
            raise _fail(cls, f"torque is not finite at ω={omega.tolist()}: {value.tolist()}")
        torques[k] = value
    return torques


def _check_area_flag(cls: type, force: Force, torques: np.ndarray, frames: np.ndarray) -> None:
    along = np.abs(np.einsum("ij,ij->i", torques, frames[:, 2, :]))
    scale = np.maximum(np.linalg.norm(torques, axis=1), 1e-300)
    worst = int(np.argmax(along / scale))
    preserved = bool(np.all(along <= AREA_RTOL * scale))
    if force.preserves_area_integral and not preserved:
        raise _fail(cls, f"preserves_area_integral is True, but the torque has a component {along[worst]:.3g} along "
                         f"the vertical γ (|torque| = {scale[worst]:.3g}), so the area integral Iω·γ is not "
                         "conserved; declare False")
    if not force.preserves_area_integral and preserved and np.any(np.linalg.norm(torques, axis=1) > 0):
        raise _fail(cls, "preserves_area_integral is False, but torque·γ = 0 at every random state, so the area "
                         "integral Iω·γ is conserved; declare True (or check with parameters that break the symmetry)")


def _check_potential(cls: type, force: Force, frames: np.ndarray) -> None:
    values = np.asarray(force.potential(_axes(force, frames)), dtype=float)
    if values.shape != (len(frames),) or not np.all(np.isfinite(values)):
        raise _fail(cls, f"potential for axes of shape ({len(frames)}, 3) returned shape {values.shape}"
                         f"{'' if np.all(np.isfinite(values)) else ' with non-finite values'}; it must be "
                         "vectorised over a trajectory, one finite energy per state")
    omega = np.zeros(3)
    for frame in frames:
        expected = rotation_torque(force, frame)
        actual = np.asarray(_call(force, omega, frame, 0.0), dtype=float)
        scale = max(np.max(np.abs(expected)), np.max(np.abs(actual)), 1e-300)
        if np.max(np.abs(actual - expected)) > POTENTIAL_RTOL * scale + 1e-12:
            raise _fail(cls, f"potential does not belong to the torque: at ω = 0 the torque is "
                             f"{np.round(actual, 9).tolist()} but Σ e_i × ∂V/∂e_i of the potential (finite "
                             f"differences) is {np.round(expected, 9).tolist()}; fix potential or torque")


def _netcdf_safe(value: Any) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, str):
        return True
    if isinstance(value, (int, float, np.integer, np.floating)):
        return math.isfinite(float(value))
    if isinstance(value, (list, tuple, np.ndarray)):
        items = list(np.asarray(value, dtype=object).reshape(-1))
        return bool(items) and all(not isinstance(v, (bool, np.bool_, str)) and _netcdf_safe(v) for v in items)
    return False


def _check_compiled(cls: type, force: Force, body: Any, omegas: np.ndarray, frames: np.ndarray) -> None:
    if force.compiled_terms() is not None:
        return  # a built-in form; the system's tests compare it with the Python right-hand side
    def torque(t: Any, y: np.ndarray) -> Any:  # y = (ω, γ, α), as the fixed point lays out its state
        frame = np.empty((3, 3), dtype=object)
        frame[0], frame[1], frame[2] = y[6:9], cross(y[3:6], y[6:9]), y[3:6]
        return _call(force, y[0:3], frame, t)

    try:
        expression.check_torques([force])
        compiled = model.compile(model.trace(torque, 9, f"force {force.name}"))
    except expression.NotCompilable as exc:
        warnings.warn(f"{cls.__name__} runs with the Python integrators only: {exc}", stacklevel=3)
        return
    ptr = ctypes.POINTER(ctypes.c_double)
    kernel = ctypes.CFUNCTYPE(None, ctypes.c_double, ptr, ptr, ptr)(int(compiled.params[model.TRACED_ADDRESS]))
    for k, (omega, frame) in enumerate(zip(omegas, frames)):
        y = np.concatenate([omega, frame[2], frame[0]])
        out = np.zeros(3)
        kernel(0.7 * k, y.ctypes.data_as(ptr), compiled.params.ctypes.data_as(ptr), out.ctypes.data_as(ptr))
        expected = np.asarray(_call(force, omega.copy(), frame, 0.7 * k), dtype=float)
        if not np.allclose(out, expected, rtol=1e-12, atol=1e-14 * max(1.0, np.max(np.abs(expected)))):
            raise _fail(cls, f"the compiled torque {out.tolist()} differs from the Python torque {expected.tolist()} "
                             f"at ω={omega.tolist()}; report this to gyrolab with the plugin's torque")


# ---- integrators --------------------------------------------------------------------------------------------

#: An adaptive integrator's error on the kit's oscillator may exceed max(rtol, atol) by this factor (global error
#: accumulates over the ~1.6 periods integrated; scipy's own methods stay within 10-50x).
ERROR_FACTOR = 1000.0
#: A fixed-step integrator states no tolerance: the kit only checks that it integrates the right equation.
FIXED_STEP_ERROR = 1e-3
#: Output times of the kit's problems: not starting at 0, unevenly spaced, so that a method that assumes either fails.
OSCILLATOR_TIMES = np.array([0.5, 0.6, 1.0, 2.5, 4.0, 4.1, 7.3, 10.5])
#: y' = y² from y(0) = 1 is y = 1/(1 − t): it blows up at t = 1, inside these output times.
BLOW_UP_TIMES = np.array([0.0, 0.5, 2.0])


@dataclass(frozen=True)
class ExactProblem:
    """An initial-value problem with a known solution, for ``check_integrator``.

    ``exact(t)`` gives the columns ``compared`` of the solution from ``y0`` at ``t_out[0]``; ``compiled`` is the
    problem in the compiled kernels' form (None for a Python-only problem).
    """

    description: str
    fun: Any
    y0: np.ndarray
    exact: Any
    compared: slice
    compiled: Any = None


def oscillator_problem() -> ExactProblem:
    """x'' = −x written as y = (x, v): the exact solution from (1, 0) at t0 is (cos(t − t0), −sin(t − t0))."""
    def exact(t: np.ndarray) -> np.ndarray:
        dt = t - OSCILLATOR_TIMES[0]
        return np.stack([np.cos(dt), -np.sin(dt)], axis=1)

    return ExactProblem("the harmonic oscillator x'' = −x", lambda t, y: np.array([y[1], -y[0]]), np.array([1.0, 0.0]),
                        exact, slice(0, 2))


#: The free symmetric top of ``free_top_problem``: A = B = 0.8 C, no torque, ω0 = (0.1, −0.05, 5).
FREE_TOP_A, FREE_TOP_OMEGA0 = 0.8, (0.1, -0.05, 5.0)


def free_top_problem() -> ExactProblem:
    """The torque-free symmetric top as gyrolab's fixed-point system, with its compiled model: I ω̇ = (Iω) × ω with
    A = B gives r constant and (p, q) turning at λ = (C − A) r / A (ṗ = −λ q, q̇ = λ p)."""
    body = Body.from_config({"units": "nondimensional", "a": FREE_TOP_A, "b": FREE_TOP_A,
                             "com_direction": [0.0, 0.0, 0.0]})
    p0, q0, r0 = FREE_TOP_OMEGA0
    system = FixedPoint(body, [], {"p0": p0, "q0": q0, "r0": r0, "theta0": 1.0, "phi0": 0.3, "psi0": 0.0},
                        {"euler_angles": False})
    lam = (1.0 - FREE_TOP_A) * r0 / FREE_TOP_A

    def exact(t: np.ndarray) -> np.ndarray:
        c, s = np.cos(lam * (t - OSCILLATOR_TIMES[0])), np.sin(lam * (t - OSCILLATOR_TIMES[0]))
        return np.stack([p0 * c - q0 * s, p0 * s + q0 * c, np.full_like(t, r0)], axis=1)

    return ExactProblem("the free symmetric top (gyrolab's fixed-point system, compiled)", system.rhs,
                        system.initial_state(), exact, slice(0, 3), system.compiled_model())


def check_integrator(cls: type, **params: Any) -> None:
    """Check an integrator plugin class against the Integrator contract; AssertionError names the first violation.

    Parameters
    ----------
    cls : type
        The integrator plugin class (a subclass of ``gyrolab.contracts.Integrator``).
    **params
        The plugin's keyword parameters for the checks (its defaults when omitted).

    Notes
    -----
    The rules it checks, in order, on a harmonic oscillator, a blow-up and (for a compiled integrator) the free
    symmetric top are listed in docs/plugins.md, "Integrator plugins".
    """
    _check_class(cls, Integrator, "the config's integrator=NAME")
    if not isinstance(getattr(cls, "adaptive", None), bool):
        raise _fail(cls, f"adaptive={getattr(cls, 'adaptive', None)!r} must be declared True or False")
    capabilities = getattr(cls, "capabilities", frozenset())
    if not isinstance(capabilities, frozenset) or not all(isinstance(c, str) for c in capabilities):
        raise _fail(cls, f"capabilities={capabilities!r} must be a frozenset of capability names (str)")
    params = _as_config(params)
    integrator = _build_plugin(cls, cls, params)
    _check_bad_parameters(cls, params, "integrator.", cls)
    if cls.supports(COMPILED_MODEL):
        stats = _check_exact_problem(cls, integrator, free_top_problem())
    else:
        stats = _check_exact_problem(cls, integrator, oscillator_problem())
        _check_blow_up(cls, integrator)
    _check_mapping(cls, stats.attributes(), "stats.attributes()")
    _check_mapping(cls, integrator.attributes(), "attributes()")


def _build_plugin(build: Any, cls: type, params: dict[str, Any]) -> Any:
    """``build(**params)``: the plugin ``cls`` built as a scene builds it."""
    try:
        return build(**params)
    except ConfigError as exc:
        raise _fail(cls, f"building it with {params} raised ConfigError: {exc}") from None


def _check_exact_problem(cls: type, integrator: Any, problem: ExactProblem) -> Any:
    """``check_integrator``'s checks on one problem with a known solution; returns the run's stats."""
    calls = [0]

    def fun(t: float, y: np.ndarray) -> np.ndarray:
        calls[0] += 1
        return problem.fun(t, y)

    reported: list[float] = []
    t_out, y0 = OSCILLATOR_TIMES.copy(), problem.y0.copy()
    solution = unchecked(integrator)(fun, t_out, y0, reported.append, problem.compiled)  # the plugin's own result
    on = f"on {problem.description}"
    if not isinstance(solution, Solution):
        raise _fail(cls, f"integrate returned {type(solution).__name__}, not gyrolab.contracts.Solution")
    if not np.array_equal(y0, problem.y0) or not np.array_equal(t_out, OSCILLATOR_TIMES):
        raise _fail(cls, "integrate modified its input y0 or t_out in place; work on copies")
    _check_samples(cls, solution, t_out, y0, on)
    _check_accuracy(cls, integrator, problem, np.asarray(solution.y), t_out, on)
    stats = _checked_stats(cls, solution, problem, calls[0])
    if not reported:
        raise _fail(cls, "integrate never called progress(t); call it every few steps when it is given")
    outside = [r for r in reported if not t_out[0] <= float(r) <= t_out[-1]]
    if outside:
        raise _fail(cls, f"progress was called with t={outside[0]!r}, outside the interval [{t_out[0]}, {t_out[-1]}]")
    return stats


def _check_samples(cls: type, solution: Solution, t_out: np.ndarray, y0: np.ndarray, on: str) -> None:
    """The solution is sampled at exactly ``t_out``, finite, with the state size, starting at ``y0``."""
    t, y = np.asarray(solution.t), np.asarray(solution.y)
    if t.shape != t_out.shape or not np.array_equal(t, t_out):
        raise _fail(cls, f"Solution.t is {np.round(t, 12).tolist()}, not the requested t_out "
                         f"{t_out.tolist()}; sample the state at exactly the requested times")
    if y.shape != (len(t_out), len(y0)):
        raise _fail(cls, f"Solution.y has shape {y.shape}, not (len(t_out), state size) = ({len(t_out)}, {len(y0)})")
    if not np.all(np.isfinite(y)):
        raise _fail(cls, f"Solution.y has non-finite values {on}; raise IntegrationError instead")
    if np.max(np.abs(y[0] - y0)) > 1e-14 * max(1.0, float(np.max(np.abs(y0)))):
        raise _fail(cls, f"Solution.y[0] = {y[0].tolist()} is not y0 = {y0.tolist()} at t_out[0], the initial time")


def _check_accuracy(cls: type, integrator: Any, problem: ExactProblem, y: np.ndarray, t_out: np.ndarray,
                    on: str) -> None:
    """The error against the exact solution is within the integrator's own tolerance."""
    error = float(np.max(np.abs(y[:, problem.compared] - problem.exact(t_out))))
    rtol, atol = getattr(integrator, "rtol", None), getattr(integrator, "atol", None)
    if cls.adaptive and rtol is not None and atol is not None:
        allowed, why = ERROR_FACTOR * max(float(rtol), float(atol)), f"{ERROR_FACTOR:g} × max(rtol, atol)"
    else:
        allowed, why = FIXED_STEP_ERROR, "the kit's bound for methods without rtol/atol"
    if not error <= allowed:
        raise _fail(cls, f"its error {on} is {error:.3g}, above {allowed:.3g} ({why}); it does not integrate to its "
                         "own tolerance")


def _checked_stats(cls: type, solution: Solution, problem: ExactProblem, calls: int) -> IntegratorStats:
    """The run's stats count the evaluations made (at most ``calls`` for a Python right-hand side) and
    the steps taken."""
    stats = solution.stats
    if not isinstance(stats, IntegratorStats):
        raise _fail(cls, f"Solution.stats is {type(stats).__name__}, not gyrolab.contracts.IntegratorStats")
    if not isinstance(stats.nfev, (int, np.integer)) or stats.nfev <= 0:
        raise _fail(cls, f"stats.nfev={stats.nfev!r} must count the right-hand-side evaluations (an integer > 0)")
    if problem.compiled is None and stats.nfev > calls:
        raise _fail(cls, f"stats.nfev={stats.nfev}, but the right-hand side was called {calls} times; count the "
                         "evaluations made, no more")
    if not isinstance(stats.n_steps, (int, np.integer)) or stats.n_steps < 1:
        raise _fail(cls, f"stats.n_steps={stats.n_steps!r} must be the number of steps taken (an integer ≥ 1)")
    return stats


def _check_blow_up(cls: type, integrator: Any) -> None:
    try:
        with np.errstate(over="ignore", invalid="ignore"):
            solution = unchecked(integrator)(lambda t, y: y * y, BLOW_UP_TIMES.copy(), np.array([1.0]), None, None)
    except IntegrationError as exc:
        if "\n" in str(exc).strip():
            raise _fail(cls, f"its IntegrationError on y' = y² is not one line: {str(exc)!r}") from None
        return
    except Exception as exc:  # noqa: BLE001  (anything but IntegrationError is the violation)
        raise _fail(cls, f"on y' = y², y(0) = 1 (blow-up at t = 1) it raised {type(exc).__name__}: {exc}; raise "
                         "gyrolab.errors.IntegrationError saying when and why") from None
    y = np.asarray(solution.y)
    if not np.all(np.isfinite(y)):
        raise _fail(cls, "on y' = y², y(0) = 1 (blow-up at t = 1) it returned non-finite values; raise "
                         "gyrolab.errors.IntegrationError instead")
    raise _fail(cls, f"on y' = y², y(0) = 1 it returned y(2) = {float(y[-1, 0]):.6g}, but the solution 1/(1 − t) "
                     "blows up at t = 1; detect the failure and raise gyrolab.errors.IntegrationError")


def _check_mapping(cls: type, attrs: Any, what: str) -> None:
    """``attrs`` (a plugin's ``attributes()``) are netCDF-safe: names of letters, digits and _, values ``_netcdf_safe``."""
    if not isinstance(attrs, dict):
        raise _fail(cls, f"{what} returned {type(attrs).__name__}, not a dict")
    for key, value in attrs.items():
        if not isinstance(key, str) or not _NAME.match(key):
            raise _fail(cls, f"{what} key {key!r} is not a netCDF-safe name (letters, digits, _)")
        if not _netcdf_safe(value):
            raise _fail(cls, f"{what}[{key!r}] = {value!r} is not netCDF-safe; use str, int, float or a non-empty "
                             "list of finite numbers (no bool, None or dict)")


def _check_bad_parameters(cls: type, params: dict[str, Any], prefix: str, build: Any) -> None:
    """Every keyword parameter set to "abc" must make ``build(**params)`` raise one ConfigError line naming it
    (NaN and inf never reach a plugin: the scene refuses non-finite config values)."""
    for key, param in inspect.signature(cls.__init__).parameters.items():
        if param.kind is not inspect.Parameter.KEYWORD_ONLY or (param.default is None and key not in params):
            continue  # a parameter off by default is checked when the caller gives it
        try:
            build(**{**params, key: "abc"})
        except ConfigError as exc:
            message = str(exc)
            if key not in message or "\n" in message.strip():
                raise _fail(cls, f"{prefix}{key}='abc' raised a ConfigError that does not name the parameter in "
                                 f"one line: {message!r}") from None
            continue
        except Exception as exc:  # noqa: BLE001  (anything but ConfigError is the violation)
            raise _fail(cls, f"{prefix}{key}='abc' raised {type(exc).__name__}: {exc}; raise gyrolab.errors."
                             "ConfigError naming the parameter (gyrolab.errors.as_number validates numbers)") from None
        raise _fail(cls, f"{prefix}{key}='abc' was accepted; validate the parameter and raise gyrolab.errors."
                         "ConfigError (gyrolab.errors.as_number does it for numbers)")


# ---- systems ------------------------------------------------------------------------------------------------

#: The kit integrates the system over [0, SYSTEM_SPAN] with scipy's DOP853 at rtol = atol = SYSTEM_RTOL ...
SYSTEM_SPAN = 2.0
SYSTEM_RTOL = 1e-12
#: ... and requires each monitored invariant to stay within this of its initial value (relative to max(1, |v0|)).
INVARIANT_TOLERANCE = 1e-9


def check_system(cls: type, body: dict[str, Any], initial: dict[str, Any], *, forces: Any = (),
                 output: dict[str, Any] | None = None, span: float = SYSTEM_SPAN,
                 invariant_tolerance: float = INVARIANT_TOLERANCE, **params: Any) -> None:
    """Check a system plugin class against the System contract; AssertionError names the first violation.

    Parameters
    ----------
    cls : type
        The system plugin class (a subclass of ``gyrolab.contracts.System``).
    body : dict
        The ``body`` config section a scene would give; ``cls.body_type.from_config(body)`` builds the body.
    initial : dict
        The ``initial`` config section.
    forces : sequence of (type, dict)
        ``(ForceClass, params)`` pairs built on that body (none by default).
    output : dict, optional
        The ``output`` section (``{"euler_angles": True}`` by default).
    span : float
        The time span of the invariant check.
    invariant_tolerance : float
        Relative drift allowed to each invariant over ``span``.
    **params
        The system's own parameters.

    Notes
    -----
    The rules it checks, in order, are listed in docs/plugins.md, "System plugins"; a system whose ``rhs`` cannot
    be traced is warned about (it runs with the Python integrators only), not failed.
    """
    _check_class(cls, System, "the config's system=NAME")
    body_type = getattr(cls, "body_type", None)
    if not callable(getattr(body_type, "from_config", None)):
        raise _fail(cls, f"body_type={body_type!r} must be a class with from_config(body section)")
    try:
        built_body = body_type.from_config(dict(body))
    except ConfigError as exc:
        raise _fail(cls, f"body_type.from_config({body}) raised ConfigError: {exc}") from None
    built_forces = [build_force(force_cls, dict(force_params), f"force.{force_cls.name}", built_body)
                    for force_cls, force_params in forces]
    output = {"euler_angles": True} if output is None else dict(output)
    def build(**kw: Any) -> Any:
        return cls(built_body, built_forces, dict(initial), output, **kw)

    system = _build_plugin(build, cls, params)
    _check_bad_parameters(cls, params, "system.", build)
    y0 = _check_state(cls, system)
    t, y = _integrate_tightly(cls, system, y0, span)
    _check_variables(cls, system, t, y)
    _check_invariants_conserved(cls, system, t, y, invariant_tolerance)
    _check_mapping(cls, system.attributes(), "attributes()")
    title = system.title()
    if not isinstance(title, str) or not title.strip() or "\n" in title:
        raise _fail(cls, f"title() returned {title!r}; it must name the scene in a few words, on one line")
    _check_compiled_system(cls, system, t, y)


def _check_compiled_system(cls: type, system: Any, t: np.ndarray, y: np.ndarray) -> None:
    """``check_system``'s last check: the compiled model against the Python right-hand side and trajectory."""
    compiled = system.compiled_model()
    if compiled is None:
        warnings.warn(f"{cls.__name__} runs with the Python integrators only: {system.compile_error}", stacklevel=3)
        return
    rng = np.random.default_rng(11)
    scale = max(1.0, float(np.max(np.abs(y[0]))))
    out = np.empty(len(y[0]))
    for state in [y[0], *(y[0] + 0.1 * scale * rng.normal(size=len(y[0])) for _ in range(10))]:
        models.evaluate(0.3, np.ascontiguousarray(state), compiled.params, out)
        expected = np.asarray(system.rhs(0.3, state.copy()), dtype=float)
        if not np.allclose(out, expected, rtol=1e-12, atol=1e-12 * max(1.0, float(np.max(np.abs(expected))))):
            raise _fail(cls, f"the compiled right-hand side {out.tolist()} differs from rhs {expected.tolist()} at "
                             f"y={state.tolist()}; report this to gyrolab with the system's rhs")
    got = Taylor(tol=1e-15).integrate(system.rhs, t, y[0], None, compiled).y
    worst = float(np.max(np.abs(got - y)))
    if worst > 1e-8 * max(1.0, float(np.max(np.abs(y)))):
        raise _fail(cls, f"the compiled model under taylor ends {worst:.3g} away from the DOP853 trajectory of rhs; "
                         "report this to gyrolab with the system's rhs")


def _check_state(cls: type, system: Any) -> np.ndarray:
    size = system.state_size
    if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 1:
        raise _fail(cls, f"state_size={size!r} must be a positive integer")
    y0 = np.asarray(system.initial_state())
    if y0.shape != (size,) or not np.issubdtype(y0.dtype, np.floating) or not np.all(np.isfinite(y0)):
        raise _fail(cls, f"initial_state() returned shape {y0.shape}, dtype {y0.dtype}; it must be a finite float "
                         f"array of shape (state_size,) = ({size},)")
    kept = y0.copy()
    dy = np.asarray(system.rhs(0.0, y0))
    if dy.shape != (size,) or not np.issubdtype(dy.dtype, np.floating):
        raise _fail(cls, f"rhs(t, y0) returned shape {dy.shape} and dtype {dy.dtype}; it must be a float array of "
                         f"shape (state_size,) = ({size},)")
    if not np.all(np.isfinite(dy)):
        raise _fail(cls, f"rhs(t, y0) is not finite at y0={y0.tolist()}: {dy.tolist()}")
    if not np.array_equal(y0, kept):
        raise _fail(cls, "rhs(t, y) modified the state y in place; integrators pass their own arrays")
    return kept


def _integrate_tightly(cls: type, system: Any, y0: np.ndarray, span: float) -> tuple[np.ndarray, np.ndarray]:
    from scipy.integrate import solve_ivp  # start-up: scipy.integrate only for this check

    t = np.linspace(0.0, span, 41)
    done = solve_ivp(system.rhs, (0.0, span), y0, method="DOP853", t_eval=t, rtol=SYSTEM_RTOL, atol=SYSTEM_RTOL)
    if not done.success or not np.all(np.isfinite(done.y)):
        raise _fail(cls, f"scipy's DOP853 could not integrate rhs over [0, {span:g}] from initial_state() "
                         f"({done.message}); the kit needs a state that stays finite that long")
    return t, np.ascontiguousarray(done.y.T)


def _check_variables(cls: type, system: Any, t: np.ndarray, y: np.ndarray) -> None:
    invariants = system.invariants
    if not isinstance(invariants, tuple) or not all(isinstance(n, str) for n in invariants):
        raise _fail(cls, f"invariants={invariants!r} must be a tuple of dataset variable names (str)")
    variables = system.variables(t, y)
    if not isinstance(variables, dict):
        raise _fail(cls, f"variables(t, y) returned {type(variables).__name__}, not a dict of xarray.Variable")
    for key, variable in variables.items():
        _check_variable(cls, key, variable, len(t))
    for name in invariants:
        if name not in variables:
            raise _fail(cls, f"invariant {name!r} is not among variables(t, y) ({', '.join(variables)}); every "
                             "monitored invariant must be a dataset variable")
        if variables[name].dims != ("time",):
            raise _fail(cls, f"invariant {name!r} has dims {variables[name].dims}, not ('time',)")


def _check_variable(cls: type, key: str, variable: Any, n_times: int) -> None:
    """A system's dataset variable: an xarray.Variable over time first, with CF units and long_name."""
    if not isinstance(variable, xr.Variable):
        raise _fail(cls, f"variables(t, y)[{key!r}] is {type(variable).__name__}, not an xarray.Variable")
    if not variable.dims or variable.dims[0] != "time" or variable.shape[0] != n_times:
        raise _fail(cls, f"variable {key!r} has dims {variable.dims} and shape {variable.shape}; its first "
                         f"dimension must be time, of length {n_times}")
    for attr in ("units", "long_name"):
        value = variable.attrs.get(attr)
        if not isinstance(value, str) or not value.strip():
            raise _fail(cls, f"variable {key!r} has no CF {attr} (got {value!r}); give every variable units "
                             "and long_name")


def _check_invariants_conserved(cls: type, system: Any, t: np.ndarray, y: np.ndarray, tolerance: float) -> None:
    variables = system.variables(t, y)
    for name in system.invariants:
        values = np.asarray(variables[name].values, dtype=float)
        drift = float(np.max(np.abs(values - values[0])))
        if not drift <= tolerance * max(1.0, abs(float(values[0]))):
            raise _fail(cls, f"invariant {name!r} drifts by {drift:.3g} from {float(values[0]):.6g} over "
                             f"t = [0, {t[-1]:g}] (DOP853 at rtol = atol = {SYSTEM_RTOL:g}), above "
                             f"{tolerance:g} × max(1, |v0|); it is not conserved by rhs")


# ---- regimes ------------------------------------------------------------------------------------------------

#: ``solution(system, [0])`` must equal ``initial_state(system)`` to this (relative to max(1, |y|)).
REGIME_START_TOLERANCE = 1e-12
EULER_KEYS = frozenset({"psi", "theta", "phi"})


def check_regime(cls: type, scene: Any = (), **params: Any) -> None:
    """Check a regime plugin class against the Regime contract; AssertionError names the first violation.

    Parameters
    ----------
    cls : type
        The regime plugin class (a subclass of ``gyrolab.contracts.Regime``).
    scene : list of str or System
        The scene the regime is checked on: overrides for ``gyrolab.compose_scene`` (the
        default scene when empty) or a built system.
    **params
        The regime's keyword parameters.

    Notes
    -----
    The rules it checks, in order, are listed in docs/plugins.md, "Regime plugins".
    """
    _check_class(cls, Regime, "the config's regime=NAME")
    _check_regime_declarations(cls)
    params = _as_config(params)
    regime = _build_plugin(cls, cls, params)
    _check_bad_parameters(cls, params, "regime.", cls)
    system = scene if isinstance(scene, System) else compose_scene(list(scene)).system
    if system.name not in cls.systems:
        raise _fail(cls, f"the kit's scene has system {system.name!r}, not one of systems={cls.systems}; give a "
                         "scene the regime is derived for (scene=[...overrides...])")
    warnings_ = regime.check_domain(system)
    if not isinstance(warnings_, list) or not all(isinstance(w, str) and "\n" not in w.strip() for w in warnings_):
        raise _fail(cls, f"check_domain returned {warnings_!r}; it must return a list of one-line warnings (str) "
                         "and raise ConfigError outside the domain")
    _check_regime_numbers(cls, regime, system)
    t = np.linspace(0.0, float(regime.period(system)), 9)
    _check_euler_angles(cls, regime, system, t)
    _check_mapping(cls, regime.attributes(), "attributes()")


def _check_regime_numbers(cls: type, regime: Any, system: Any) -> None:
    """A finite parameter value, a start state matching the solution at 0, a finite positive period
    over which the solution is finite, of shape (n, 6)."""
    value = regime.parameter_value(system)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) or not math.isfinite(float(value)):
        raise _fail(cls, f"parameter_value(system) returned {value!r}, not a finite number")
    _check_regime_start(cls, regime, system)
    period = regime.period(system)
    if isinstance(period, bool) or not isinstance(period, (int, float, np.number)) or not 0 < float(period) < math.inf:
        raise _fail(cls, f"period(system) returned {period!r}; it must be a finite number > 0")
    t = np.linspace(0.0, float(period), 9)
    y = np.asarray(regime.solution(system, t))
    if y.shape != (len(t), 6) or not np.all(np.isfinite(y)):
        raise _fail(cls, f"solution(system, t) for {len(t)} times returned shape {y.shape}"
                         f"{'' if np.all(np.isfinite(y)) else ' with non-finite values'}; it must be finite, (n, 6)")


def _check_regime_declarations(cls: type) -> None:
    systems = getattr(cls, "systems", None)
    if not isinstance(systems, tuple) or not systems or not all(isinstance(s, str) for s in systems):
        raise _fail(cls, f"systems={systems!r} must be a non-empty tuple of the system names it is derived for")
    for attr in ("parameter", "parameter_long_name"):
        if not isinstance(getattr(cls, attr, None), str):
            raise _fail(cls, f"{attr}={getattr(cls, attr, None)!r} must be a str naming the expansion's parameter")
    order = getattr(cls, "order", None)
    if not isinstance(order, dict) or not all(isinstance(k, str) and isinstance(v, (int, float))
                                              for k, v in order.items()):
        raise _fail(cls, f"order={order!r} must be a dict of variable name → error order in the parameter")


def _check_regime_start(cls: type, regime: Any, system: Any) -> None:
    y0 = np.asarray(regime.initial_state(system))
    if y0.shape != (6,) or not np.issubdtype(y0.dtype, np.floating) or not np.all(np.isfinite(y0)):
        raise _fail(cls, f"initial_state(system) returned shape {y0.shape}, dtype {y0.dtype}; it must be the "
                         "orbit's finite (ω, γ) at t = 0, a float array of shape (6,)")
    start = np.asarray(regime.solution(system, np.array([0.0])))
    if start.shape != (1, 6):
        raise _fail(cls, f"solution(system, [0]) returned shape {start.shape}, not (1, 6)")
    gap = float(np.max(np.abs(start[0] - y0)))
    if not gap <= REGIME_START_TOLERANCE * max(1.0, float(np.max(np.abs(y0)))):
        raise _fail(cls, f"solution(system, [0]) = {np.round(start[0], 12).tolist()} differs from initial_state = "
                         f"{np.round(y0, 12).tolist()} by {gap:.3g}; the solution must start at its initial state")


def _check_euler_angles(cls: type, regime: Any, system: Any, t: np.ndarray) -> None:
    angles = regime.euler_angles(system, t)
    if not isinstance(angles, dict) or set(angles) != EULER_KEYS:
        raise _fail(cls, f"euler_angles(system, t) returned keys {sorted(angles) if isinstance(angles, dict) else angles!r}; "
                         "it must return exactly psi, theta, phi")
    for key, values in angles.items():
        values = np.asarray(values)
        if values.shape != t.shape or not np.all(np.isfinite(values)):
            raise _fail(cls, f"euler_angles(system, t)[{key!r}] has shape {values.shape}"
                             f"{'' if np.all(np.isfinite(values)) else ' with non-finite values'}; it must be finite, "
                             f"of shape ({len(t)},)")
